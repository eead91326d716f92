"""``python -m rainuav.evaluate RUN_DIR``: re-evaluate a saved training run.

Loads the run's ``config.toml``, ``radiomap.npz`` and ``checkpoint.pt``, evaluates the greedy
policy (the final network, or with ``keep_best`` the best on validation) from the run's fixed
evaluation starts against the exact planner, and rewrites ``metrics.json`` and
``trajectories.png``.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import torch

from rainuav._io import write_atomic
from rainuav.errors import InvalidInputError
from rainuav.radiomap import RadioMap
from rainuav.train import (
    Validation,
    evaluate_run_policy,
    load_config,
    make_agent,
    make_env,
    pick_device,
    plot_trajectories,
)


def evaluate_run(run_dir: Path, device: str = "cpu") -> dict:
    run = Path(run_dir)
    for name in ("config.toml", "radiomap.npz", "checkpoint.pt"):
        if not (run / name).exists():
            raise InvalidInputError(f"{run}: missing {name}; is this a rainuav.train output?")
    cfg = load_config(run / "config.toml")
    rm = RadioMap.load(run / "radiomap.npz")
    env = make_env(cfg, rm.sir_db, rm.extent_m)
    agent = make_agent(cfg, env, pick_device(device))
    state = torch.load(run / "checkpoint.pt", weights_only=False, map_location=agent.device)
    agent.load_state_dict(state["agent"])
    checks = Validation(np.zeros((0, 2)), np.zeros(0))
    if "validation" in state:
        checks.load_state_dict(state["validation"])
    metrics, rolls = evaluate_run_policy(cfg, agent, env, checks)
    metrics["episodes"] = len(state["returns"])
    metrics["training_seconds"] = state["train_seconds"]
    text = json.dumps(metrics, indent=2)
    write_atomic(run / "metrics.json", lambda t: t.write_text(text + "\n"))
    plot_trajectories(
        env,
        rolls[:40],
        run / "trajectories.png",
        f"greedy policy, success {100 * metrics['success_rate']:.0f}%",
    )
    return metrics


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m rainuav.evaluate", description=__doc__)
    ap.add_argument("run_dir", type=Path)
    ap.add_argument("--device", default="cpu")
    args = ap.parse_args(argv)
    try:
        metrics = evaluate_run(args.run_dir, args.device)
    except InvalidInputError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    print(json.dumps(metrics, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
