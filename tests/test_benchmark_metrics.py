"""Selection metrics and their rliable-style aggregates against values computed by hand."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from classifiers.experiments.benchmark.aggregate import (
    iqm,
    performance_profile,
    probability_of_improvement,
    stratified_bootstrap,
)
from classifiers.experiments.benchmark.aggregate import mean as mean_score
from classifiers.experiments.benchmark.leaderboard import build_leaderboard
from classifiers.experiments.benchmark.methods import baseline_scores, choice_scores
from classifiers.experiments.benchmark.selection import selection_metrics
from classifiers.experiments.selector.evaluation import attempt_metrics, random_metrics
from classifiers.report.leaderboard import leaderboard_markdown

LOG3 = np.log2(3.0)


def tiny() -> pd.DataFrame:
    """Object A: success 0, .5, 1 (robustness 10, 20, 30); object B: all 0.25 (degenerate)."""
    return pd.DataFrame({
        "object_id": ["A"] * 3 + ["B"] * 2, "candidate": [0, 1, 2, 0, 1],
        "success_rate": [0.0, 0.5, 1.0, 0.25, 0.25],
        "robustness_mean": [10.0, 20.0, 30.0, 5.0, 7.0],
    })  # fmt: skip


def scores(method: str, a: list[float], b: list[float], seed: int = 0) -> pd.DataFrame:
    return pd.DataFrame({"method": method, "seed": seed, "object_id": ["A"] * 3 + ["B"] * 2,
                         "candidate": [0, 1, 2, 0, 1], "score": [*a, *b]})  # fmt: skip


def metrics_of(*frames: pd.DataFrame) -> pd.DataFrame:
    return selection_metrics(tiny(), pd.concat(frames)).set_index(["method", "object_id"])


def test_worst_first_ranking_by_hand() -> None:
    row = metrics_of(scores("m", [3, 2, 1], [1, 0])).loc[("m", "A")]
    assert row["success"] == 0.0 and row["robustness"] == 10.0
    assert row["regret"] == 1.0 and row["robustness_regret"] == 20.0
    assert row["normalised"] == pytest.approx((0.0 - 0.5) / (1.0 - 0.5))  # -1
    dcg, ideal = 0.5 / LOG3 + 1.0 / 2.0, 1.0 + 0.5 / LOG3
    assert row["ndcg5"] == pytest.approx(dcg / ideal)
    assert row["success_at_2"] == pytest.approx(0.5)
    assert row["success_at_3"] == pytest.approx(1.0)
    assert row["attempts"] == pytest.approx(1 + 1 + 0.5)  # budget 5, only 3 grips


def test_ties_are_averaged_exactly_and_random_is_the_exact_expectation() -> None:
    found = metrics_of(scores("tie", [1, 1, 0], [0, 0]), scores("random", [0, 0, 0], [0, 0]))
    tie = found.loc[("tie", "A")]
    assert tie["success"] == pytest.approx(0.25)
    assert tie["success_at_2"] == pytest.approx(0.5)
    mean_discount = (1.0 + 1.0 / LOG3) / 2
    assert tie["ndcg5"] == pytest.approx((0.5 * mean_discount + 0.5) / (1.0 + 0.5 / LOG3))
    rand = found.loc[("random", "A")]
    assert rand["success"] == pytest.approx(0.5) and rand["normalised"] == pytest.approx(0.0)
    assert rand["robustness"] == pytest.approx(20.0)
    # pairs {0,1}: fails with 0.5; {0,2}, {1,2}: never -> 1 - 0.5 / 3
    assert rand["success_at_2"] == pytest.approx(1 - 0.5 / 3)
    assert rand["ndcg5"] == pytest.approx(0.5 * (1 + 1 / LOG3 + 0.5) / (1 + 0.5 / LOG3))


def test_expected_attempts_stop_when_the_candidates_run_out() -> None:
    row = metrics_of(scores("m", [3, 2, 1], [1, 0])).loc[("m", "B")]
    assert row["attempts"] == pytest.approx(1 + 0.75)  # two grips: a second try, never a third
    assert row["success_at_5"] == pytest.approx(1 - 0.75**2)


def test_degenerate_object_has_no_normalised_score_and_all_failing_no_ndcg() -> None:
    table = tiny()
    table.loc[table["object_id"] == "B", "success_rate"] = 0.0
    found = selection_metrics(table, scores("m", [3, 2, 1], [1, 0])).set_index("object_id")
    assert np.isnan(found.loc["B", "normalised"]) and np.isnan(found.loc["B", "ndcg5"])
    assert found.loc["B", "regret"] == 0.0


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_attempt_curve_matches_the_selector_formulas(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = 20
    p = rng.integers(0, 5, size=n) / 4  # many ties, as 4 trials give
    table = pd.DataFrame({"object_id": "X", "candidate": np.arange(n), "success_rate": p})
    ranked = pd.DataFrame({"method": "ranked", "seed": 0, "object_id": "X",
                           "candidate": np.arange(n), "score": -np.arange(n, dtype=float)})
    flat = ranked.assign(method="random", score=0.0)
    found = selection_metrics(table, pd.concat([ranked, flat])).set_index("method")
    for k in range(1, 6):
        assert found.loc["ranked", f"success_at_{k}"] == pytest.approx(attempt_metrics(p, k)[1])
        assert found.loc["random", f"success_at_{k}"] == pytest.approx(random_metrics(p, k)[1])
    assert found.loc["random", "attempts"] == pytest.approx(random_metrics(p, 5)[2])


def test_oracle_baseline_is_the_oracle_and_choice_is_one_hot() -> None:
    table = tiny().assign(Q_C=[1.0, 2.0, 3.0, 1.0, 2.0], Q_G=[3.0, 2.0, 1.0, 1.0, 2.0])
    table = pd.concat([table] * 1, ignore_index=True)
    base = baseline_scores(table.assign(**_geometry(len(table))))
    found = selection_metrics(table, base).set_index(["method", "object_id"])
    assert found.loc[("oracle", "A"), "success"] == 1.0
    assert found.loc[("oracle", "A"), "normalised"] == 1.0
    assert found.loc[("best_qc", "A"), "success"] == 0.0  # lowest Q_C first
    assert found.loc[("best_qg", "A"), "success"] == 1.0
    assert choice_scores(np.int64(2), 3, "x").tolist() == [0.0, 0.0, 1.0]
    for bad, message in ((3, "invalid index"), (1.5, "integer"), ([0.1, np.nan, 0], "NaN"),
                         ([1.0, 2.0], "2 scores")):  # fmt: skip
        with pytest.raises(ValueError, match=message):
            choice_scores(bad, 3, "x")


def _geometry(n: int) -> dict[str, np.ndarray]:
    """Contacts on a unit circle and inward normals: a valid epsilon input."""
    angles = np.array([0.0, 2.1, 4.2])
    out = {}
    for i, a in enumerate(angles, start=1):
        out[f"p{i}_x"], out[f"p{i}_y"] = np.full(n, 50 * np.cos(a)), np.full(n, 50 * np.sin(a))
        out[f"n{i}_x"], out[f"n{i}_y"] = np.full(n, -np.cos(a)), np.full(n, -np.sin(a))
    out.update(centroid_x=np.zeros(n), centroid_y=np.zeros(n), semi_major=np.full(n, 50.0),
               semi_minor=np.full(n, 50.0))  # fmt: skip
    return out


def test_iqm_poi_and_profile_by_hand() -> None:
    matrix = np.array([[1.0, 2, 3, 4], [5, 6, 7, 8]])
    assert float(iqm(matrix)) == pytest.approx(4.5)  # mean of 3, 4, 5, 6
    assert float(iqm(np.arange(10.0)[None])) == pytest.approx(np.mean([2, 3, 4, 5, 6, 7]))
    assert float(probability_of_improvement(np.array([[1.0, 0.0]]),
                                            np.array([[0.0, 0.0]]))) == 0.75  # fmt: skip
    assert float(probability_of_improvement(np.array([[1.0], [0.0]]), np.array([[0.0]]))) == 0.75
    profile = performance_profile(np.array([[0.0, 0.5, 1.0]]), np.array([-0.1, 0.25, 0.75, 1]))
    assert profile.tolist() == pytest.approx([1, 2 / 3, 1 / 3, 0])


def test_stratified_bootstrap_on_known_inputs() -> None:
    two = stratified_bootstrap(np.array([[0.0, 1.0]]), mean_score, reps=4000, seed=3)
    assert two["estimate"] == 0.5 and two["ci"] == [0.0, 1.0]  # means 0, .5, 1 w.p. 1/4 1/2 1/4
    runs = np.array([[0.0, 0.0], [1.0, 1.0]])
    seeds_only = stratified_bootstrap(runs, mean_score, reps=4000, seed=3, task_bootstrap=False)
    # each object draws 2 runs of {0, 1}: resampled mean is k/4, k ~ Binomial(4, 1/2)
    assert seeds_only["estimate"] == 0.5 and seeds_only["ci"] == [0.0, 1.0]
    fixed = stratified_bootstrap(np.array([[0.2, 0.4]] * 3), mean_score, task_bootstrap=False)
    assert fixed["ci"] == pytest.approx([0.3, 0.3])


def test_leaderboard_verdicts() -> None:
    rng = np.random.default_rng(0)
    rows = []
    for obj in range(12):
        for method, value in (("best_qc", 0.2), ("good", 0.8), ("same", 0.2)):
            for seed in range(3 if method == "good" else 1):
                rows.append({"method": method, "seed": seed, "object_id": f"o{obj}",
                             "normalised": value + 0.01 * rng.random(), **_plain()})
    board = build_leaderboard(pd.DataFrame(rows), {"name": "t", "version": 0}, reps=500)
    assert board["methods"]["good"]["verdict"] == "beats best_qc"
    assert board["methods"]["same"]["verdict"] == "not distinguishable from best_qc"
    assert board["methods"]["good"]["runs"] == 3
    assert board["methods"]["good"]["probability_of_improvement"]["estimate"] == 1.0
    text = leaderboard_markdown(board)
    assert "Beat the best-Q_C pick" in text and "`good`" in text
    assert "indicative only" not in text  # 12 objects
    few = build_leaderboard(pd.DataFrame(rows)[lambda f: f["object_id"].isin(["o1", "o2"])],
                            {"name": "t", "version": 0}, reps=100)  # fmt: skip
    assert "Only 2 objects" in leaderboard_markdown(few)


def _plain() -> dict[str, float]:
    keys = ("success", "robustness", "regret", "robustness_regret", "ndcg5", "attempts",
            *(f"success_at_{k}" for k in range(1, 6)))
    return dict.fromkeys(keys, 0.5)


def test_report_and_readme_show_the_leaderboard_and_its_verdict(tmp_path) -> None:
    from classifiers.experiments.benchmark.leaderboard import write_leaderboard
    from classifiers.report.document import Report
    from classifiers.report.readme import _leaderboard_lines
    from classifiers.report.study_report import _benchmark_section

    rows = [{"method": m, "seed": 0, "object_id": f"o{i}", "normalised": v + 0.01 * i,
             **_plain()} for i in range(10) for m, v in (("best_qc", 0.1), ("good", 0.9))]
    board = build_leaderboard(pd.DataFrame(rows), {"name": "t", "version": 0}, reps=300)
    write_leaderboard(board, tmp_path / "benchmark")
    report = Report("r")
    _benchmark_section(report, tmp_path)
    text = report.to_markdown()
    assert "## Leaderboard" in text and "Beat the best-Q_C pick" in text
    assert "| good | 1 |" in text and "benchmark/performance_profile.png" in text
    readme = "\n".join(_leaderboard_lines(tmp_path))
    assert "| good | 1 | 0.500 [0.500, 0.500] |" in readme and "`good`" in readme


@pytest.mark.parametrize("attempts", [1, 2, 3])
def test_success_within_k_is_what_grip_accept_earns_executing_the_top_k(attempts: int) -> None:
    """GripAccept-v0 shows candidates in Q_C order; an agent executing exactly the method's
    top-k (in another order) holds as often as the exact ``success_at_k`` says."""
    import gymnasium

    import grip_env  # noqa: F401  (registers the environments)
    from classifiers.evaluation.synthetic import synthetic_grips
    from grip_env.envs.observation import best_candidates

    table = synthetic_grips(n_objects=2, grips=(8, 8), trials=4, seed=0)
    rows = best_candidates(table[table["object_id"] == 0], 8)
    candidates = pd.DataFrame({"object_id": "0", "candidate": np.arange(8),
                               "success_rate": rows["successes"] / rows["trials"]})
    score = np.array([7.0, 1, 2, 8, 3, 6, 4, 5])  # top 3 in slots 3, 0, 5 (not Q_C order)
    exact = selection_metrics(candidates, pd.DataFrame({
        "method": "m", "seed": 0, "object_id": "0", "candidate": np.arange(8), "score": score,
    }))[f"success_at_{attempts}"].item()  # fmt: skip
    top = set(np.argsort(-score)[:attempts].tolist())
    env = gymnasium.make("GripAccept-v0", data=table, max_candidates=8, max_attempts=attempts,
                         split="all")  # fmt: skip
    episodes, held = 3000, 0
    for episode in range(episodes):
        env.reset(seed=episode if episode == 0 else None, options={"object_id": "0"})
        for position in range(8):
            _, _, terminated, _, info = env.step(int(position in top))
            if terminated:
                held += bool(info["success"])
                break
    env.close()
    rates = candidates["success_rate"].to_numpy()
    assert exact == pytest.approx(1 - np.prod(1 - rates[[3, 0, 5][:attempts]]))
    assert 0.05 < exact < 0.95  # (0.25, 0.5, 0.25 today): a check the simulation can fail
    assert abs(held / episodes - exact) < 4 * np.sqrt(exact * (1 - exact) / episodes)


def test_study_benchmark_reads_the_learners_per_seed_score_files(tmp_path) -> None:
    from classifiers.evaluation.synthetic import synthetic_grips
    from classifiers.experiments.benchmark import study_benchmark
    from classifiers.experiments.benchmark.split import candidate_sets, candidate_table, study_split
    from grip_env.config import Config

    table = synthetic_grips(n_objects=16, grips=(5, 9), seed=3)
    table["object_id"] = table["object_id"].astype(str)
    table["grip_id"] = table["grip_id"].astype(str)
    config = Config().override(selector={"max_candidates": 8})
    held = candidate_table(candidate_sets(table, config, study_split(table, config, [0])))
    rng = np.random.default_rng(0)
    frames = [held[["object_id", "candidate", "grip_id"]].assign(method=m, seed=s,
                                                                 score=rng.random(len(held)))
              for m in ("classifier_x", "classifier_rank_qc") for s in (0, 1, 2)]  # fmt: skip
    (tmp_path / "classifiers").mkdir()
    pd.concat(frames).to_parquet(tmp_path / "classifiers" / "scores.parquet")
    board = study_benchmark(table, tmp_path, config, reps=200)
    assert board["methods"]["classifier_x"]["runs"] == 3
    assert "classifier_rank_qc" not in board["methods"] and "best_qc" in board["methods"]
    assert board["split"]["seeds"] == [0, 1, 2] and board["split"]["name"] == "study"
    assert (tmp_path / "benchmark" / "leaderboard.json").exists()  # the .md is the report's
    train = table[~table["object_id"].isin(set(held["object_id"]))]
    budget = board["methods"]["classifier_x"]["budget"]
    assert (budget["grips"], budget["objects"]) == (len(train), train["object_id"].nunique())
    assert budget["text"] == (f"{len(train):,} labelled grips of {train['object_id'].nunique()} "
                              f"objects ({int(train['trials'].sum()):,} recorded trials)")
    assert "budget" not in board["methods"]["best_qc"]
    pd.concat(frames).iloc[1:].to_parquet(tmp_path / "classifiers" / "scores.parquet")
    with pytest.raises(ValueError, match="every candidate"):
        study_benchmark(table, tmp_path, config, reps=200)


def test_the_success_difference_to_best_qc_is_paired_over_every_held_out_object(tmp_path) -> None:
    """A method that succeeds 0.2 more than best-Q_C on every object has difference 0.2 with a
    zero-width interval (paired: the objects' spread cancels), although each method's own
    success interval is wide; degenerate objects (no normalised score) still count."""
    rng = np.random.default_rng(1)
    base = rng.uniform(0.1, 0.7, 20)
    rows = [{"method": m, "seed": 0, "object_id": f"o{i}", "normalised": np.nan if i < 4 else
             0.1 + shift + 0.01 * i, **_plain(), "success": base[i] + shift}
            for i in range(20) for m, shift in (("best_qc", 0.0), ("rl", 0.2))]
    board = build_leaderboard(pd.DataFrame(rows), {"name": "t", "version": 0}, reps=300)
    found = board["methods"]["rl"]["success_difference_vs_reference"]
    assert found["estimate"] == pytest.approx(0.2)
    assert found["ci"] == pytest.approx([0.2, 0.2])
    low, high = board["methods"]["rl"]["success_ci"]
    assert high - low > 0.1
    assert len(board["objects"]) == 16 and len(board["degenerate_objects"]) == 4
    from classifiers.experiments.benchmark.leaderboard import write_leaderboard
    from classifiers.report.answers import signed
    from classifiers.report.readme import _leaderboard_lines

    write_leaderboard(board, tmp_path / "benchmark")
    assert signed(found) == "+0.200 [+0.200, +0.200]"
    assert "(20 held-out objects, 16 rankable)" in "\n".join(_leaderboard_lines(tmp_path))


def test_the_study_leaderboard_lists_the_rl_selectors_environment_steps(tmp_path) -> None:
    """Each run's zip (``selector/seed_<s>/model.zip``) says its steps; the table shows them."""
    from classifiers.evaluation.synthetic import synthetic_grips
    from classifiers.experiments.benchmark import study_benchmark
    from classifiers.experiments.benchmark.split import candidate_sets, candidate_table, study_split
    from classifiers.experiments.selector.training import make_selector_env, make_selector_model
    from classifiers.report.leaderboard import leaderboard_markdown
    from grip_env.config import Config

    table = synthetic_grips(n_objects=16, grips=(5, 9), seed=3)
    table["object_id"] = table["object_id"].astype(str)
    table["grip_id"] = table["grip_id"].astype(str)
    config = Config().override(selector={"max_candidates": 8})
    held = candidate_table(candidate_sets(table, config, study_split(table, config, [0, 1])))
    rng = np.random.default_rng(0)
    for seed in (0, 1):
        env = make_selector_env(table, config, split="train", n_envs=1)
        model = make_selector_model(env, "set", seed=seed, timesteps=16)
        model.learn(16 * (seed + 1))
        (tmp_path / "selector" / f"seed_{seed}").mkdir(parents=True)
        model.save(tmp_path / "selector" / f"seed_{seed}" / "model.zip")
        env.close()
    frames = [held[["object_id", "candidate", "grip_id"]].assign(method="rl", seed=s,
                                                                 score=rng.random(len(held)))
              for s in (0, 1)]  # fmt: skip
    pd.concat(frames).to_parquet(tmp_path / "selector" / "scores.parquet")
    board = study_benchmark(table, tmp_path, config, reps=200)
    budget = board["methods"]["rl"]["budget"]
    steps = [run["environment_steps"] for run in budget["runs"]]
    assert steps[1] > steps[0] >= 16  # each run's own count, as SB3 saved it
    assert budget["text"] == "; ".join(f"{n:,} environment steps" for n in steps)
    assert "| training budget |" in leaderboard_markdown(board)
