"""Physics sanity of grip execution: good grips hold, bad ones fail, labels are reproducible."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest

from grip_env.config import Config
from grip_env.objects import PlanarObject, make_shape
from grip_env.planning.finger import finger_reaches
from grip_env.sim import (
    TrialNoise,
    render_trial_strip,
    run_trial_outcomes,
    run_trials,
    sample_noise,
)
from grip_env.sim.uncertainty import stable_key, trial_noises, trial_rng

BOX = make_shape("rectangle")  # 90 x 55 mm
PLATE = PlanarObject.from_polygon(
    np.array([[-50, -30], [50, -30], [50, 30], [-50, 30]], dtype=float), name="plate"
)


def grip(palm, yaw, spread, contacts, grip_id="g"):
    row = {"grip_id": grip_id, "hand_x": palm[0], "hand_y": palm[1], "hand_yaw": yaw,
           "spread": spread}
    for i, (x, y) in enumerate(contacts, start=1):
        row[f"p{i}_x"], row[f"p{i}_y"] = x, y
    return row


# Thumb on the lower long side pushing +y, fingers 1 and 2 side by side on the upper side.
OPPOSED = grip((0, 0), np.pi / 2, 0.0, ((25, 27.5), (-25, 27.5), (0, -27.5)), "opposed")


def test_finger_reaches_of_a_hand_built_grip():
    reaches = finger_reaches(pd.DataFrame([OPPOSED]))
    np.testing.assert_allclose(reaches, [[27.5, 27.5, 27.5]], atol=1e-9)


def test_centred_opposed_grip_on_a_box_holds():
    result = run_trials(BOX, pd.DataFrame([OPPOSED]), trials=5, seed=0)
    assert result.loc[0, "robustness_mean"] >= 8.0  # 74 g box, 3 x 15 N at mu >= 0.4


def test_heavy_object_with_low_friction_slips():
    # Steel (7.85 g/cm^3), weight class 2: 2.3 kg against 3 x 15 N at mu 0.2 (9 N of friction).
    config = Config().override(grasp={"mu": 0.2, "weight": 2.0},
                               uncertainty={"friction_range": (0.2, 0.25)},
                               objects={"density_kg_m3": 7850.0})
    result = run_trials(BOX, pd.DataFrame([OPPOSED]), config, trials=5, seed=0)
    assert result.loc[0, "successes"] <= 1
    assert result.loc[0, "robustness_mean"] < 1.0


@pytest.mark.slow
def test_fingers_facing_each_other_fail_more_than_opposed_fingers():
    spread = 1.45  # fingers 1 and 2 press the short sides almost head on; the thumb is unopposed
    reach = 25 / np.sin(spread)
    facing = grip((0, 0), np.pi / 2, spread,
                  ((50, reach * np.cos(spread)), (-50, reach * np.cos(spread)), (0, -30)), "f")
    opposed = grip((0, 0), np.pi / 2, 0.0, ((25, 30), (-25, 30), (0, -30)), "o")
    config = Config().override(grasp={"mu": 0.2}, uncertainty={"friction_range": (0.3, 0.3)},
                               objects={"density_kg_m3": 1700.0})  # 0.3 kg
    result = run_trials(PLATE, pd.DataFrame([facing, opposed]), config, trials=6, seed=0)
    assert result.loc[1, "robustness_mean"] >= 2.0  # 0.3 kg at mu 0.3: about 0.3 x 45 N / 2.9 N
    assert result.loc[0, "robustness_mean"] <= 0.5 * result.loc[1, "robustness_mean"]


def test_same_seed_same_labels_regardless_of_chunking():
    rows = pd.DataFrame([OPPOSED, {**OPPOSED, "grip_id": "shifted", "hand_x": 6.0}],
                        index=[10, 11])
    config = Config().override(uncertainty={"position_std_mm": 4.0})
    whole = run_trials(BOX, rows, config, trials=2, seed=3)
    again = run_trials(BOX, rows, config, trials=2, seed=3)
    second = run_trials(BOX, rows.iloc[1:], config, trials=2, seed=3)
    pd.testing.assert_frame_equal(whole, again)
    assert list(whole.index) == [10, 11] and (whole["trials"] == 2).all()
    assert second.loc[11, "successes"] == whole.loc[11, "successes"]


def test_noise_depends_only_on_seed_grip_and_trial():
    config = Config()
    a = sample_noise(trial_rng(1, 7, 2), config)
    assert a == sample_noise(trial_rng(1, 7, 2), config)
    assert a != sample_noise(trial_rng(1, 7, 3), config)
    assert isinstance(a, TrialNoise)


def test_noise_statistics_follow_the_config():
    config = Config().override(uncertainty={"position_std_mm": 2.0, "friction_range": (0.1, 0.9)})
    draws = [sample_noise(trial_rng(0, 0, k), config) for k in range(2000)]
    offsets = np.array([d.offset_mm for d in draws])
    friction = np.array([d.friction for d in draws])
    mass = np.array([d.mass_scale for d in draws])
    assert offsets.std() == pytest.approx(2.0, rel=0.1)
    assert friction.min() >= config.grasp.mu and friction.max() <= 0.9  # never below mu
    assert mass.mean() == pytest.approx(1.0, rel=0.05)
    assert mass.std() == pytest.approx(config.uncertainty.mass_rel_std, rel=0.1)


def test_bad_input_is_refused():
    rows = pd.DataFrame([OPPOSED])
    with pytest.raises(ValueError, match="trials"):
        run_trials(BOX, rows, trials=0)
    with pytest.raises(ValueError, match="hand_yaw"):
        run_trials(BOX, rows.drop(columns="hand_yaw"))
    with pytest.raises(ValueError, match="NaN"):
        run_trials(BOX, rows.assign(hand_x=np.nan))
    empty = run_trials(BOX, rows.iloc[:0])
    assert list(empty.columns) == ["trials", "successes", "robustness_mean", "robustness_std"]
    assert empty.empty


def test_trial_strip_is_written(tmp_path):
    from PIL import Image

    path = tmp_path / "strip.png"
    render_trial_strip(BOX, OPPOSED, Config(), seed=0, path=path, width=80, height=60)
    image = np.asarray(Image.open(path))
    assert image.shape == (60, 3 * 80, 3) and image.std() > 0


def _wedge(half_angle: float) -> PlanarObject:
    """A symmetric wedge narrowing towards +x: its long faces lean by ``half_angle`` from x."""
    slope = np.tan(half_angle)
    xs = np.array([-40.0, 35.0])
    top = 27.5 - slope * xs
    return PlanarObject.from_polygon(
        [[xs[0], -top[0]], [xs[1], -top[1]], [xs[1], top[1]], [xs[0], top[0]]], name="wedge"
    )


@pytest.mark.slow
@pytest.mark.parametrize(("half_angle_deg", "holds"), [(10.0, True), (30.0, False)])
def test_squeeze_outside_the_friction_cone_slips(half_angle_deg, holds):
    # Opposed fingers squeeze along y; each face's normal leans half_angle from y. With true
    # friction 0.30-0.35 (cone half-angle 17-19 deg) a 10 deg wedge stays, a 30 deg one squirts out.
    angle = np.radians(half_angle_deg)
    lean = 25 * np.tan(angle)
    wedge_grip = grip((0, 0), np.pi / 2, 0.0, ((25, 27.5 - lean), (-25, 27.5 + lean), (0, -27.5)))
    config = Config().override(grasp={"mu": 0.3}, uncertainty={"friction_range": (0.3, 0.35)},
                               objects={"density_kg_m3": 2000.0})
    result = run_trials(_wedge(angle), pd.DataFrame([wedge_grip]), config, trials=6, seed=0)
    robustness = result.loc[0, "robustness_mean"]
    assert robustness >= 2.0 if holds else robustness <= 0.5


# ------------------------------------------------------------------ common random numbers
def test_every_grip_of_an_object_meets_the_same_draw_in_trial_k():
    rows = pd.DataFrame([OPPOSED, {**OPPOSED, "grip_id": "shifted", "hand_x": 6.0}])
    common = run_trial_outcomes(BOX, rows, trials=3, seed=4).set_index(["grip", "trial"])
    for k in range(3):
        assert common.loc[(0, k), ["friction", "mass_kg"]].tolist() == pytest.approx(
            common.loc[(1, k), ["friction", "mass_kg"]].tolist(), abs=0)
    assert common.loc[(0, 0), "friction"] != common.loc[(0, 1), "friction"]
    own = Config().override(uncertainty={"draws": "per_grip"})
    per_grip = run_trial_outcomes(BOX, rows, own, trials=1, seed=4).set_index("grip")
    assert per_grip.loc[0, "friction"] != per_grip.loc[1, "friction"]


def test_the_common_draw_is_keyed_by_the_object_id_not_by_its_place_in_a_run():
    config = Config()
    keyed = [trial_noises(config, 2, stable_key(name), [0], [0, 1]) for name in ("a", "a", "b")]
    assert keyed[0] == keyed[1] and keyed[0] != keyed[2]
    rows = pd.DataFrame([OPPOSED])
    as_box = run_trial_outcomes(BOX, rows.assign(object_id="box"), trials=1, seed=2)
    as_other = run_trial_outcomes(BOX, rows.assign(object_id="other"), trials=1, seed=2)
    renamed = run_trial_outcomes(dataclasses.replace(BOX, name="box"), rows, trials=1, seed=2)
    assert as_box["friction"].iloc[0] == renamed["friction"].iloc[0]
    assert as_box["friction"].iloc[0] != as_other["friction"].iloc[0]
    with pytest.raises(ValueError, match="one object"):
        run_trial_outcomes(BOX, pd.DataFrame([OPPOSED, OPPOSED]).assign(object_id=["a", "b"]))


def test_per_grip_draws_are_the_draws_before_common_random_numbers():
    """``draws: per_grip`` keeps the old scheme: trial k of grip key g draws from (seed, g, k)."""
    config = Config().override(uncertainty={"draws": "per_grip"})
    noises = trial_noises(config, 5, stable_key("obj"), [11, 12], [0, 1])
    assert noises[1][0] == sample_noise(trial_rng(5, 12, 0), config)


@pytest.mark.parametrize("yaw", [0.0, 0.7, 2.5])
def test_the_palm_error_is_in_the_palm_frame(yaw):
    """The same draw moves every grip's palm by the same amount relative to its own plan: along
    the thumb's force and across it, whatever the plan's yaw."""
    from grip_env.sim import GripPlan, TrialScene

    plan = GripPlan((4.0, -2.0), yaw, 0.0, (27.5, 27.5, 27.5))
    along_thumb = TrialNoise((0.0, 3.0), 0.0, 0.5, 1.0)
    with TrialScene(BOX, Config()) as scene:
        palm, _, _ = scene._place(plan, along_thumb)
    np.testing.assert_allclose(palm - np.asarray(plan.palm_mm),
                               3.0 * np.array([np.cos(yaw), np.sin(yaw)]), atol=1e-12)


def test_stratified_draws_put_one_trial_in_each_stratum_of_a_block():
    config = Config().override(dataset={"trials": 5}, uncertainty={"stratified": True})
    low, high = config.uncertainty.friction_range
    noises = trial_noises(config, 3, 99, [0], range(10))[0]
    for block in (noises[:5], noises[5:]):
        strata = sorted(int((n.friction - low) / (high - low) * 5) for n in block)
        assert strata == [0, 1, 2, 3, 4]
    masses = np.array([n.mass_scale for n in noises])
    assert len(set(np.round(masses, 12))) == 10 and (masses > 0).all()


def test_stratified_palm_errors_put_one_trial_in_each_stratum_and_leave_the_rest_alone():
    """``stratified_palm`` spreads both palm offsets and the yaw error over their normal
    distributions (one trial in each fifth of a block); friction and mass keep their own draws,
    and their stratification keeps its strata."""
    from scipy.special import ndtr

    five = Config().override(dataset={"trials": 5})
    u = five.uncertainty
    palm = five.override(uncertainty={"stratified_palm": True})
    plain = trial_noises(five, 3, 99, [0], range(10))[0]
    spread = trial_noises(palm, 3, 99, [0], range(10))[0]
    for block in (spread[:5], spread[5:]):
        for values, std in (([n.offset_mm[0] for n in block], u.position_std_mm),
                            ([n.offset_mm[1] for n in block], u.position_std_mm),
                            ([n.yaw_error for n in block], u.yaw_std_rad)):
            assert sorted((ndtr(np.array(values) / std) * 5).astype(int)) == [0, 1, 2, 3, 4]
    assert [(n.friction, n.mass_scale) for n in spread] == [
        (n.friction, n.mass_scale) for n in plain]
    assert spread[0].offset_mm != plain[0].offset_mm
    both = five.override(uncertainty={"stratified": True, "stratified_palm": True})
    objects_only = five.override(uncertainty={"stratified": True})
    assert [(n.friction, n.mass_scale) for n in trial_noises(both, 3, 99, [0], range(10))[0]] == [
        (n.friction, n.mass_scale) for n in trial_noises(objects_only, 3, 99, [0], range(10))[0]]


def test_an_unknown_draw_scheme_is_refused_by_name():
    with pytest.raises(ValueError, match="draws"):
        Config().override(uncertainty={"draws": "shared"})


def test_importing_and_connecting_pybullet_prints_nothing():
    """pybullet's C code prints a build banner on stderr at import and ``argv[0]=`` on stdout at
    connection: the simulation layer keeps both off every command's output."""
    import subprocess
    import sys

    script = ("import sys\nfrom grip_env.sim import World\nWorld().close()\n"
              "print('done'); print('still', file=sys.stderr)\n")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    assert (done.stdout, done.stderr) == ("done\n", "still\n")
