"""Parts of the documentation that a program can write, written from the code they document.

Each page below holds its generated part inline, between :data:`BEGIN` and :data:`END`, so that
it reads whole as Markdown in the repository; ``python docs/_ext/grip_docs.py`` rewrites those
parts from the code (:func:`write_generated`), and the site's build (a warning: an error under
``-W``) and the tests refuse a page whose part is stale (:func:`stale_pages`):

- ``reference/configuration.md``: the configuration reference,
  :func:`grip_env.config.config_reference_markdown`;
- ``reference/cli.md``: every ``grip-env`` command, its usage, help text and options, read from the
  Typer command tree (:func:`cli_reference_markdown`);
- ``environments/<name>.md``: one page body per registered environment in Gymnasium's form: a
  summary table and spaces from a live ``gymnasium.make(id)``, the sections of the class docstring,
  the ``info`` keys of a live episode and the arguments of ``make`` from the constructor's
  signature (:func:`env_page_markdown`).

The module also turns the ``## Section`` headings of the environments' docstrings into rubrics
for autodoc (:func:`markdown_headings_as_rubrics`), so the API reference shows them as headings.
"""

from __future__ import annotations

import inspect
import re
import sys
from collections.abc import Callable
from functools import partial
from importlib import import_module
from pathlib import Path
from typing import Any

BEGIN = ("<!-- generated:begin (written from the code by `python docs/_ext/grip_docs.py`; "
         "do not edit) -->")
END = "<!-- generated:end -->"
DOCS = Path(__file__).resolve().parents[1]
#: The order of a Gymnasium environment page; the docstring must hold each of these sections.
ENV_SECTIONS = ("Description", "Action Space", "Observation Space", "Rewards", "Starting State",
                "Episode End", "Arguments", "Version History")
#: The test that runs the environments' docstring examples (the pages' Example blocks).
_DOCTEST = "tests/test_envs.py::test_docstrings_have_gymnasiums_sections_and_a_running_example"
_ROLE = re.compile(r":(meth|class|func|data|attr|mod):`(~?)([^`]+)`")


# ------------------------------------------------------------------ configuration
def config_markdown() -> str:
    """The configuration reference table of :mod:`grip_env.config`."""
    from grip_env.config import config_reference_markdown

    return config_reference_markdown() + "\n"


# ------------------------------------------------------------------ command line
def cli_reference_markdown() -> str:
    """Every ``grip-env`` command as Markdown: usage, help and its options as ``--help`` shows them.

    Each option's line is the command's own help record (the text ``--help`` prints, with its
    default, range and ``[required]``), so this page and ``--help`` cannot differ.
    """
    import typer

    from grip_env.cli import _register_commands, app
    from grip_env.cli.helptext import fill_learner_names, learner_names

    _register_commands()
    group = typer.main.get_command(app)
    root = group.context_class(group, info_name="grip-env")
    lines = _command_lines(group, root)
    for name in group.list_commands(root):
        command = group.get_command(root, name)
        context = command.context_class(command, info_name=name, parent=root)
        lines += ["", f"## grip-env {name}", "", *_command_lines(command, context)]
    names = learner_names()
    return "\n".join(fill_learner_names(line, names) or "" for line in lines) + "\n"


def _command_lines(command: Any, context: Any) -> list[str]:
    """One command's help text, usage line and table of arguments and options."""
    text = inspect.cleandoc((command.help or "").split("\f", 1)[0])
    rows = ["| argument or option | meaning |", "| --- | --- |"]
    for param in command.get_params(context):
        record = param.get_help_record(context)
        if record is not None:
            rows.append(f"| `{_cell(record[0])}` | {_cell(record[1])} |")
    epilog = [inspect.cleandoc(command.epilog), ""] if getattr(command, "epilog", None) else []
    return [text, "", "```text", command.get_usage(context), "```", "", *rows, "", *epilog]


def _cell(text: str) -> str:
    """``text`` on one line, safe inside a Markdown table cell."""
    return " ".join(text.split()).replace("|", "\\|")


# ------------------------------------------------------------------ environments
def env_page_markdown(env_id: str) -> str:
    """The body of ``env_id``'s page in Gymnasium's form, from a live environment and its class."""
    import gymnasium

    import grip_env  # noqa: F401  registers the ids
    from grip_env.envs.registration import ENV_IDS

    module_name, class_name = ENV_IDS[env_id].split(":")
    env_class = getattr(import_module(module_name), class_name)
    sections = docstring_sections(env_class)
    env = gymnasium.make(env_id)  # the defaults: live PyBullet on the default objects
    try:
        summary = [
            "| | |", "| --- | --- |",
            f"| Action Space | `{env.action_space}` |",
            f"| Observation Space | `{env.observation_space}` |",
            f"| import | `gymnasium.make(\"{env_id}\")` (after `import grip_env`) |",
            f"| class | {{class}}`~{module_name}.{class_name}` |",
        ]
    finally:
        env.close()
    qualified = f"{module_name}.{class_name}"
    lines = [*summary, "", sections.pop("", "").strip(), ""]
    for title in ENV_SECTIONS:
        lines += [f"## {title}", "", _myst_roles(sections[title], qualified), ""]
        if title == "Episode End":
            lines += ["## Info keys", "", *_info_table(env_id), ""]
        if title == "Arguments":
            lines += ["The arguments of `gymnasium.make` and their defaults, from the constructor:",
                      "", *_arguments_table(env_class), ""]
    if "Example" in sections:
        lines += ["## Example", "",
                  "The class docstring's example; the test suite runs it as a doctest "
                  "(`tests/test_envs.py`).", "", f"<!-- run by: {_DOCTEST} -->", "```pycon",
                  sections["Example"].strip(), "```", ""]
    return "\n".join(lines)


def docstring_sections(env_class: type) -> dict[str, str]:
    """The ``## Title`` sections of ``env_class``'s docstring (the text before them under "")."""
    text = inspect.getdoc(env_class) or ""
    parts = re.split(r"^## (.+)$", text, flags=re.M)
    sections = {"": parts[0]}
    sections.update({title.strip(): body.strip() for title, body in zip(parts[1::2], parts[2::2],
                                                                        strict=True)})
    missing = [title for title in ENV_SECTIONS if title not in sections]
    if missing:
        raise ValueError(f"{env_class.__name__}'s docstring lacks the sections {missing}")
    return sections


def _myst_roles(text: str, qualified: str) -> str:
    """``:meth:`name``` roles as MyST's ``{meth}`name```, bare names qualified by the class."""
    def replace(match: re.Match[str]) -> str:
        role, tilde, target = match.groups()
        if "." not in target and role in ("meth", "attr"):
            target, tilde = f"{qualified}.{target}", "~"
        return f"{{py:{role}}}`{tilde}{target}`"

    return _ROLE.sub(replace, text)


def _info_table(env_id: str) -> list[str]:
    """The keys of ``reset``'s and ``step``'s ``info`` in one live episode, with their types (a
    key that is None live is typed from a replayed episode too)."""
    import gymnasium

    from classifiers.evaluation.synthetic import synthetic_grips

    live = _first_step_infos(gymnasium.make(env_id, objects=["rectangle"], max_candidates=8))
    replay = _first_step_infos(gymnasium.make(env_id, data=synthetic_grips(n_objects=4, seed=0),
                                              max_candidates=8))
    rows = ["Measured on one live episode (`objects=[\"rectangle\"]`) when this page was written:",
            "",
            "| key | in `reset` | in `step` | type |", "| --- | --- | --- | --- |"]
    reset_info, step_info = live
    for key in dict.fromkeys([*reset_info, *step_info]):
        value = step_info.get(key, reset_info.get(key))
        kind = f"`{type(value).__name__}`"
        if value is None:
            kind = f"`None` live, `{type(replay[1][key]).__name__}` replayed"
        rows.append(f"| `{key}` | {'yes' if key in reset_info else ''} | "
                    f"{'yes' if key in step_info else ''} | {kind} |")
    return rows


def _first_step_infos(env: Any) -> tuple[dict[str, Any], dict[str, Any]]:
    """The ``info`` of ``reset(seed=0)`` and of executing the first candidate, then close."""
    try:
        _, reset_info = env.reset(seed=0)
        *_, step_info = env.step(1)  # GripSelect: slot 1; GripAccept: execute
    finally:
        env.close()
    return reset_info, step_info


def _arguments_table(env_class: type) -> list[str]:
    """The keyword arguments of ``env_class`` with their defaults."""
    rows = ["| argument | default |", "| --- | --- |"]
    for name, parameter in inspect.signature(env_class.__init__).parameters.items():
        if name != "self":
            rows.append(f"| `{name}` | `{parameter.default!r}` |")
    return rows


# ------------------------------------------------------------------ the pages
def generators() -> dict[str, Callable[[], str]]:
    """Each page (its path under ``docs/``) with a generated part, and the function writing it."""
    from grip_env.envs.registration import ENV_IDS

    found: dict[str, Callable[[], str]] = {"reference/configuration.md": config_markdown,
                                           "reference/cli.md": cli_reference_markdown}
    for env_id in ENV_IDS:
        found[f"environments/{env_page_name(env_id)}.md"] = partial(env_page_markdown, env_id)
    return found


def env_page_name(env_id: str) -> str:
    """The page of an environment: ``GripSelect-v0`` is ``grip_select``."""
    return re.sub(r"(?<!^)(?=[A-Z])", "_", env_id.split("-")[0]).lower()


def with_generated(text: str, generated: str, page: str) -> str:
    """``text`` of ``page`` with the part between :data:`BEGIN` and :data:`END` replaced."""
    start, end = text.find(BEGIN), text.find(END)
    if start < 0 or end < start:
        raise ValueError(f"{page} lacks the markers of its generated part: {BEGIN} ... {END}")
    return f"{text[:start + len(BEGIN)]}\n{generated.rstrip()}\n{text[end:]}"


def _pages_as_generated(docs: Path) -> dict[Path, tuple[str, str]]:
    """Each page with a generated part: its text now and its text with the part written anew."""
    found = {}
    for page, generate in generators().items():
        path = docs / page
        text = path.read_text(encoding="utf-8")
        found[path] = (text, with_generated(text, generate(), page))
    return found


def stale_pages(docs: Path = DOCS) -> list[str]:
    """The pages whose generated part differs from what the code writes now."""
    return [str(path.relative_to(docs)) for path, (text, fresh) in _pages_as_generated(docs).items()
            if text != fresh]


def write_generated(docs: Path = DOCS) -> list[Path]:
    """Rewrite the generated part of each page whose part is stale; the pages rewritten."""
    written = []
    for path, (text, fresh) in _pages_as_generated(docs).items():
        if text != fresh:
            path.write_text(fresh, encoding="utf-8")
            written.append(path)
    return written


# ------------------------------------------------------------------ Sphinx
def markdown_headings_as_rubrics(app: Any, what: str, name: str, obj: Any, options: Any,
                                 lines: list[str]) -> None:
    """autodoc hook: a docstring's ``## Title`` lines become ``.. rubric:: Title``."""
    for index, line in enumerate(lines):
        if line.startswith("## "):
            lines[index] = f".. rubric:: {line[3:].strip()}"


def _on_builder_inited(app: Any) -> None:
    from sphinx.util import logging

    for page in stale_pages(Path(app.srcdir)):
        logging.getLogger(__name__).warning(
            f"{page}: its generated part is out of date with the code; rewrite it with "
            "python docs/_ext/grip_docs.py")


def setup(app: Any) -> dict[str, Any]:
    """Register the hooks with Sphinx."""
    app.connect("builder-inited", _on_builder_inited)
    app.connect("autodoc-process-docstring", markdown_headings_as_rubrics)
    return {"parallel_read_safe": True, "parallel_write_safe": True}


if __name__ == "__main__":  # python docs/_ext/grip_docs.py: rewrite the stale generated parts
    sys.path.insert(0, str(DOCS.parent))  # the checkout's grip_env and classifiers
    for rewritten in write_generated():
        print(f"wrote {rewritten.relative_to(DOCS.parent)}")
