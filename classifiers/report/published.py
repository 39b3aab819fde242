"""The study's figures as the README and the docs show them, with a stamp naming their run.

``grip-env study --update-readme`` copies the answer figures and the gallery from the study's
``figures/`` folder into :data:`RESULTS_FOLDER` beside the README (committed, so GitHub and the
Sphinx build show them) and writes :data:`STAMP_FILE` there: the run's commit and dataset
sha256, which the README's results block states too, and each figure's sha256. A rerun replaces
them all together; a test checks that the README's text, figures and stamp are one run's.
"""

from __future__ import annotations

import hashlib
import json
import shutil
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from classifiers.report.answer_figures import ALT_TEXT

#: Where the published figures live, relative to the README's folder (a POSIX path: the README
#: and ``docs/results.md``, which includes its block, link to it as written).
RESULTS_FOLDER = "docs/_static/results"
STAMP_FILE = "run.json"
GALLERY = "gallery.png"
#: Alt text of every published figure, in the order the README shows them.
PUBLISHED_ALT: dict[str, str] = {
    **ALT_TEXT,
    GALLERY: "Drawn shapes and pybullet_data meshes of the study's dataset, each with its best "
             "(solid) and worst (faint) grip by Q_C and how often they held",
}


def publish(out: Path, folder: Path, commit: str, dataset_sha256: str) -> dict[str, Any]:
    """Copy the published figures the study in ``out`` drew (``out/figures``) into ``folder``,
    remove the ones an earlier stamp listed that this run did not draw, and write the stamp;
    returns it."""
    folder.mkdir(parents=True, exist_ok=True)
    earlier = read_stamp(folder).get("figures", {}) if (folder / STAMP_FILE).is_file() else {}
    figures = {}
    for name in PUBLISHED_ALT:
        source = Path(out) / "figures" / name
        if source.is_file():
            shutil.copyfile(source, folder / name)
            figures[name] = file_sha256(folder / name)
    for name in set(earlier) - set(figures):
        (folder / name).unlink(missing_ok=True)
    stamp = {"study": str(out), "commit": commit, "dataset_sha256": dataset_sha256,
             "written": datetime.now(UTC).isoformat(timespec="seconds"), "figures": figures}
    (folder / STAMP_FILE).write_text(json.dumps(stamp, indent=2) + "\n")
    return stamp


def read_stamp(folder: Path) -> dict[str, Any]:
    """The stamp of the published figures in ``folder``.

    Raises:
        ValueError: ``folder`` has no stamp (no study was published there).
    """
    path = Path(folder) / STAMP_FILE
    if not path.is_file():
        raise ValueError(f"{path} is missing: run grip-env study --update-readme")
    return json.loads(path.read_text())


def figure_markdown(name: str, prefix: str = RESULTS_FOLDER) -> str:
    """The Markdown image of the published figure ``name`` with its alt text."""
    return f"![{PUBLISHED_ALT[name]}]({prefix}/{name})"


def file_sha256(path: Path) -> str:
    """SHA-256 of a file's bytes."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()
