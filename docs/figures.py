"""Regenerates the documentation's figures from the package (``make figures``).

    python docs/figures.py                       # the map and flight figures (about a minute)
    python docs/figures.py --storm-run runs/storms   # and the storm network's, from a run
                                                     # evaluated on storms 1000000-1000049

Each figure is made by the command a user would type, then stamped with that command, the date
and the machine (CPU model and cores) before it lands in ``docs/figures``.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FIGURES = ROOT / "docs" / "figures"
sys.path.insert(0, str(ROOT / "docs" / "tutorials"))
from radiomap_in_rain import made_by  # noqa: E402  (the stamp the tutorials use)


def stamp(src: Path, dst: Path, command: str) -> None:
    """Copies the PNG ``src`` to ``dst`` with a line under it: command, date, machine."""
    import matplotlib.image as mpimg
    from matplotlib.figure import Figure

    img = mpimg.imread(src)
    h, w = img.shape[:2]
    lines = textwrap.wrap(made_by(command), width=max(40, w // 5))
    foot = 14 * len(lines) + 6
    dpi = 100
    fig = Figure(figsize=(w / dpi, (h + foot) / dpi), dpi=dpi)
    ax = fig.add_axes((0, foot / (h + foot), 1, h / (h + foot)))
    ax.imshow(img)
    ax.set_axis_off()
    fig.text(0.005, 3 / (h + foot), "\n".join(lines), fontsize=7, color="0.4", va="bottom")
    fig.savefig(dst, dpi=dpi)


def run(args: list[str]) -> str:
    """Runs a command from the repository's root and returns it as typed."""
    subprocess.run([sys.executable, *args], check=True, cwd=ROOT)
    return "python " + " ".join(args)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--storm-run", type=Path, default=None,
                    help="a run of python -m rainuav.train --preset storms, "
                    "evaluated with --storm-seeds 1000000-1000049")  # fmt: skip
    args = ap.parse_args()
    FIGURES.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        flight = Path(tmp) / "flight"
        cmd = run(["-m", "rainuav.fly", "--sites", "examples/sites.csv", "--start",
                   "47.3660,8.5380", "--goal", "47.3800,8.5560", "--weather",
                   "examples/radar.nc", "--out", str(flight)])  # fmt: skip
        stamp(flight / "flight.png", FIGURES / "fly_example.png", cmd.replace(str(flight), "OUT"))
    # Each stamps its own figure; by default they write outside docs/ (figures/).
    run(["docs/tutorials/radiomap_in_rain.py", "--out", str(FIGURES)])
    run(["docs/terrain_example.py", "--out", str(FIGURES / "terrain_flight.png")])
    run(["docs/buildings_example.py", "--out", str(FIGURES / "buildings.png")])
    if args.storm_run is None:
        print("not regenerated (give --storm-run RUN): storm_network_1000000.png, "
              "storm_network_worst.png")  # fmt: skip
        return
    ev = args.storm_run / "eval_storms_1000000-1000049"
    stamp(ev / "evaluation_storm_flights.png", FIGURES / "storm_network_1000000.png",
          "python -m rainuav.evaluate RUN --storm-seeds 1000000-1000049")  # fmt: skip
    cmd = run(["experiments/worst_flights.py", str(args.storm_run), str(ev)])
    # The run's folder is the user's own: the stamp names it RUN.
    cmd = cmd.replace(str(ev), "RUN/eval_storms_1000000-1000049").replace(
        str(args.storm_run), "RUN"
    )
    stamp(ev / "worst_flights.png", FIGURES / "storm_network_worst.png", cmd)


if __name__ == "__main__":
    main()
