"""How every ``grip-env`` command shows its help, in one place.

Typer's own rendering shows a required argument as ``{obj}`` (its parameter name, in braces) and a
flag as taking a ``<bool>``. Here instead:

- an argument is named as its command's text names it: its ``metavar`` (``OBJECT``) or else its
  parameter name in capitals (``DIRECTORY``), ``[NAME]`` when optional, ``NAME...`` when repeated;
- a flag (``--quick``, ``--progress/--no-progress``, ``--help``) shows no value type;
- :class:`LearnerHelp` fills ``{classifiers}``, ``{regressors}`` and ``{rankers}`` in a command's
  help with the names of the learning package's registries, read only when the help is shown
  (registering the commands loads no learning code).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from typer.core import TyperArgument, TyperCommand, TyperGroup, TyperOption


def _as_documented(params: Sequence[Any]) -> list[Any]:
    """``params`` with each argument named in capitals and each flag without a value type."""
    for param in params:
        if isinstance(param, TyperArgument) and param.metavar is None:
            param.metavar = (param.name or "").upper()
        elif isinstance(param, TyperOption) and param.is_flag and param.metavar is None:
            param.metavar = ""  # typer's help shows the metavar in place of "<bool>"
    return list(params)


def usage_name(argument: TyperArgument) -> str:
    """An argument as the usage line shows it: ``OBJECT``, ``[OBJECT]`` or ``METHODS...``."""
    name = argument.metavar or (argument.name or "").upper()
    if argument.nargs != 1:
        name += "..."
    return name if argument.required else f"[{name}]"


class Command(TyperCommand):
    """A ``grip-env`` subcommand: arguments named as its text names them, flags as flags."""

    def get_params(self, ctx: Any) -> list[Any]:
        return _as_documented(super().get_params(ctx))

    def collect_usage_pieces(self, ctx: Any) -> list[str]:
        pieces = [self.options_metavar] if self.options_metavar else []
        return pieces + [usage_name(param) for param in self.get_params(ctx)
                         if isinstance(param, TyperArgument)]


class Group(TyperGroup):
    """The ``grip-env`` command group: its flags (``--version``, ``--help``) shown as flags."""

    def get_params(self, ctx: Any) -> list[Any]:
        return _as_documented(super().get_params(ctx))


def learner_names() -> dict[str, str]:
    """``{classifiers}``, ``{regressors}``, ``{rankers}``: each registry's names, in a line."""
    from classifiers.learners.models import MODEL_NAMES, REGRESSOR_NAMES
    from classifiers.learners.ranking import RANKER_NAMES

    return {"{classifiers}": ", ".join(MODEL_NAMES), "{regressors}": ", ".join(REGRESSOR_NAMES),
            "{rankers}": ", ".join(RANKER_NAMES)}


def fill_learner_names(text: str | None, names: dict[str, str]) -> str | None:
    """``text`` with each placeholder of :func:`learner_names` replaced."""
    for placeholder, value in names.items():
        text = text.replace(placeholder, value) if text else text
    return text


class LearnerHelp(Command):
    """A command whose help names the learners of the registries (see the module docstring)."""

    def format_help(self, ctx: Any, formatter: Any) -> None:
        names = learner_names()
        self.help = fill_learner_names(self.help, names)
        for param in self.params:
            if hasattr(param, "help"):
                param.help = fill_learner_names(param.help, names)
        super().format_help(ctx, formatter)
