"""Tutorial: train, evaluate and fly a policy.

    python docs/tutorials/train_evaluate_fly.py --out runs/tutorial            # the full budget
    python docs/tutorials/train_evaluate_fly.py --out /tmp/tutorial --small   # a quick check

Three commands, as a user types them: train one network over the distribution of moving
storms (it reads the weather around it and over the area, never the storm's future), fly it
through storms it never saw against each storm's exact space-time optimum, and fly it at a
real place through a radar file, written as missions an autopilot loads. ``--small`` runs the
same commands on a tiny budget (a few episodes, one storm, few starts) to check they finish;
its figures mean nothing. Needs the ``geo`` and ``weather`` extras
(``pip install '.[geo,weather]'``).
"""

from __future__ import annotations

import argparse
import json
import shlex
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def run(args: list[str]) -> None:
    """Runs ``python -m rainuav.<tool> ...`` as typed in a shell, and stops on failure."""
    print("$ python -m " + " ".join(shlex.quote(str(a)) for a in args), flush=True)
    subprocess.run([sys.executable, "-m", *map(str, args)], check=True, cwd=ROOT)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "runs" / "tutorial")
    ap.add_argument(
        "--small", action="store_true", help="a tiny budget and the ray engine, to check it runs"
    )
    args = ap.parse_args()
    out = args.out.resolve()
    storms = out / "storms"

    # --8<-- [start:steps]
    # 1. Train one network over the storm distribution (the default command: about 25-60 min
    #    on 2 cores; it resumes with --resume if stopped).
    small_train = [
        "--dqn.episodes",
        "8",
        "--storm-pool",
        "1",
        "--eval-starts",
        "4",
        "--validate-starts",
        "4",
        "--engine",
        "ray",
    ]
    run(["rainuav.train", "--preset", "storms", "--out", storms,
         *(small_train if args.small else [])])  # fmt: skip

    # 2. Fly it through held-out storms (seeds from 1 000 000 are never trained on), 20 starts
    #    each, against the exact optimum, the straight line and a plan made at take-off.
    seeds, starts = ("1000000-1000000", "2") if args.small else ("1000000-1000009", "20")
    run(["rainuav.evaluate", storms, "--storm-seeds", seeds, "--starts", starts])
    result = json.loads((storms / f"eval_storms_{seeds}" / "evaluation.json").read_text())
    print(json.dumps(result["mean"], indent=2))

    # 3. Fly it at a real place: three sites in Zurich and a radar file of a convective cell
    #    crossing the area (shipped examples), written as missions and a figure.
    run(["rainuav.fly", "--sites", ROOT / "examples" / "sites.csv",
         "--start", "47.3660,8.5380", "--goal", "47.3800,8.5560",
         "--weather", ROOT / "examples" / "radar.nc", "--policy", storms,
         "--out", out / "flight", *(["--engine", "ray"] if args.small else [])])  # fmt: skip
    summary = json.loads((out / "flight" / "summary.json").read_text())
    print({k: summary[k] for k in ("flown_by", "excess_over_optimum", "outage_share",
                                   "flight_time_s", "waypoints")})  # fmt: skip

    # --8<-- [end:steps]


if __name__ == "__main__":
    main()
