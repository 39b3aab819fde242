"""The documentation's code runs: every code block of ``docs/`` and the README either runs here (on
a small dataset generated for real), is run by the test its marker names, or says why it is not run.

A block is marked by an HTML comment on the line before its fence, which the site does not show:
``<!-- not run: REASON -->`` or ``<!-- run by: tests/FILE.py::TEST -->``. The first ``bash`` block
of the commands page is walked line by line by ``tests/test_readme_commands.py``. The generated
parts of the pages (written into them by ``python docs/_ext/grip_docs.py``) are checked against
the code they are generated from.
"""

from __future__ import annotations

import re
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from classifiers.report.readme import BEGIN, END

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
COMMANDS_PAGE = DOCS / "reference" / "commands.md"
#: Fence languages that are code a reader may run; other fences (text, bibtex) are pictures and
#: output, and ``{directive}`` fences are MyST's.
CODE = ("python", "pycon", "bash", "sh", "shell", "console")
#: How a page's Python is made small here: (page, [(text, replaced by)]); each text must be there.
SMALL: dict[str, list[tuple[str, str]]] = {
    "docs/datasets.md": [("grips.head(5), trials=5", "grips.head(2), trials=1")],
}
_FENCE = re.compile(r"^(`{3,})\s*(\S*)")
_MARKER = re.compile(r"^<!-- (not run|run by): (.+?) -->$")


@dataclass(frozen=True)
class Block:
    """One fenced block of a page: where it starts, its language, its text and its marker."""

    page: str
    line: int
    language: str
    text: str
    marker: tuple[str, str] | None

    def __str__(self) -> str:
        return f"{self.page}:{self.line} ({self.language})"


def pages() -> list[Path]:
    """Every Markdown source of the site (not the build) and the README."""
    found = [path for path in DOCS.rglob("*.md") if "_build" not in path.relative_to(DOCS).parts]
    return [*sorted(found), ROOT / "README.md"]


def blocks(path: Path) -> list[Block]:
    """The fenced blocks of ``path`` with the marker on the line before each."""
    lines = path.read_text().splitlines()
    found, index = [], 0
    while index < len(lines):
        opening = _FENCE.match(lines[index])
        if not opening:
            index += 1
            continue
        fence, language = opening.groups()
        end = next(i for i in range(index + 1, len(lines)) if lines[i].startswith(fence))
        before = lines[index - 1].strip() if index else ""
        marker = _MARKER.match(before)
        found.append(Block(str(path.relative_to(ROOT)), index + 1, language,
                           "\n".join(lines[index + 1:end]) + "\n",
                           marker.groups() if marker else None))  # type: ignore[arg-type]
        index = end + 1
    return found


def walked_commands_block() -> Block:
    """The commands page's block that tests/test_readme_commands.py walks."""
    return next(block for block in blocks(COMMANDS_PAGE) if block.language == "bash")


def runnable(path: Path) -> list[Block]:
    """The Python blocks of ``path`` that run here (unmarked)."""
    return [block for block in blocks(path) if block.language == "python" and not block.marker]


def test_every_code_block_runs_or_says_why_not():
    walked = walked_commands_block()
    unaccounted = []
    for path in pages():
        for block in blocks(path):
            if block.language not in CODE or block == walked:
                continue
            if block.marker is None and block.language != "python":
                unaccounted.append(str(block))
            elif block.marker is not None and not block.marker[1].strip():
                unaccounted.append(f"{block}: a marker without its reason")
    assert not unaccounted, f"code blocks neither run nor marked: {unaccounted}"


def test_run_by_markers_name_existing_tests():
    for path in pages():
        for block in blocks(path):
            if block.marker and block.marker[0] == "run by":
                file, _, test = block.marker[1].partition("::")
                assert test and f"def {test}(" in (ROOT / file).read_text(), str(block)


def test_yaml_blocks_are_valid_configs(tmp_path):
    from grip_env.config import load_config

    checked = 0
    for path in pages():
        for block in blocks(path):
            if block.language == "yaml":
                config = tmp_path / "block.yaml"
                config.write_text(block.text)
                load_config(config)  # raises naming the bad key
                checked += 1
    assert checked


@pytest.mark.slow
@pytest.mark.parametrize(
    "page", [str(path.relative_to(ROOT)) for path in pages() if runnable(path)]
)
def test_python_blocks_run(page, generated_dataset_dir, tmp_path, monkeypatch, capsys):
    """A page's unmarked Python blocks, in order and in one namespace, in an empty folder, with the
    small generated dataset standing in for the standard one (unfinished while it is generated)."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr("grip_env.datasets.standard_path", lambda: generated_dataset_dir)
    namespace: dict[str, object] = {"__name__": "__main__"}
    for block in runnable(ROOT / page):
        code = block.text
        for old, new in SMALL.get(page, []):
            if old in code:
                code = code.replace(old, new)
        exec(compile(code, f"{page}:{block.line}", "exec"), namespace)
    for old, _ in SMALL.get(page, []):
        assert any(old in block.text for block in runnable(ROOT / page)), f"{page}: {old!r} gone"
    capsys.readouterr()


# ------------------------------------------------------------------ generated pages
def _grip_docs():
    sys.path.insert(0, str(DOCS / "_ext"))
    try:
        import grip_docs
    finally:
        sys.path.remove(str(DOCS / "_ext"))
    return grip_docs


def test_the_generated_parts_of_the_pages_are_written_in_and_current():
    """The configuration, CLI and environment pages read whole in the repository (no include of
    a file that exists only after a build), and what they hold is what the code writes now."""
    grip_docs = _grip_docs()
    for page in grip_docs.generators():
        text = (DOCS / page).read_text()
        body = text[text.index(grip_docs.BEGIN) + len(grip_docs.BEGIN):text.index(grip_docs.END)]
        assert len(body.strip().splitlines()) > 20, page
    missing = [f"{path.name}: {name}" for path in pages()
               for name in re.findall(r"```\{include\} (\S+)", path.read_text())
               if not (path.parent / name).is_file()]
    assert not missing, f"includes of files not in the repository: {missing}"
    assert grip_docs.stale_pages() == [], "rewrite them: python docs/_ext/grip_docs.py"


def test_a_stale_generated_part_is_found_and_rewritten(tmp_path, monkeypatch):
    grip_docs = _grip_docs()
    page = "reference/configuration.md"
    monkeypatch.setattr(grip_docs, "generators", lambda: {page: grip_docs.config_markdown})
    copy = tmp_path / page
    copy.parent.mkdir(parents=True)
    stale = (DOCS / page).read_text().replace("| `grasp.mu` | 0.4 |", "| `grasp.mu` | 0.5 |")
    copy.write_text(stale)
    assert grip_docs.stale_pages(tmp_path) == [page]
    assert grip_docs.write_generated(tmp_path) == [copy]
    assert copy.read_text() == (DOCS / page).read_text() and grip_docs.stale_pages(tmp_path) == []
    copy.write_text("# no markers\n")
    with pytest.raises(ValueError, match="lacks the markers"):
        grip_docs.stale_pages(tmp_path)


def test_the_cli_reference_is_every_command_as_its_help_shows_it():
    from grip_env.cli import _COMMAND_MODULES

    text = _grip_docs().cli_reference_markdown()
    for name in _COMMAND_MODULES:
        assert f"\n## grip-env {name}\n" in text, name
        assert f"Usage: grip-env {name} [OPTIONS]" in text, name
    assert "| `-d, --data <path>` |" in text and "{classifiers}" not in text


@pytest.mark.parametrize("env_id", ["GripSelect-v0", "GripAccept-v0"])
def test_environment_pages_have_gymnasiums_sections_from_a_live_env(env_id):
    grip_docs = _grip_docs()
    text = grip_docs.env_page_markdown(env_id)
    for title in (*grip_docs.ENV_SECTIONS, "Info keys", "Example"):
        assert f"\n## {title}\n" in text, title
    import gymnasium

    env = gymnasium.make(env_id)
    assert f"| Action Space | `{env.action_space}` |" in text
    assert f"| Observation Space | `{env.observation_space}` |" in text
    env.close()
    for key in ("object_id", "grip_id", "success", "is_success", "attempts"):
        assert f"| `{key}` |" in text
    assert ":meth:" not in text and ":class:" not in text  # RST roles made MyST's


def test_the_results_page_includes_the_readme_block_the_study_writes():
    page = (DOCS / "results.md").read_text()
    assert f':start-after: "{BEGIN}"' in page and f':end-before: "{END}"' in page
    readme = (ROOT / "README.md").read_text()
    assert readme.index(BEGIN) < readme.index(END)


def test_where_robustness_is_defined_g_is_said_once_to_be_gravity_not_grams():
    """The data card (written by grip_env.dataset.card), the concepts page and the column
    reference each say once what a level in g is."""
    from grip_env.dataset.card import GRAVITY_UNIT, dataset_card
    from grip_env.datasets import standard_path

    def said(text: str) -> int:
        return " ".join(text.split()).lower().count(GRAVITY_UNIT.lower())

    for page in ("concepts.md", "datasets.md", "dataset.md"):
        assert said((DOCS / page).read_text()) == 1, page
    assert said(dataset_card(standard_path())) == 1


def test_the_pages_say_what_the_main_job_learns_on():
    """``scripts/study.sh`` runs ``grip-env study`` with neither --data nor --regenerate: it
    learns on the shipped standard dataset (and --quick alone generates a tiny one), which is
    what the quick start and the learning page say, not that it generates a dataset."""
    from grip_env.cli.study import study_data
    from grip_env.datasets import standard_path

    script = (ROOT / "scripts" / "study.sh").read_text()
    assert "grip-env study" in script and "--data" not in script and "--regenerate" not in script
    assert study_data(None, regenerate=False, quick=False) == standard_path()
    assert study_data(None, regenerate=False, quick=True) is None  # None: generate one
    said = {"quickstart.md": "The first generates no dataset: it learns on the standard dataset "
                             "shipped with the package, after simulating a seeded sample",
            "learning.md": "learns on the shipped standard dataset after re-simulating a seeded "
                           "sample of it"}  # fmt: skip
    for page, sentence in said.items():
        text = " ".join((DOCS / page).read_text().split())
        assert sentence in text and "generates a labelled dataset" not in text, page
