"""A trained storm network flown by ``python -m rainuav.fly --policy`` on the shipped example
place, against the exact plan the command makes by default: arrival share and
excess cost over it, for seeded (start, destination) pairs the network has never seen.

    python experiments/fly_policy.py RUN [--pairs 20] [--seed 0]

The place: ``examples/sites.csv`` around Zurich, the area fixed to the box below, at the
flight altitude of 100 m, 28 GHz. Three weathers: clear air, 25 mm/h, and the moving radar
cell of ``examples/radar.nc`` (13 scans, maps every 5 s, the plan in space-time). Each pair:
start and destination uniform in the box shrunk by 150 m, at least 500 m apart. The network
(``RUN``, trained with ``--observation weather``, best with ``--random-goal true``) was trained
on synthetic 2 km storms only: the place's area, sites and rain are new to it.
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np
from rainuav.errors import InvalidInputError
from rainuav.fly import _policy
from rainuav.fly.plan import fly_place
from rainuav.world.place import place_scenario

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
BOX = (47.3590, 8.5290, 47.3830, 8.5600)
"""The area, (south, west, north, east) degrees: the example's sites with room around them."""
INSET_DEG = (0.00135, 0.0020)
"""The pairs keep about 150 m from the box's edges (latitude, longitude degrees)."""


def pairs(n: int, seed: int) -> list[tuple[tuple[float, float], tuple[float, float]]]:
    rng = np.random.default_rng(seed)
    s, w, nn, e = BOX
    out: list[tuple[tuple[float, float], tuple[float, float]]] = []
    while len(out) < n:
        a = (rng.uniform(s + INSET_DEG[0], nn - INSET_DEG[0]),
             rng.uniform(w + INSET_DEG[1], e - INSET_DEG[1]))  # fmt: skip
        b = (rng.uniform(s + INSET_DEG[0], nn - INSET_DEG[0]),
             rng.uniform(w + INSET_DEG[1], e - INSET_DEG[1]))  # fmt: skip
        dy = (a[0] - b[0]) * 111_200.0
        dx = (a[1] - b[1]) * 75_400.0
        if np.hypot(dx, dy) >= 500.0:
            out.append((a, b))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", type=Path)
    ap.add_argument("--pairs", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    flyer, by = _policy(args.run)
    weathers = {"clear": {"rain_rate_mm_h": 0.0}, "25 mm/h": {"rain_rate_mm_h": 25.0},
                "radar cell": {"weather": EXAMPLES / "radar.nc"}}  # fmt: skip
    report = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, kw in weathers.items():
            excess, arrived, straight = [], 0, []
            for k, (a, b) in enumerate(pairs(args.pairs, args.seed)):
                place = place_scenario(EXAMPLES / "sites.csv", a, b, box=BOX, **kw)  # type: ignore[arg-type]
                out = Path(tmp) / f"{k}"
                try:
                    s = fly_place(place, out, flyer=flyer, flown_by=by)  # type: ignore[arg-type]
                except InvalidInputError as err:
                    print(f"{name} pair {k}: {err}")
                    continue
                arrived += 1
                excess.append(s["excess_over_optimum"])
                opt = s["optimal_cost"]
                straight.append((s["straight_line_cost"] - opt) / opt)
            report[name] = {
                "pairs": args.pairs,
                "arrived": arrived,
                "mean_excess_over_optimum": float(np.mean(excess)) if excess else None,
                "worst_excess_over_optimum": float(np.max(excess)) if excess else None,
                "straight_line_mean_excess": float(np.mean(straight)) if straight else None,
            }
            print(name, json.dumps(report[name]), flush=True)
    print(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
