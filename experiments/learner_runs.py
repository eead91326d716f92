"""The learner's headline figures: default runs on several maps and seeds, each evaluated on the
network alone from the run's 200 fixed evaluation starts, tabulated.

    python experiments/learner_runs.py --scenarios paper uma rain_cell --seeds 0 1 2 --out runs/m

Each run is ``python -m rainuav.train --scenario S --seed K`` (nothing else changed) in
``OUT/S_sK``; a run whose ``metrics.json`` exists is not repeated. Prints a Markdown table
(success, mean and worst excess cost, the straight line's excess cost, moves, SINR, outage,
training seconds, and where the run reports the weight average, the last online network's
success and mean excess cost) and writes it to ``OUT/table.md``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from rainuav.train import main as train_main


def row(name: str, seed: int, m: dict) -> str:
    def pct(v: float | None) -> str:
        return "n/a" if v is None else f"{100 * v:.1f}%"

    return (
        f"| {name} | {seed} | {pct(m['success_rate'])} | {pct(m['mean_excess_cost'])} | "
        f"{pct(m['worst_excess_cost'])} | {pct(m['straight_line_mean_excess_cost'])} | "
        f"{m['mean_steps']:.1f} | {m['mean_signal_db']:.2f} | {pct(m['outage_share'])} | "
        f"{m['training_seconds']:.0f} | {online(m)} |"
    )


def online(m: dict) -> str:
    """The last online network's success and mean excess cost, where the run reports the weight
    average (``average_from`` < 1); else n/a."""
    if "online_success_rate" not in m:
        return "n/a"
    excess = m["online_mean_excess_cost"]
    cost = "n/a" if excess is None else f"{100 * excess:.1f}%"
    return f"{100 * m['online_success_rate']:.1f}% / {cost}"


HEADER = (
    "| scenario | seed | success | mean excess cost | worst excess cost | straight line's "
    "mean excess | moves | mean SINR dB | outage | training s | last online network |\n"
    "|---|---|---|---|---|---|---|---|---|---|---|"
)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--scenarios", nargs="+", default=["paper", "uma", "rain_cell"])
    ap.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("extra", nargs="*", help="more rainuav.train flags, after --")
    args = ap.parse_args(argv)
    lines = [HEADER]
    for name in args.scenarios:
        for seed in args.seeds:
            out = args.out / f"{name}_s{seed}"
            if not (out / "metrics.json").exists():
                flags = ["--scenario", name, "--seed", str(seed), "--out", str(out)]
                if train_main([*flags, *args.extra]) != 0:
                    return 1
            lines.append(row(name, seed, json.loads((out / "metrics.json").read_text())))
    table = "\n".join(lines)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "table.md").write_text(table + "\n")
    print(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
