"""Configuration: defaults, YAML loading, validation messages."""

from __future__ import annotations

import pytest

from grip_env import GraspParams
from grip_env.config import DEFAULT_CONFIG_PATH, Config, config_reference_markdown, load_config


def test_default_yaml_equals_the_code_defaults():
    assert load_config(DEFAULT_CONFIG_PATH) == Config()
    assert load_config().grasp == GraspParams()


def test_grasp_params_defaults_are_the_papers():
    p = GraspParams()
    assert (p.mu, p.lam, p.weight, p.eta, p.rho_scale, p.feature_cap) == (
        0.4, 2.0, 1.0, 101.5, 10.0, 100.0,
    )


@pytest.mark.parametrize("field", ["mu", "lam", "weight", "eta", "rho_scale"])
def test_negative_parameters_are_refused(field):
    with pytest.raises(ValueError, match=field):
        GraspParams(**{field: -0.1})


def test_unknown_key_is_named(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("grasp:\n  mu: 0.5\n  muu: 3\n")
    with pytest.raises(ValueError, match=r"grasp\.muu"):
        load_config(path)


def test_out_of_range_value_is_named(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("dataset:\n  trials: 0\n")
    with pytest.raises(ValueError, match=r"dataset\.trials"):
        load_config(path)


def test_unsafe_yaml_is_not_executed(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("grasp: !!python/object/apply:os.system ['echo hi']\n")
    with pytest.raises(ValueError, match="not valid YAML"):
        load_config(path)


def test_missing_file_and_non_mapping(tmp_path):
    with pytest.raises(ValueError, match="not found"):
        load_config(tmp_path / "nope.yaml")
    path = tmp_path / "list.yaml"
    path.write_text("- 1\n- 2\n")
    with pytest.raises(ValueError, match="mapping"):
        load_config(path)


def test_override_validates():
    cfg = Config().override(dataset={"trials": 3})
    assert cfg.dataset.trials == 3
    with pytest.raises(ValueError, match="unknown config section"):
        Config().override(nothing={"a": 1})
    with pytest.raises(ValueError, match=r"grasp\.mu"):
        Config().override(grasp={"mu": 0})


def test_readme_configuration_reference_is_current():
    readme = (DEFAULT_CONFIG_PATH.parents[1] / "README.md").read_text()
    assert config_reference_markdown() in readme
