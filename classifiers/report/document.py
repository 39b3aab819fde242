"""A small report document: headings, text, tables, code and figures, as Markdown and HTML.

The Markdown is the source; the HTML page is that Markdown rendered by markdown-it-py
(CommonMark plus tables, raw HTML disabled), so inline markup such as ``**bold**`` renders in
both and nothing in a cell or caption can inject markup.
"""

from __future__ import annotations

import html
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd
from markdown_it import MarkdownIt


@dataclass(frozen=True)
class _Block:
    kind: str  # "heading", "text", "table", "figure", "code"
    content: object
    level: int = 2
    caption: str = ""


@dataclass
class Report:
    """An ordered list of blocks; figures are PNG paths relative to the report's folder."""

    title: str
    blocks: list[_Block] = field(default_factory=list)

    def heading(self, text: str, level: int = 2) -> None:
        """A section heading (level 2) or sub-heading (3)."""
        self.blocks.append(_Block("heading", text, level))

    def text(self, paragraph: str) -> None:
        """A paragraph; Markdown inline markup is kept as is in Markdown, escaped in HTML."""
        self.blocks.append(_Block("text", paragraph))

    def table(self, frame: pd.DataFrame, caption: str = "", float_format: str = "{:.4g}") -> None:
        """A table from a DataFrame (its index is shown when it is named or not a RangeIndex)."""
        shown = frame if isinstance(frame.index, pd.RangeIndex) else frame.reset_index()
        formatted = shown.map(lambda v: float_format.format(v) if isinstance(v, float) else str(v))
        self.blocks.append(_Block("table", formatted, caption=caption))

    def figure(self, path: str, caption: str) -> None:
        """A PNG figure beside the report."""
        self.blocks.append(_Block("figure", path, caption=caption))

    def code(self, text: str, language: str = "") -> None:
        """A fenced code block (a config, a command), shown verbatim."""
        self.blocks.append(_Block("code", text, caption=language))

    # ------------------------------------------------------------------ writers
    def to_markdown(self) -> str:
        """The report as Markdown."""
        lines = [f"# {self.title}", ""]
        for block in self.blocks:
            lines += _MARKDOWN[block.kind](block)
            lines.append("")
        return "\n".join(lines)

    def to_html(self) -> str:
        """The report as a standalone HTML page (its Markdown rendered by markdown-it-py)."""
        body = _RENDERER.render(self.to_markdown())
        return (
            "<!doctype html><html><head><meta charset='utf-8'>"
            f"<title>{html.escape(self.title)}</title><style>{_CSS}</style></head>"
            f"<body>\n{body}\n</body></html>\n"
        )

    def write(self, folder: str | Path, stem: str = "report") -> tuple[Path, Path]:
        """Write ``report.md`` and ``report.html`` into ``folder``."""
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        md, page = folder / f"{stem}.md", folder / f"{stem}.html"
        md.write_text(self.to_markdown())
        page.write_text(self.to_html())
        return md, page


def frame_of_intervals(results: dict[str, dict[str, Any]], metrics: list[str]) -> pd.DataFrame:
    """``{name: {metric: {"mean", "ci"}}}`` as a table of ``mean [lo, hi]`` strings."""
    rows = {
        name: {m: _interval_text(values[m]) for m in metrics if m in values}
        for name, values in results.items()
    }
    return pd.DataFrame(rows).T.rename_axis("name")


def _interval_text(value: dict[str, Any]) -> str:
    low, high = value["ci"]
    if value["mean"] is None:
        return "n/a"
    if low is None or high is None:
        return _short(value["mean"])
    return f"{_short(value['mean'])} [{_short(low)}, {_short(high)}]"


def _short(number: float) -> str:
    """Three decimals, or three significant digits beyond ±10 000 (a diverging fit's R²)."""
    return f"{number:.3f}" if abs(number) < 1e4 else f"{number:.3g}"


def _md_table(block: _Block) -> list[str]:
    frame: pd.DataFrame = block.content  # type: ignore[assignment]
    header = "| " + " | ".join(_cell(c) for c in frame.columns) + " |"
    rule = "|" + "|".join(" --- " for _ in frame.columns) + "|"
    rows = ["| " + " | ".join(_cell(v) for v in row) + " |"
            for row in frame.astype(str).to_numpy().tolist()]  # fmt: skip
    caption = [f"*{block.caption}*", ""] if block.caption else []
    return [*caption, header, rule, *rows]


def _cell(value: object) -> str:
    return str(value).replace("|", "\\|").replace("\n", " ")


def _md_code(block: _Block) -> list[str]:
    fence = "````" if "```" in str(block.content) else "```"
    return [f"{fence}{block.caption}", str(block.content).rstrip("\n"), fence]


_MARKDOWN = {
    "heading": lambda b: [f"{'#' * b.level} {b.content}"],
    "text": lambda b: [str(b.content)],
    "table": _md_table,
    "figure": lambda b: [f"![{b.caption}]({b.content})", "", f"*{b.caption}*"],
    "code": _md_code,
}

_RENDERER = MarkdownIt("commonmark", {"html": False}).enable("table")

_CSS = (
    "body{font-family:sans-serif;max-width:1000px;margin:2em auto;line-height:1.45}"
    "table{border-collapse:collapse;margin:1em 0;font-size:0.9em}"
    "td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}"
    "caption{font-style:italic;text-align:left}img{max-width:100%}"
    "figcaption{font-style:italic;color:#444}"
)
