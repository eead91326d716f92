"""``python -m rainuav.train``: learn to fly from any start to the destination (the main job).

With no arguments: the paper's scenario in its own weather (25 mm/h; radio map built or taken from
the cache), the default learner (the paper's Algorithm 1 with measured departures from its Table I,
each listed on the Learning page; ``--preset paper-learner`` runs Algorithm 1 and Table I
literally), seed 0, results in ``runs/paper``. ``--preset NAME|FILE`` starts from a preset (a TOML
file of fields: ``paper-learner``, ``storms``, ``storm-levels`` ship with the package); every field
of [`rainuav.rl.config.TrainConfig`][rainuav.rl.config.TrainConfig] is a flag ``--name`` and
every field of its task, [`rainuav.nav.task.NavConfig`][rainuav.nav.task.NavConfig], a flag
``--task.name`` and every field of
[`rainuav.rl.config.DQNConfig`][rainuav.rl.dqnconfig.DQNConfig] a flag ``--dqn.name``
(``--help`` lists the run's own, ``--help-all`` all); ``--config run.toml`` reads fields from a
file; flags win over the file, the file over the preset. ``--resume`` continues an
interrupted run from its checkpoint (same configuration). The world (map or maps in time, and the
task) is built here from the configuration's world part
([`rainuav.world.build_world()`][rainuav.world.build_world]) and handed to the job,
[`rainuav.rl.loop.train()`][rainuav.rl.loop.train]."""

from __future__ import annotations

import argparse
import dataclasses
import sys
import textwrap
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from rainuav import _cli


def _parse_bool(text: str) -> bool:
    if text.lower() in ("1", "true", "yes", "on"):
        return True
    if text.lower() in ("0", "false", "no", "off"):
        return False
    raise argparse.ArgumentTypeError(f"expected true or false (got {text!r})")


SHOWN = (
    "preset", "scenario", "scenario_file", "rain_rate_mm_h", "freq_ghz", "engine", "altitudes_m",
    "storm_seed", "seed", "out", "device", "time_budget_s", "eval_starts", "dqn.episodes",
)  # fmt: skip
"""The run's own flags, the ones ``--help`` lists (``--help-all``: every field)."""


def _storm_seed(text: str) -> int:
    """A storm's seed (an integer; the storm distribution is ``--preset storms``)."""
    try:
        return int(text)
    except ValueError:
        msg = f"expected an integer (got {text!r}; every storm: --preset storms)"
        raise argparse.ArgumentTypeError(msg) from None


def _point(text: str) -> tuple[float, float]:
    """A point ``X,Y`` in metres."""
    try:
        x, y = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected X,Y in metres (got {text!r})") from None
    return (x, y)


def _flag(name: str) -> str:
    return f"--{name.replace('_', '-')}"


def build_parser(show_all: bool = False) -> argparse.ArgumentParser:
    """CLI flags generated from TrainConfig (``--name``), its task
    ([`rainuav.nav.task.NavConfig`][rainuav.nav.task.NavConfig], ``--task.name``) and
    DQNConfig (``--dqn.name``), one per field; ``--help`` lists the run's own
    ([`SHOWN`][rainuav.train.SHOWN]), ``--help-all`` every one."""
    from rainuav._checks import field_kind
    from rainuav.rl.config import SECTIONS, TrainConfig, preset_names

    flag_types = {"int": int, "float": float, "str": str, "bool": _parse_bool}
    ap = _cli.Parser(
        removed={"--goal-x-m": "--task.goal-m X,Y", "--goal-y-m": "--task.goal-m X,Y"},
        prog="python -m rainuav.train",
        description=_cli.plain_help(__doc__),
        epilog=textwrap.fill(
            f"Presets shipped: {', '.join(preset_names())} (rainuav/rl/preset_files). Every "
            "field of the run is a flag: --NAME for the run's (e.g. --storm-pool 8), "
            "--task.NAME for the task's (e.g. --task.max-steps 80), --dqn.NAME for the "
            "learner's (e.g. --dqn.lr 1e-4); --help-all lists them with their defaults.",
            width=79,
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument("--config", type=Path, help="a TOML file of the run's fields (config.toml)")
    ap.add_argument("--resume", action="store_true", help="continue from OUT/checkpoint.pt")
    for cls, prefix in ((TrainConfig, ""), *((c, f"{n}.") for n, c in SECTIONS.items())):
        docs = _cli.field_docs(cls)
        for f in dataclasses.fields(cls):
            if f.name in SECTIONS:
                continue
            name = prefix + f.name
            default = "unset" if f.default is None else f.default
            if f.name == "storm_seed":
                kind: Any = _storm_seed
            elif f.name in ("goal_m", "start_m"):
                kind = _point
            else:
                kind = flag_types.get(field_kind(f)[0], str)
            more = " As X,Y." if f.name in ("goal_m", "start_m") else ""
            text = _cli.plain_help(f"{docs.get(f.name, '')}{more} (default {default})")
            action = ap.add_argument(_flag(prefix + f.name), dest=name, type=kind, default=None,
                                     help=text)  # fmt: skip
            if name not in SHOWN:
                ap.hide(action)
    return _cli.show_all(ap) if show_all else ap


def config_from_args(args: argparse.Namespace) -> Any:
    """The run's TrainConfig: its preset, then the ``--config`` file's fields, then the flags
    given ([`rainuav.rl.config.resolve_config()`][rainuav.rl.config.resolve_config])."""
    from rainuav.rl.config import SECTIONS, TrainConfig, preset_fields, read_config, resolve_config

    fields: dict[str, Any] = {}
    if args.config is not None:
        fields.update(read_config(args.config))
    flags = {}
    for cls, prefix in ((TrainConfig, ""), *((c, f"{n}.") for n, c in SECTIONS.items())):
        for f in dataclasses.fields(cls):
            value = getattr(args, prefix + f.name, None)
            if f.name not in SECTIONS and value is not None:
                flags[prefix + f.name] = value
    fields.update(flags)
    preset = preset_fields(fields["preset"]) if fields.get("preset") else {}
    if preset and not args.resume:
        for k in sorted(set(flags) & set(preset)):
            if flags[k] != preset[k]:
                print(f"note: {_flag(k)} {flags[k]} in place of the preset "
                      f"{fields['preset']!r}'s {preset[k]}", file=sys.stderr)  # fmt: skip
    return resolve_config(fields)


def summary(metrics: dict[str, Any], out: Path) -> str:
    """The primary figures of a finished run as a short table (the network alone, the
    baselines, the exact optimum) and where its files are."""

    def pct(v: Any) -> str:
        return "-" if v is None else f"{100 * v:.1f}%"

    def num(v: Any) -> str:
        return "-" if v is None else f"{v:.1f}"

    rows = [
        ("network alone", "", "mean_excess_cost"),
        ("straight line", "straight_line_", "straight_line_mean_excess_cost"),
        ("frozen plan", "frozen_plan_", "frozen_plan_mean_excess_cost"),
        ("replanning", "replan_", "replan_mean_excess_cost"),
        ("fixed altitude", "fixed_altitude_", "fixed_altitude_mean_excess_cost"),
        ("best altitude", "best_single_altitude_", "best_single_altitude_mean_excess_cost"),
        ("exact optimum", "optimal_", None),
    ]
    # The plan of the weather at take-off and re-planning are there where the weather moves;
    # the plans of one altitude where the flight chooses among levels.
    rows = [r for r in rows if r[1] == "" or f"{r[1]}success_rate" in metrics]
    lines = [
        f"{metrics['eval_starts']} evaluation starts, {metrics['episodes']} episodes, "
        f"{metrics['training_seconds']:.0f} s of training on {metrics['device']}",
        f"{'':<15}{'success':>9}{'excess cost':>13}{'mean cost':>11}{'outage':>9}",
    ]
    for name, prefix, excess in rows:
        excess_cost = 0.0 if excess is None else metrics.get(excess)
        lines.append(
            f"{name:<15}{pct(metrics.get(prefix + 'success_rate')):>9}"
            f"{pct(excess_cost):>13}{num(metrics.get(prefix + 'mean_cost')):>11}"
            f"{pct(metrics.get(prefix + 'outage_share')):>9}"
        )
    lines.append(f"wrote {out.resolve()} (metrics.json has every figure)")
    return "\n".join(lines)


def budget_note(done: int, planned: int, budget_s: float, out: Path) -> str:
    """What to do when the wall-clock budget ended training before its episodes ("" when
    they all ran): resuming with a larger budget ends as if the run had never stopped."""
    if done >= planned or not budget_s:
        return ""
    return (
        f"the {budget_s:.0f} s budget ended training after {done} of {planned} episodes; "
        f"python -m rainuav.train --resume --config {out / 'config.toml'} --time-budget-s "
        f"{2 * budget_s:.0f} continues it to {planned}"
    )


def main(argv: Sequence[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if "--help-all" in argv:
        build_parser(show_all=True).print_help()
        return 0
    ap = build_parser()
    args = ap.parse_args(_cli.attach_negative_values(argv, _cli.metre_flags(ap)))
    out: list[Path] = []  # the run's folder, once its configuration is known

    def kept() -> str:
        ck = out[0] / "checkpoint.pt" if out else None
        if ck is None or not ck.exists():
            return "training stopped before its first checkpoint; nothing to resume from"
        return f"training stopped; the same command with --resume continues from {ck}"

    def body() -> int:
        from rainuav._io import check_out_dir
        from rainuav.radio.scene.storms import check_storm_seed
        from rainuav.rl.config import check_config
        from rainuav.rl.loop import train
        from rainuav.rl.setup import check_fits
        from rainuav.world import build_world, load_world
        from rainuav.world.pool import StormPool

        cfg = config_from_args(args)
        check_config(cfg)
        # Refused before any map is built: a run that cannot fit, a bad --out, a storm
        # reserved for evaluation.
        check_fits(cfg)
        check_out_dir(cfg.out, "out")
        if cfg.scenario == "storm" and not cfg.scenario_file:
            check_storm_seed(cfg.storm_seed, training=True)
        out.append(Path(cfg.out))
        # The run's world: its own saved signal when resuming, else built from its spec.
        world = load_world(Path(cfg.out), cfg) if args.resume else None
        if cfg.storm_pool:
            world = StormPool(cfg, cfg.seed).world()
        world = world or build_world(cfg, progress=True)
        metrics = train(cfg, world, resume=args.resume, progress=True)
        print(summary(metrics, Path(cfg.out)))
        note = budget_note(metrics["episodes"], cfg.dqn.episodes, cfg.time_budget_s, Path(cfg.out))
        if note:
            print(note)
        return 0

    return _cli.run(body, kept)


if __name__ == "__main__":
    sys.exit(main())
