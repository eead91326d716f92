"""``python -m rainuav.evaluate RUN_DIR [--out DIR]``: re-evaluate a saved training run.

Loads the run's ``config.toml``, ``radiomap.npz`` and ``checkpoint.pt``, evaluates the greedy
policy (the final network, or with ``keep_best`` the best on validation) from the run's fixed
evaluation starts against the exact planner (:func:`rainuav.rl.evaluation.evaluate_saved_run`),
prints the metrics and writes ``evaluation.json`` and ``evaluation_trajectories.png`` into
``--out`` (default: the run's folder). The run's own ``metrics.json`` is never touched.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

from rainuav._io import write_atomic
from rainuav.errors import InvalidInputError


def main(argv: Sequence[str] | None = None) -> int:
    from rainuav.rl.evaluation import evaluate_saved_run
    from rainuav.rl.plots import plot_trajectories

    ap = argparse.ArgumentParser(prog="python -m rainuav.evaluate", description=__doc__)
    ap.add_argument("run_dir", type=Path)
    ap.add_argument("--device", default="cpu", choices=("cpu", "cuda", "auto"))
    ap.add_argument("--out", type=Path, default=None, help="output folder (default: RUN_DIR)")
    args = ap.parse_args(argv)
    out = args.run_dir if args.out is None else args.out
    try:
        metrics, rolls, env = evaluate_saved_run(args.run_dir, args.device)
    except InvalidInputError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    text = json.dumps(metrics, indent=2)
    write_atomic(out / "evaluation.json", lambda t: t.write_text(text + "\n"))
    title = f"greedy policy, success {100 * metrics['success_rate']:.0f}%"
    plot_trajectories(env, rolls[:40], out / "evaluation_trajectories.png", title)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
