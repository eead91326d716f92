"""``python -m rainuav.evaluate RUN_DIR``: fly a trained policy, on its own map or another.

    python -m rainuav.evaluate runs/paper                          # its own map and starts
    python -m rainuav.evaluate runs/paper --rain-rate-mm-h 50            # the same network in rain
    python -m rainuav.evaluate runs/uma --scenario rain_cell --starts 100 --seed 7 --shield
    python -m rainuav.evaluate runs/storm0 --scenario storm --storm-seed 1000003
    python -m rainuav.evaluate runs/storms --storm-seeds 1000000-1000049 --starts 20

``--storm-seeds A-B`` flies the network through every storm of the range (20 starts each by
default; ``--random-goals``: each start to its own destination) with every baseline and
writes the per-storm figures and their mean ([`rainuav.rl.storm_eval`][rainuav.rl.storm_eval]) into
``RUN_DIR/eval_storms_A-B`` with ``evaluation_storm_flights.png`` of the first storm.

Loads the run's ``config.toml`` and ``checkpoint.pt`` and flies the network the run reports (the
weight average of the last episodes, the final one with ``average_from = 1``, or with ``keep_best``
the best on validation; ``--online``: the last online network) from fixed starts, against the exact
optimum of the map flown and the straight line
([`rainuav.rl.evaluation.evaluate_saved_run()`][rainuav.rl.evaluation.evaluate_saved_run]).
``--scenario``, ``--rain-rate-mm-h``, ``--engine`` and ``--storm-seed`` fly it in another world (the
run's spec with those changed, built or taken from the cache:
[`rainuav.world.build_world()`][rainuav.world.build_world]): the paper's central comparison, a
policy trained in clear air flown in rain against one trained in rain, or a network trained on one
storm flown through another. In a weather that moves, the plan of the weather at take-off and
re-planning are reported beside it. Writes ``evaluation.json`` and ``evaluation_trajectories.png``
(the network's flights and the exact optimum's from the same starts) into ``--out`` (default: the
run's folder for its own map, ``RUN_DIR/eval_<scenario>_<rain>mmh`` for another; with ``--online``,
``RUN_DIR/eval_online`` and ``..._online``). The run's own files are never touched.
``evaluation.json`` is written last: a folder holding it is complete."""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from rainuav import _cli
from rainuav._checks import check_integer
from rainuav._io import begin_folder, check_out_dir, write_atomic
from rainuav.radio.engines import ENGINES

OTHER_WORLD = ("scenario", "rain_rate_mm_h", "engine", "storm_seed", "freq_ghz")
"""The flags that fly the run in another world."""


def _out_dir(args: argparse.Namespace) -> Path:
    if args.out is not None:
        return args.out
    if all(getattr(args, k) is None for k in OTHER_WORLD):
        return args.run_dir / "eval_online" if args.online else args.run_dir
    rain = "own" if args.rain_rate_mm_h is None else f"{args.rain_rate_mm_h:g}"
    storm = "" if args.storm_seed is None else f"_storm{args.storm_seed}"
    suffix = "_online" if args.online else ""
    return args.run_dir / f"eval_{args.scenario or 'same'}_{rain}mmh{storm}{suffix}"


def _world(args: argparse.Namespace) -> object:
    """The world to fly in: None (the run's own), or a function of the run's configuration
    that builds its spec with the flags given (called once the run's files are read)."""
    import dataclasses

    from rainuav.world import build_world, spec_of

    if all(getattr(args, k) is None for k in OTHER_WORLD):
        return None
    changes = {k: getattr(args, k) for k in OTHER_WORLD if getattr(args, k) is not None}
    if args.scenario is not None:
        changes["scenario_file"] = ""  # another preset comes in its own weather
        changes.setdefault("rain_rate_mm_h", None)
    changes["storm_pool"] = 0  # one world: a run over the storm distribution flown in it

    def build(cfg: object) -> object:
        return build_world(dataclasses.replace(spec_of(cfg), **changes), progress=True)

    return build


@dataclass
class EvaluateOptions:
    """What ``python -m rainuav.evaluate`` takes besides the run's folder (one docstring line per
    field = one flag, generated as ``train``'s are)."""

    scenario: str | None = None
    """Fly on this preset's map (in its own weather, unless --rain-rate-mm-h)."""
    rain_rate_mm_h: float | None = None
    """Homogeneous rain, mm/h."""
    engine: str | None = dataclasses.field(default=None, metadata={"choices": tuple(ENGINES)})
    """Propagation engine of the world flown."""
    storm_seed: int | None = None
    """Fly through this storm of the 'storm' scenario."""
    freq_ghz: float | None = dataclasses.field(default=None, metadata={"more": True})
    """Carrier frequency, GHz."""
    storm_seeds: str | None = None
    """Fly through every storm A-B (inclusive), 20 starts each unless --starts."""
    random_goals: bool = False
    """A destination per start (with --storm-seeds, or in the world the flags give)."""
    starts: int | None = None
    """Number of fixed starts (default: the run's eval_starts)."""
    seed: int | None = None
    """Seed of the starts (default: the run's eval_seed)."""
    shield: bool = dataclasses.field(default=False, metadata={"more": True})
    """Also report shielded flights."""
    online: bool = dataclasses.field(default=False, metadata={"more": True})
    """Fly the last online network, not the one the run reports (the weight average)."""
    device: str = dataclasses.field(
        default="cpu", metadata={"more": True, "choices": ("cpu", "cuda", "auto")}
    )
    """Where the network runs."""
    out: Path | None = None
    """Output folder (default: the run's folder for its own map, a folder in it for another)."""


def build_parser() -> argparse.ArgumentParser:
    """The command line: the run's folder, then a flag for each field of
    [`EvaluateOptions`][rainuav.evaluate.EvaluateOptions]."""
    ap = _cli.Parser(
        prog="python -m rainuav.evaluate",
        description=_cli.plain_help(__doc__),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument("run_dir", type=Path)
    _cli.add_fields(ap, EvaluateOptions)
    return ap


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return _cli.run(lambda: _evaluate(args), "the evaluation stopped; nothing was written")


def _evaluate(args: argparse.Namespace) -> int:
    from rainuav.nav.figures import plot_policy, plot_storm_flights
    from rainuav.rl.config import MAX_SEED, MAX_STARTS
    from rainuav.rl.evaluation import evaluate_saved_run

    if args.starts is not None:
        check_integer("--starts", args.starts, 1, MAX_STARTS)
    if args.seed is not None:
        check_integer("--seed", args.seed, 0, MAX_SEED)
    if args.storm_seeds is not None or args.random_goals:
        return _evaluate_storms(args)
    out = check_out_dir(_out_dir(args))  # before any work
    metrics, rolls, env = evaluate_saved_run(
        args.run_dir,
        args.device,
        world=_world(args),  # type: ignore[arg-type]
        starts=args.starts,
        seed=args.seed,
        shield=args.shield,
        online=args.online,
    )
    text = json.dumps(metrics, indent=2)
    begin_folder(out, "evaluation.json")
    plot_policy(env, metrics, rolls[:40], out / "evaluation_trajectories.png")
    if env.field.varies and env.altitudes_m is None:  # (among levels: the heights)
        plot_storm_flights(env, rolls[:6], out / "evaluation_storm_flights.png")
    write_atomic(out / "evaluation.json", lambda t: t.write_text(text + "\n"))  # last
    print(text)
    print(f"wrote {out.resolve()}", file=sys.stderr)
    return 0


def _evaluate_storms(args: argparse.Namespace) -> int:
    """``--storm-seeds`` (every storm of the range) or ``--random-goals`` (in the one world the
    flags give):
    [`rainuav.rl.storm_eval.evaluate_worlds()`][rainuav.rl.storm_eval.evaluate_worlds]."""
    from rainuav.errors import InvalidInputError
    from rainuav.nav.figures import plot_policy, plot_storm_flights
    from rainuav.rl.storm_eval import evaluate_worlds, parse_seeds

    if args.shield:
        raise InvalidInputError("--storm-seeds and --random-goals fly the network alone")
    given = {k: getattr(args, k) for k in OTHER_WORLD if getattr(args, k) is not None}
    goals = ("_random_goals" if args.random_goals else "") + ("_online" if args.online else "")
    if args.storm_seeds is not None:
        if given:
            raise InvalidInputError(f"--storm-seeds: give no --{next(iter(given))} beside it")
        seeds = parse_seeds(args.storm_seeds)
        worlds = [{"storm_seed": k} for k in seeds]
        name = f"eval_storms_{seeds[0]}-{seeds[-1]}{goals}"
    else:
        if not given:
            raise InvalidInputError(
                "--random-goals: name the world (--scenario, --rain-rate-mm-h, --storm-seed, ...)"
            )
        worlds = [given]
        name = "eval_" + "_".join(f"{k}{v}" for k, v in given.items()) + goals
    out = check_out_dir(args.out if args.out is not None else args.run_dir / name)
    result, first = evaluate_worlds(
        args.run_dir,
        worlds,
        starts=20 if args.starts is None else args.starts,
        seed=args.seed,
        random_goals=args.random_goals,
        device=args.device,
        storms=args.storm_seeds is not None,
        online=args.online,
    )
    text = json.dumps(result, indent=2)
    begin_folder(out, "evaluation.json")
    if first is not None and first[0].altitudes_m is not None:  # the flights and heights
        plot_policy(first[0], result["worlds"][0], first[1], out / "evaluation_trajectories.png")
    elif first is not None and first[0].field.varies:
        plot_storm_flights(first[0], first[1], out / "evaluation_storm_flights.png")
    write_atomic(out / "evaluation.json", lambda t: t.write_text(text + "\n"))  # last
    print(json.dumps(result["mean"], indent=2))
    print(f"wrote {out.resolve()}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
