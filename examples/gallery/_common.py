"""What the gallery's examples share: their ``--out`` folder (``gallery/`` under the current
folder unless given: an example never writes into ``docs/``) and the stamp under each figure
(the command, the date and the machine: the tutorials' ``made_by``)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "docs" / "tutorials"))
from radiomap_in_rain import made_by  # the stamp every published figure carries


def out_dir(doc: str | None, argv: list[str] | None = None) -> Path:
    """The ``--out`` folder of an example (made if missing)."""
    ap = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--out", type=Path, default=Path("gallery"), help="output folder")
    out = ap.parse_args(argv).out
    out.mkdir(parents=True, exist_ok=True)
    return out


def stamp(fig, script: str) -> None:
    """Writes the command, today's date and the machine under ``fig``."""
    engine = fig.get_layout_engine()
    if engine is not None:  # room for the line below the axes
        engine.set(rect=(0.0, 0.035, 1.0, 0.965))
    text = made_by(f"python examples/gallery/{script}")
    fig.text(0.01, 0.005, text, fontsize=6, color="0.45", va="bottom")
