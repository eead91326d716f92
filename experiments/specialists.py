"""The per-storm learner as a yardstick for the network that flies every storm:
today's learner (the position and the flight time as input) trained on one held-out storm
alone and flown on that very storm, from the same 20 fixed starts as the generalist's
evaluation (``python -m rainuav.evaluate RUN --storm-seeds A-B``, the run's ``eval_seed``).

    python experiments/specialists.py --seeds 1000000-1000002 --out runs/specialists

Evaluation storms are refused for training everywhere else; here each specialist is the
best a single-storm network does on its storm, not a result of ours, so it trains on it
(``train(..., yardstick=True)``). Writes ``specialists.json`` (per storm: success, excess
cost over the optimum, training seconds).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from rainuav.rl.config import TrainConfig
from rainuav.rl.loop import train
from rainuav.rl.storm_eval import parse_seeds
from rainuav.world import build_world

KEYS = ("success_rate", "mean_excess_cost", "worst_excess_cost", "training_seconds")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seeds", default="1000000-1000002")
    ap.add_argument("--starts", type=int, default=20)
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args(argv)
    rows = []
    for k in parse_seeds(args.seeds):
        cfg = TrainConfig(
            scenario="storm", storm_seed=k, eval_starts=args.starts, out=str(args.out / f"s{k}")
        )
        m = train(cfg, build_world(cfg, cache=False), progress=False, yardstick=True)
        rows.append({"storm_seed": k, **{key: m[key] for key in KEYS}})
        print(json.dumps(rows[-1]))
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "specialists.json").write_text(json.dumps(rows, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
