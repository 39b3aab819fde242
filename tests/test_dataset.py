"""Dataset storage, manifest, resume, parallel backends and validation.

Most tests inject ``toy_job``, a cheap deterministic per-object job whose rows have consistent
features, so the machinery is tested in isolation; the end-to-end test uses the real job.
"""

from __future__ import annotations

import json
import os
import signal
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from grip_env.columns import DATASET_COLUMNS, DESCRIPTORS
from grip_env.config import Config
from grip_env.dataset import (
    FORMAT_VERSION,
    DatasetMismatchError,
    FormatVersionError,
    ObjectTask,
    WorkerLost,
    generate,
    keep_grips,
    kept_ranks,
    load,
    load_objects,
    read_objects,
    validate,
    with_outcomes,
)
from grip_env.dataset.files import sha256_of
from grip_env.dataset.jobs import object_seeds
from grip_env.objects import load_object_set
from grip_env.planning.features import compute_features
from grip_env.planning.pipeline import candidates

CONFIG = Config().override(dataset={"trials": 4, "seed": 7, "max_grips_per_object": 5})
TRIALS_SEEN: list[int] = []


def toy_job(task: ObjectTask) -> pd.DataFrame:
    """Rows drawn from the task seed only: valid descriptors, exact features, binomial outcomes."""
    rng = np.random.default_rng(task.seed)
    count = 1 + task.index % 3
    angles = rng.uniform(0, 2 * np.pi, (count, 6))
    columns = {name: rng.uniform(-50, 50, count) for name in DESCRIPTORS}
    for k, prefix in enumerate(("n1", "n2", "n3", "f1", "f2", "f3")):
        columns[f"{prefix}_x"], columns[f"{prefix}_y"] = np.cos(angles[:, k]), np.sin(angles[:, k])
    columns |= {f"rho{i}": rng.uniform(-0.3, 0.3, count) for i in (1, 2, 3)}
    columns |= {f"e{i}": rng.uniform(40, 150, count) for i in (1, 2, 3)}
    columns["spread"] = rng.uniform(0, 1.4, count)
    columns |= {name: np.full(count, value) for name, value in task.obj.descriptors().items()}
    grips = pd.DataFrame(columns)
    grips.insert(0, "object_id", "ignored")
    grips.insert(1, "grasp_id", np.arange(count))
    grips.insert(2, "grip_id", np.arange(count))
    grips.insert(3, "two_finger", False)
    grips = pd.concat([grips, compute_features(grips, task.config.grasp)], axis=1)
    trials = np.full(count, task.config.dataset.trials)
    robustness = rng.uniform(0.0, 3.0, (count, trials[0]))
    outcome = pd.DataFrame({
        "trials": trials, "successes": (robustness >= 1.5).sum(axis=1),
        "robustness_mean": robustness.mean(axis=1), "robustness_std": robustness.std(axis=1),
    })
    return with_outcomes(grips, outcome, task.object_id)


def empty_job(task: ObjectTask) -> pd.DataFrame:
    """An object with no feasible grip."""
    return toy_job(task).iloc[:0]


def run(out: Path, **kwargs) -> Path:  # type: ignore[no-untyped-def]
    options = {"objects": 5, "workers": 1, "progress": False, "job": toy_job} | kwargs
    return generate(CONFIG, out, **options)


# ----------------------------------------------------------------------------- layout, round trip
def test_layout_manifest_and_load_round_trip(tmp_path: Path) -> None:
    path = run(tmp_path / "d")
    manifest = json.loads((path / "manifest.json").read_text())
    shards = sorted(p.name for p in (path / "grips").iterdir())
    assert shards[0].startswith("part-000000-proc_7_00000")
    assert len(shards) == 5 and manifest["complete"]
    assert manifest["seed"] == 7 and manifest["trials"] == 4
    assert manifest["params"] == CONFIG.grasp.model_dump(mode="json")
    assert {"numpy", "pandas", "pyarrow", "python"} <= set(manifest["versions"])
    grips = load(path)
    assert list(grips.columns) == list(DATASET_COLUMNS)
    # objects have 1, 2, 3, 1, 2 rows in that order
    assert len(grips) == manifest["rows"] == 9
    object_ids = [entry["object_id"] for entry in manifest["objects"]]
    assert list(grips["object_id"].drop_duplicates()) == object_ids
    assert grips["grip_id"].is_unique
    assert grips.attrs["params"]["feature_cap"] == CONFIG.grasp.feature_cap
    assert pq.read_schema(path / "grips" / shards[0]).metadata[b"grip_env"]
    expected = pd.concat([toy_job(_task(path, i)) for i in range(5)], ignore_index=True)
    pd.testing.assert_frame_equal(grips, expected, check_dtype=False)
    assert validate(path) == []


def _task(path: Path, index: int) -> ObjectTask:
    obj = load_objects(path)[index]
    seed = object_seeds(7, 5)[index]
    object_id = json.loads((path / "manifest.json").read_text())["objects"][index]["object_id"]
    return ObjectTask(index, object_id, obj, CONFIG, seed)


def test_objects_table_round_trip(tmp_path: Path) -> None:
    path = run(tmp_path / "d", objects="default")
    restored = load_objects(path)
    originals = load_object_set("default")
    assert [o.name for o in restored] == [o.name for o in originals]
    for before, after in zip(originals, restored, strict=True):
        np.testing.assert_allclose(after.contour, before.contour)


def test_objects_table_describes_the_body_at_the_configured_tolerance(tmp_path: Path) -> None:
    coarse = CONFIG.override(objects={"sim_tolerance_mm": 3.0})
    fine = CONFIG.override(objects={"sim_tolerance_mm": 0.1})
    options = {"objects": "ellipse", "workers": 1, "progress": False, "job": toy_job}
    tables = [read_objects(generate(config, tmp_path / name, **options))
              for name, config in (("coarse", coarse), ("fine", fine))]
    assert tables[0]["sim_tolerance_mm"].tolist() == [3.0]
    assert tables[1]["sim_tolerance_mm"].tolist() == [0.1]
    assert tables[0]["sim_vertices"][0] < tables[1]["sim_vertices"][0]
    assert tables[0]["sim_deviation_mm"][0] <= 3.0 and tables[1]["sim_deviation_mm"][0] <= 0.1


def test_object_seeds_depend_on_run_seed_and_index_only() -> None:
    assert object_seeds(3, 4)[:2] == object_seeds(3, 2)
    assert object_seeds(3, 2) != object_seeds(4, 2)
    assert len(set(object_seeds(0, 100))) == 100


def test_empty_object_is_a_valid_empty_shard(tmp_path: Path) -> None:
    path = run(tmp_path / "d", objects=2, job=empty_job)
    grips = load(path)
    assert grips.empty and list(grips.columns) == list(DATASET_COLUMNS)
    assert grips["trials"].dtype == np.int64
    assert validate(path) == []


# ----------------------------------------------------------------- which grips a dataset keeps
def test_stratified_keeps_the_best_quarter_and_one_pick_per_stratum() -> None:
    ranks = kept_ranks(200, 30, "stratified", seed=11)
    assert len(ranks) == len(set(ranks)) == 30 and (np.diff(ranks) > 0).all()
    np.testing.assert_array_equal(ranks[:8], np.arange(8))  # ceil(30 / 4) from the best end
    # the other 22: one in each of 22 equal-rank strata of ranks 8..199, down to the worst end
    edges = 8 + np.arange(23) * 192 // 22
    strata = np.searchsorted(edges, ranks[8:], side="right") - 1
    np.testing.assert_array_equal(strata, np.arange(22))
    assert (ranks >= 150).sum() >= 5  # the worst quartile is covered
    np.testing.assert_array_equal(ranks, kept_ranks(200, 30, "stratified", seed=11))
    assert not np.array_equal(ranks, kept_ranks(200, 30, "stratified", seed=12))


@pytest.mark.parametrize("method", ["stratified", "best", "uniform"])
def test_every_method_keeps_all_when_there_are_few(method: str) -> None:
    np.testing.assert_array_equal(kept_ranks(5, 30, method, seed=0), np.arange(5))
    assert len(kept_ranks(0, 30, method, seed=0)) == 0


def test_best_and_uniform_sampling() -> None:
    np.testing.assert_array_equal(kept_ranks(100, 10, "best", seed=3), np.arange(10))
    uniform = kept_ranks(100, 10, "uniform", seed=3)
    assert len(set(uniform)) == 10 and (np.diff(uniform) > 0).all() and uniform.max() < 100
    np.testing.assert_array_equal(uniform, kept_ranks(100, 10, "uniform", seed=3))
    with pytest.raises(ValueError, match="unknown sampling 'top'"):
        kept_ranks(100, 10, "top", seed=3)


def test_stratified_grips_of_a_real_object_span_its_q_c_ranking() -> None:
    pentagon = next(o for o in load_object_set("default") if o.name == "pentagon")
    table = candidates(pentagon, CONFIG.grasp, CONFIG)
    dataset = Config().dataset
    assert dataset.sampling == "stratified" and len(table) > 2 * dataset.max_grips_per_object
    kept = keep_grips(table, dataset, seed=5)
    assert len(kept) == dataset.max_grips_per_object and kept["Q_C"].is_monotonic_increasing
    assert kept["Q_C"].iloc[0] == table["Q_C"].min()
    assert (kept["Q_C"] >= table["Q_C"].quantile(0.75)).sum() >= 5
    best = keep_grips(table, dataset.model_copy(update={"sampling": "best"}), seed=5)
    assert best["Q_C"].max() < table["Q_C"].quantile(0.5)
    pd.testing.assert_frame_equal(kept, keep_grips(table, dataset, seed=5))


def test_manifest_records_the_sampling_and_a_change_is_refused(tmp_path: Path) -> None:
    out = run(tmp_path / "d")
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["sampling"] == {"method": "stratified", "max_grips_per_object": 5,
                                    "best_fraction": 0.25, "ranked_by": "Q_C"}
    best = CONFIG.override(dataset={"sampling": "best"})
    with pytest.raises(DatasetMismatchError, match=r"dataset\.sampling: 'stratified' -> 'best'"):
        generate(best, out, objects=5, workers=1, progress=False, job=toy_job)


# ----------------------------------------------------------------------------- parallel, resume
def test_same_dataset_from_one_and_two_workers(tmp_path: Path) -> None:
    serial = load(run(tmp_path / "one", workers=1))
    pooled = load(run(tmp_path / "two", workers=2))
    pd.testing.assert_frame_equal(serial, pooled)


@pytest.mark.slow
def test_same_dataset_from_ray_backend(tmp_path: Path) -> None:
    ray = pytest.importorskip("ray")
    ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        via_ray = load(run(tmp_path / "ray", workers=2, backend="ray"))
    finally:
        ray.shutdown()
    pd.testing.assert_frame_equal(load(run(tmp_path / "local")), via_ray)


def counting_job(task: ObjectTask) -> pd.DataFrame:
    TRIALS_SEEN.append(task.index)
    return toy_job(task)


def failing_after_two(task: ObjectTask) -> pd.DataFrame:
    if task.index >= 2:
        raise RuntimeError("simulated crash")
    return toy_job(task)


def test_resume_after_crash_computes_only_missing_objects(tmp_path: Path) -> None:
    out = tmp_path / "d"
    with pytest.raises(RuntimeError, match="simulated crash"):
        run(out, job=failing_after_two)
    manifest = json.loads((out / "manifest.json").read_text())
    assert sorted(manifest["shards"]) == ["proc_7_00000", "proc_7_00001"]
    assert not manifest["complete"]
    with pytest.raises(ValueError, match="unfinished"):
        load(out)
    TRIALS_SEEN.clear()
    run(out, job=counting_job)
    assert TRIALS_SEEN == [2, 3, 4]
    pd.testing.assert_frame_equal(load(out), load(run(tmp_path / "clean")))
    TRIALS_SEEN.clear()
    run(out, job=counting_job)
    assert TRIALS_SEEN == []


def dying_job(task: ObjectTask) -> pd.DataFrame:
    if task.index == 3:
        os.kill(os.getpid(), signal.SIGKILL)
    return toy_job(task)


def test_resume_after_a_killed_worker(tmp_path: Path) -> None:
    out = tmp_path / "d"
    with pytest.raises(WorkerLost, match="proc_7_0000"):
        run(out, workers=2, job=dying_job)
    assert not json.loads((out / "manifest.json").read_text())["complete"]
    pd.testing.assert_frame_equal(load(run(out, workers=2)), load(run(tmp_path / "clean")))


def test_job_error_in_a_pool_worker_reaches_the_caller_and_ends_the_workers(
    tmp_path: Path,
) -> None:
    import multiprocessing

    with pytest.raises(RuntimeError, match="simulated crash"):
        run(tmp_path / "d", workers=2, job=failing_after_two)
    assert not [p for p in multiprocessing.active_children() if p.name == "grip-env-worker"]
    assert not json.loads((tmp_path / "d" / "manifest.json").read_text())["complete"]


def test_resume_recomputes_a_deleted_shard(tmp_path: Path) -> None:
    out = run(tmp_path / "d")
    next((out / "grips").glob("part-000003-*")).unlink()
    TRIALS_SEEN.clear()
    run(out, job=counting_job)
    assert TRIALS_SEEN == [3]
    assert validate(out) == []


def test_other_seed_into_same_dir_is_refused_unless_overwrite(tmp_path: Path) -> None:
    out = run(tmp_path / "d")
    with pytest.raises(DatasetMismatchError, match=r"dataset\.seed: 7 -> 8"):
        generate(CONFIG, out, objects=5, seed=8, workers=1, progress=False, job=toy_job)
    with pytest.raises(DatasetMismatchError, match="trials"):
        run(out, trials=2)
    run(out, trials=2, overwrite=True)
    assert (load(out)["trials"] == 2).all()
    # workers and backend do not change the data, so they may differ on resume
    run(out, trials=2, workers=2)


# ----------------------------------------------------------------------------- validation, errors
def test_validate_catches_corrupted_shard(tmp_path: Path) -> None:
    out = run(tmp_path / "d")
    shard = next((out / "grips").glob("part-000001-*"))
    data = bytearray(shard.read_bytes())
    data[len(data) // 2] ^= 0xFF
    shard.write_bytes(bytes(data))
    problems = validate(out)
    assert any("part-000001" in p and "SHA-256" in p for p in problems)
    with pytest.raises(ValueError, match="corrupt"):
        load(out)


def _rewrite_shard(out: Path, index: int, change) -> None:  # type: ignore[no-untyped-def]
    """Tamper with a shard's rows while keeping its metadata (checksum will differ)."""
    shard = next((out / "grips").glob(f"part-{index:06d}-*"))
    table = pq.read_table(shard)
    frame = table.to_pandas()
    change(frame)
    pq.write_table(table.from_pandas(frame, schema=table.schema, preserve_index=False), shard)


def test_validate_catches_tampered_feature_and_outcome(tmp_path: Path) -> None:
    out = run(tmp_path / "d")

    def tamper(frame: pd.DataFrame) -> None:
        frame.loc[0, "C3"] += 0.01
        frame.loc[1, "successes"] = frame.loc[1, "trials"] + 1

    _rewrite_shard(out, 2, tamper)
    problems = validate(out)
    assert any("C3 differs" in p and "1 row(s)" in p for p in problems)
    assert any("successes outside" in p for p in problems)
    assert any("SHA-256" in p for p in problems)
    assert not any("part-000000" in p for p in problems)


def test_validate_reports_unfinished_run(tmp_path: Path) -> None:
    out = tmp_path / "d"
    with pytest.raises(RuntimeError):
        run(out, job=failing_after_two)
    assert sum("no shard" in p for p in validate(out)) == 3


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"trials": 0}, "trials must be >= 1"),
    ({"workers": 0}, "workers must be an integer >= 1"),
    ({"backend": "dask"}, "unknown backend 'dask'"),
    ({"objects": "no_such_set"}, "unknown object set 'no_such_set'"),
    ({"objects": 0}, "number of objects must be >= 1"),
    ({"seed": -1}, "seed must be >= 0"),
])
def test_bad_arguments_raise_value_error(tmp_path: Path, kwargs, message) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ValueError, match=message):
        run(tmp_path / "d", **kwargs)
    assert not (tmp_path / "d" / "manifest.json").exists()


def test_unwritable_or_file_output_is_refused(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(ValueError, match="not a directory"):
        run(blocker)
    with pytest.raises(ValueError, match="not writable"):
        run(blocker / "sub")


def _set_format_version(out: Path, version: int) -> None:
    manifest = json.loads((out / "manifest.json").read_text())
    manifest["format_version"] = version
    (out / "manifest.json").write_text(json.dumps(manifest))


def test_other_format_version_and_non_dataset_are_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="not a grip-env dataset"):
        load(tmp_path)
    out = run(tmp_path / "d")
    _set_format_version(out, 999)
    for call in (load, validate):
        with pytest.raises(FormatVersionError, match=r"format version 999.*upgrade grip-env"):
            call(out)
    with pytest.raises(DatasetMismatchError, match=r"format_version: 999 -> 2.*--overwrite"):
        run(out)


def test_too_old_dataset_says_regenerate_in_one_line(tmp_path: Path) -> None:
    out = run(tmp_path / "d")
    _set_format_version(out, 1)
    for call in (load, validate):
        with pytest.raises(FormatVersionError) as caught:
            call(out)
        message = str(caught.value)
        assert "format version 1" in message and "reads version 2" in message
        assert "regenerate" in message and "\n" not in message
    with pytest.raises(DatasetMismatchError, match=r"format_version: 1 -> 2"):
        run(out)
    run(out, overwrite=True)
    assert load(out).attrs["manifest"]["format_version"] == FORMAT_VERSION == 2


def test_validate_accepts_large_string_columns(tmp_path: Path) -> None:
    out = run(tmp_path / "d")
    shard = next((out / "grips").glob("part-000001-*"))
    table = pq.read_table(shard)
    for name in ("object_id", "grip_id"):
        position = table.schema.get_field_index(name)
        table = table.set_column(position, name, table[name].cast(pa.large_string()))
    pq.write_table(table, shard)
    manifest = json.loads((out / "manifest.json").read_text())
    record = next(r for r in manifest["shards"].values() if r["file"].endswith(shard.name))
    record["sha256"] = sha256_of(shard)
    (out / "manifest.json").write_text(json.dumps(manifest))
    assert pq.read_schema(shard).field("grip_id").type == pa.large_string()
    assert validate(out) == []
    assert len(load(out)) == 9


def test_validate_flags_negative_or_missing_robustness(tmp_path: Path) -> None:
    out = run(tmp_path / "d")

    def tamper(frame: pd.DataFrame) -> None:
        frame.loc[0, "robustness_mean"] = -0.5
        frame.loc[1, "robustness_std"] = np.nan

    _rewrite_shard(out, 2, tamper)
    problems = validate(out)
    assert any("robustness_mean not a finite value >= 0 g in 1 row(s)" in p for p in problems)
    assert any("robustness_std not a finite value >= 0 g in 1 row(s)" in p for p in problems)


def test_missing_shard_is_refused_by_load(tmp_path: Path) -> None:
    out = run(tmp_path / "d")
    next((out / "grips").glob("part-000004-*")).unlink()
    with pytest.raises(ValueError, match="missing"):
        load(out)
    assert any("part-000004" in p and "missing" in p for p in validate(out))


# ----------------------------------------------------------------------------- the real job
REAL = Config().override(dataset={"max_grips_per_object": 2, "trials": 2, "seed": 3})
POLYGON = REAL.override(perception={"source": "polygon"})


@pytest.mark.slow
def test_real_job_same_dataset_from_one_and_two_workers(tmp_path: Path) -> None:
    config = POLYGON.override(dataset={"max_grips_per_object": 3, "trials": 1})
    serial = generate(config, tmp_path / "one", objects="basic", workers=1, progress=False)
    pooled = generate(config, tmp_path / "two", objects="basic", workers=2, progress=False)
    grips = load(serial)
    pd.testing.assert_frame_equal(grips, load(pooled))
    assert validate(serial) == []
    assert set(grips["object_id"]) <= {"rectangle", "triangle", "hexagon", "l_shape"}
    assert (grips.groupby("object_id").size() <= 3).all()
    assert (grips["trials"] == 1).all()
    assert grips["grip_id"].str.count("/").eq(2).all()  # object/grasp/thumb, one object prefix
    assert (grips["robustness_mean"] >= 0).all() and (grips["robustness_std"] >= 0).all()
    # within an object, rows are the stratified sample of its Q_C ranking, best first
    manifest = grips.attrs["manifest"]
    for entry, obj in zip(manifest["objects"], load_object_set("basic"), strict=True):
        rows = grips[grips["object_id"] == entry["object_id"]]
        task = ObjectTask(entry["index"], entry["object_id"], obj, config, entry["seed"])
        ranked = candidates(obj, config.grasp, config).sort_values("Q_C", kind="stable")
        ranks = kept_ranks(len(ranked), 3, "stratified", task.sampling_seed())
        np.testing.assert_allclose(rows["Q_C"].to_numpy(), ranked["Q_C"].to_numpy()[ranks])
        assert rows["Q_C"].is_monotonic_increasing


@pytest.mark.slow
def test_real_job_plans_on_perceived_contour(tmp_path: Path) -> None:
    from grip_env.dataset import load_perceived_objects
    from grip_env.objects import make_shape
    from grip_env.sim.camera import perceive

    config = REAL.override(perception={"source": "render"})
    seen_dir = generate(config, tmp_path / "d", objects="rectangle", workers=1, progress=False)
    true_dir = generate(POLYGON, tmp_path / "p", objects="rectangle", workers=1, progress=False)
    grips, planned = load(seen_dir), load(true_dir)
    assert len(grips) > 0
    # the perceived rectangle's descriptors differ slightly from the true polygon's
    assert not np.allclose(grips["area"].iloc[0], planned["area"].iloc[0], rtol=0, atol=1e-9)
    assert np.isclose(grips["area"].iloc[0], planned["area"].iloc[0], rtol=0.05)
    # the objects table keeps the perceived contour beside the true one; it is what was planned on
    (seen,), (true,) = load_perceived_objects(seen_dir), load_objects(seen_dir)
    assert load_perceived_objects(true_dir) == [None]
    np.testing.assert_allclose(true.contour, make_shape("rectangle").contour)
    entry = grips.attrs["manifest"]["objects"][0]
    task = ObjectTask(0, entry["object_id"], make_shape("rectangle"), config, entry["seed"])
    np.testing.assert_allclose(
        seen.contour, perceive(task.obj, config.perception, seed=task.child_seeds()[0]).contour)
    assert grips["area"].iloc[0] == pytest.approx(seen.area)
    assert validate(seen_dir) == [] and validate(true_dir) == []


def test_validate_checks_the_perceived_contours(tmp_path: Path) -> None:
    config = CONFIG.override(perception={"source": "render"})
    out = generate(config, tmp_path / "d", objects="basic", workers=1, progress=False,
                   job=toy_job)
    assert validate(out) == []
    path = out / "objects.parquet"
    table = pq.read_table(path)
    contours = table["perceived_contour"].to_pylist()
    contours[1] = [[0.0, 0.0], [1.0, 1.0]]
    index = table.schema.get_field_index("perceived_contour")
    pq.write_table(table.set_column(index, table.schema.field(index), pa.array(
        contours, table.schema.field(index).type)), path)
    manifest = json.loads((out / "manifest.json").read_text())
    manifest["objects_file"]["sha256"] = sha256_of(path)
    (out / "manifest.json").write_text(json.dumps(manifest))
    assert validate(out) == ["objects.parquet: object triangle: perceived_contour is not a "
                             "contour of >= 3 finite points"]


def test_frames_derived_from_a_loaded_table_share_its_manifest(generated_dataset_dir):
    """pandas deep-copies attrs on every operation: the manifest is shared, so selecting one
    object's rows of the standard dataset does not copy 598 objects' records."""
    import copy

    from grip_env.dataset import load

    table = load(generated_dataset_dir)
    manifest = table.attrs["manifest"]
    part = table[table["object_id"] == table["object_id"].iloc[0]][["Q_C", "success"]]
    assert part.attrs["manifest"] is manifest and copy.deepcopy(manifest) is manifest
    assert json.loads(json.dumps(manifest)) == dict(manifest)  # still plain JSON


def test_a_string_format_version_is_refused_as_the_wrong_type(tmp_path: Path) -> None:
    out = run(tmp_path / "d")
    manifest = json.loads((out / "manifest.json").read_text())
    manifest["format_version"] = str(FORMAT_VERSION)
    (out / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(FormatVersionError) as caught:
        load(out)
    message = str(caught.value)
    assert f"the string '{FORMAT_VERSION}'" in message and "an integer" in message, message
    assert f"format version '{FORMAT_VERSION}', this grip-env reads" not in message


def test_a_truncated_manifest_is_refused_with_how_to_recover(tmp_path: Path) -> None:
    out = run(tmp_path / "d")
    text = (out / "manifest.json").read_text()
    (out / "manifest.json").write_text(text[: len(text) // 2])
    for call in (load, validate):
        with pytest.raises(ValueError, match="corrupt") as caught:
            call(out)
        assert "--overwrite" in str(caught.value) and "\n" not in str(caught.value)
    with pytest.raises(DatasetMismatchError, match=r"manifest.json is unreadable.*--overwrite"):
        run(out)
    run(out, overwrite=True)  # the recovery the message names works
    assert len(load(out)) == len(load(run(tmp_path / "fresh")))
