"""Configuration: defaults, YAML loading, validation messages."""

from __future__ import annotations

import pytest
import yaml

from grip_env import GraspParams
from grip_env.config import (
    DEFAULT_CONFIG_PATH,
    MAX_CONTOUR_POINTS,
    Config,
    PerceptionConfig,
    check_contour_budget,
    config_reference_markdown,
    load_config,
)


def test_default_yaml_equals_the_code_defaults():
    assert load_config(DEFAULT_CONFIG_PATH) == Config()
    assert load_config().grasp == GraspParams()


def test_default_yaml_lists_every_field_with_its_code_default():
    """configs/default.yaml and Config() are one source: same sections, fields and values."""
    written = yaml.safe_load(DEFAULT_CONFIG_PATH.read_text())
    defaults = Config().model_dump(mode="json")
    assert list(written) == list(defaults)
    for section, fields in defaults.items():
        assert list(written[section]) == list(fields), section
        for name, value in fields.items():
            shown = written[section][name]
            assert shown == value, f"{section}.{name}: yaml {shown!r} != Config() {value!r}"


def test_load_config_without_a_path_reads_no_file(monkeypatch, tmp_path):
    monkeypatch.setattr("grip_env.config.DEFAULT_CONFIG_PATH", tmp_path / "gone.yaml")
    assert load_config() == Config()


BAD_SETTINGS = [
    ("uncertainty:\n  friction_range: [1.0e308, 1.0e309]\n", r"uncertainty\.friction_range"),
    ("uncertainty:\n  friction_range: [0.1, 3.5]\n", r"uncertainty\.friction_range\.1.*3\.5"),
    ("uncertainty:\n  friction_range: [1.0, 0.4]\n", r"friction_range must be \(low, high\)"),
    ("perception:\n  contour_spacing_mm: 1.0e-9\n", r"perception\.contour_spacing_mm.*1e-09"),
    ("sim:\n  timestep: 1.0e-9\n", r"sim\.timestep.*1e-09"),
    ("sim:\n  timestep: 0.5\n", r"sim\.timestep.*0\.5"),
    ("objects:\n  procedural_size_mm: [1.0e300, 1.0e301]\n", r"objects\.procedural_size_mm"),
    ("objects:\n  procedural_size_mm: [100.0, 60.0]\n", r"procedural_size_mm must be \(low"),
    ("dataset:\n  workers: 1000000000000\n", r"dataset\.workers.*1000000000000"),
    ("objects:\n  procedural_count: 99999999999999999999\n", r"objects\.procedural_count"),
    ("sim:\n  finger_force_n: .nan\n", r"sim\.finger_force_n"),
    ("learning:\n  seed: 4294967296\n", r"learning\.seed.*4294967296"),
    ("selector:\n  seed: 99999999999999999999\n", r"selector\.seed"),
    ("dataset:\n  trials: 0\n", r"dataset\.trials"),
]
#: Files that are no config at all; each is refused with a ValueError saying why.
BAD_FILES = [
    pytest.param("grasp:\n  mu: 0.5\n  muu: 3\n", r"grasp\.muu", id="unknown_key_is_named"),
    pytest.param("grasp: !!python/object/apply:os.system ['echo hi']\n", "not valid YAML",
                 id="unsafe_yaml_is_not_executed"),
    pytest.param("- 1\n- 2\n", "mapping", id="not_a_mapping"),
    pytest.param("grasp: " + "[" * 5000 + "]" * 5000 + "\n", "nested too deeply",
                 id="deeply_nested_yaml_not_a_recursion_error"),
    pytest.param("# padding\n" * 200_000, "larger than", id="huge_file"),
]


@pytest.mark.parametrize(("text", "message"), BAD_SETTINGS + BAD_FILES)
def test_a_bad_config_file_is_refused_naming_its_problem(tmp_path, text, message):
    """Settings out of their physical range are named with their value; files that are no
    config are refused saying why."""
    path = tmp_path / "c.yaml"
    path.write_text(text)
    with pytest.raises(ValueError, match=message):
        load_config(path)


def test_a_missing_config_file_is_refused(tmp_path):
    with pytest.raises(ValueError, match="not found"):
        load_config(tmp_path / "nope.yaml")


def test_contour_budget_bounds_vertices_size_and_sample_count():
    perception = PerceptionConfig()
    check_contour_budget("ok", 4, 400.0, 100.0, perception)
    with pytest.raises(ValueError, match="1000000 vertices"):
        check_contour_budget("many", 1_000_000, 400.0, 100.0, perception)
    with pytest.raises(ValueError, match=r"1e\+09 mm across"):
        check_contour_budget("huge", 4, 4e9, 1e9, perception)
    fine = PerceptionConfig(contour_spacing_mm=0.1)
    perimeter = 0.1 * (MAX_CONTOUR_POINTS + 10)
    with pytest.raises(ValueError, match=r"contour_spacing_mm 0\.1"):
        check_contour_budget("fine", 4, perimeter, 100.0, fine)


def test_grasp_params_defaults_are_the_papers():
    p = GraspParams()
    assert (p.mu, p.lam, p.weight, p.eta, p.rho_scale, p.feature_cap) == (
        0.4, 2.0, 1.0, 101.5, 10.0, 100.0,
    )


@pytest.mark.parametrize("field", ["mu", "lam", "weight", "eta", "rho_scale"])
def test_negative_parameters_are_refused(field):
    with pytest.raises(ValueError, match=field):
        GraspParams(**{field: -0.1})


def test_override_validates():
    cfg = Config().override(dataset={"trials": 6})
    assert cfg.dataset.trials == 6
    with pytest.raises(ValueError, match="unknown config section"):
        Config().override(nothing={"a": 1})
    with pytest.raises(ValueError, match=r"grasp\.mu"):
        Config().override(grasp={"mu": 0})


def test_the_configuration_reference_is_generated_with_every_key():
    """The documentation's configuration page holds the table generated from the fields, which
    names every key with its default and accepted values (tests/test_docs_examples.py keeps the
    page's copy current); the README keeps no copy."""
    root = DEFAULT_CONFIG_PATH.parents[1]
    page = (root / "docs" / "reference" / "configuration.md").read_text()
    table = config_reference_markdown()
    assert table.strip() in page
    assert "| `grasp.mu` |" not in (root / "README.md").read_text()
    for section, fields in Config().model_dump().items():
        for name in fields:
            assert f"| `{section}.{name}` |" in table, f"{section}.{name}"
    assert "| `grasp.mu` | 0.4 | number in (0, 2] |" in table
    assert "| `dataset.sampling` | stratified | `stratified`, `best`, `uniform` |" in table
    assert "| `learning.test_fraction` | 0.25 | number in (0, 1) |" in table


def test_check_setting_bounds_a_cli_override_like_its_config_key():
    from grip_env.config import check_setting

    assert check_setting("dataset", "workers", 3) == 3
    with pytest.raises(ValueError, match=r"^--workers: .*1024 \(got 1000000000000\)"):
        check_setting("dataset", "workers", 10**12, "--workers")
    with pytest.raises(ValueError, match=r"^--objects: .*\(got 99999999999999999999\)"):
        check_setting("objects", "procedural_count", 99999999999999999999, "--objects")
    with pytest.raises(ValueError, match=r"^selector\.timesteps"):
        check_setting("selector", "timesteps", 0)
    with pytest.raises(ValueError, match=r"unknown config key dataset\.nope"):
        check_setting("dataset", "nope", 1)


def test_a_misspelled_key_names_the_file_and_the_nearest_key(tmp_path):
    path = tmp_path / "mine.yaml"
    path.write_text("dataset:\n  trails: 3\n")
    with pytest.raises(ValueError, match=r"config .*mine\.yaml: .*dataset\.trails: unknown key; "
                                         r"did you mean dataset\.trials\?"):
        load_config(path)
    path.write_text("datset:\n  trials: 3\n")
    with pytest.raises(ValueError, match=r"datset: unknown key; did you mean dataset\?"):
        load_config(path)
    path.write_text("dataset:\n  zzz: 3\n")
    with pytest.raises(ValueError, match=r"dataset\.zzz: unknown key$"):
        load_config(path)
