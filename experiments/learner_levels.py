"""The single-map learner with altitude as a decision: default runs among levels on several
seeds, each evaluated on the network alone from the run's 200 fixed evaluation starts against
the exact plan among levels, beside the plans of one altitude, tabulated.

    python experiments/learner_levels.py --seeds 0 1 2 --out runs/levels

Each run is ``python -m rainuav.train --scenario uma --freq-ghz 28 --rain-rate-mm-h 0 --altitudes-m
25:115:15 --seed K`` (the defaults otherwise; ``--altitudes-m``, ``--scenario``... given here
replace them) in ``OUT/sK``; a run whose ``metrics.json`` exists is not repeated. Prints a
Markdown table (the network's success, mean and worst excess cost and outage share; the fixed
100 m plan's, the best single altitude's and the straight line's at 100 m excess cost and
outage share; the mean altitude flown by the network and by the optimum; training seconds)
and writes it to ``OUT/table.md``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from rainuav.train import main as train_main

HEADER = (
    "| seed | success | mean excess cost | worst | outage | fixed 100 m plan | best single "
    "altitude | straight line at 100 m | mean altitude (network / optimum) | training s |\n"
    "|---|---|---|---|---|---|---|---|---|---|"
)


def row(seed: int, m: dict) -> str:
    def pct(v: float | None) -> str:
        return "n/a" if v is None else f"{100 * v:.1f}%"

    def base(prefix: str) -> str:
        return f"{pct(m[prefix + 'mean_excess_cost'])}, outage {pct(m[prefix + 'outage_share'])}"

    return (
        f"| {seed} | {pct(m['success_rate'])} | {pct(m['mean_excess_cost'])} | "
        f"{pct(m['worst_excess_cost'])} | {pct(m['outage_share'])} | {base('fixed_altitude_')} | "
        f"{base('best_single_altitude_')} | {base('straight_line_')} | "
        f"{m['mean_altitude_m']:.1f} / {m['optimal_mean_altitude_m']:.1f} m | "
        f"{m['training_seconds']:.0f} |"
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("extra", nargs="*", help="more rainuav.train flags, after --")
    args = ap.parse_args(argv)
    base = ["--scenario", "uma", "--freq-ghz", "28", "--rain-rate-mm-h", "0",
            "--altitudes-m", "25:115:15"]  # fmt: skip
    lines = [HEADER]
    for seed in args.seeds:
        out = args.out / f"s{seed}"
        if not (out / "metrics.json").exists():
            rc = train_main([*base, "--seed", str(seed), "--out", str(out), *args.extra])
            if rc != 0:
                return rc
        m = json.loads((out / "metrics.json").read_text())
        lines.append(row(seed, m))
        print(lines[-1], flush=True)
    table = "\n".join(lines) + "\n"
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "table.md").write_text(table)
    print(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
