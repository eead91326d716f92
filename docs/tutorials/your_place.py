"""Plan a flight at your place: every input a user has (sites, a DEM, building footprints, a
radar file) to a mission an autopilot loads, on the shipped examples.

    python docs/tutorials/your_place.py [--out OUT]

Runs ``python -m rainuav.fly`` with all four inputs (``examples/``: three tri-sector sites in
Zurich, a DEM with a ridge, about 660 footprints, 13 radar scans of a convective cell), 60 m
above the ground, the ray engine. Writes into ``--out`` (default ``runs/your_place``;
``docs/gallery.py``, the documentation build, gives ``docs/gallery``) ``your_place/``
(everything ``fly`` writes), ``your_place.png`` (its figure) and ``your_place.md`` (the table
the page "Plan a flight at your place" shows: each figure read from ``summary.json``, and the
wall time of the command).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"

COMMAND = [
    "--sites", "examples/sites.csv",
    "--start", "47.3660,8.5380", "--goal", "47.3800,8.5560",
    "--terrain", "examples/dem.tif",
    "--footprints", "examples/buildings.geojson",
    "--weather", "examples/radar.nc",
    "--altitude-m", "60", "--engine", "ray",
]  # fmt: skip
"""The command of the page, its paths relative to the clone's root."""


def table(summary: dict, wall_s: float, machine: str) -> str:
    """The page's table of what the run gave, from its ``summary.json``."""
    chance = summary["outage_chance"]
    rows = [
        ("the run", machine),
        ("wall time of the command (an empty map cache)", f"{wall_s:.0f} s"),
        ("flown by", summary["flown_by"]),
        ("flight time", f"{summary['flight_time_s']:.0f} s"),
        ("waypoints in the mission", f"{summary['waypoints']}"),
        ("moves below the SINR threshold (outage share)", f"{100 * summary['outage_share']:.1f}%"),
        ("the outage share expected from the map's spreads (independent / correlated spread)",
         f"{100 * chance['expected_outage_share']:.1f}% "
         f"(± {100 * chance['spread_independent']:.1f} / {100 * chance['spread_correlated']:.1f})"),
        ("cost over the exact optimum", f"{100 * summary['excess_over_optimum']:.1f}%"),
        ("the straight line's cost over the exact optimum",
         f"{100 * summary['excess_of_straight_line']:.1f}%"),
    ]  # fmt: skip
    lines = ["| what | this run |", "|---|---|", *[f"| {k} | {v} |" for k, v in rows]]
    return "\n".join(lines) + "\n"


def stamped(png: Path, out: Path, line: str) -> None:
    """``png`` (fly's figure) with ``line`` (the command, the date, the machine) under it."""
    import textwrap

    from matplotlib.figure import Figure
    from matplotlib.image import imread

    img = imread(png)
    h, w = img.shape[:2]
    text = textwrap.wrap(line, width=int(w / 4.2))  # about 4.2 px a character at 6 points
    strip = 0.12 * len(text) + 0.05  # inches
    fig = Figure(figsize=(w / 100, h / 100 + strip), dpi=100)
    ax = fig.add_axes((0.0, strip / (h / 100 + strip), 1.0, 1.0 - strip / (h / 100 + strip)))
    ax.imshow(img)
    ax.set_axis_off()
    fig.text(0.01, 0.005, "\n".join(text), fontsize=6, color="0.45", va="bottom")
    fig.savefig(out)


def main(argv: list[str]) -> int:
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from radiomap_in_rain import made_by  # the stamp every published figure carries

    # The wall time is the command's from scratch: a map cache of its own, empty.
    os.environ["RAINUAV_CACHE_DIR"] = tempfile.mkdtemp(prefix="rainuav-your-place-")
    from rainuav.fly import main as fly

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("runs") / "your_place")
    out = ap.parse_args(argv).out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    flight = out / "your_place"
    shutil.rmtree(flight, ignore_errors=True)
    t0 = time.perf_counter()
    args = [str(ROOT / a) if a.startswith("examples/") else a for a in COMMAND]
    with contextlib.redirect_stdout(io.StringIO()):  # the summary fly prints: in the table
        code = fly([*args, "--out", str(flight)])
    wall = time.perf_counter() - t0
    if code != 0:
        return code
    summary = json.loads((flight / "summary.json").read_text())
    line = made_by("python -m rainuav.fly " + " ".join(COMMAND))
    stamped(flight / "flight.png", out / "your_place.png", line)
    (out / "your_place.md").write_text(table(summary, wall, line.split("; ", 1)[1]))
    shutil.rmtree(os.environ["RAINUAV_CACHE_DIR"], ignore_errors=True)
    print(f"your_place: {wall:.1f} s, {summary['waypoints']} waypoints -> {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
