"""What a training run depends on: the learner's hyperparameters
([`DQNConfig`][rainuav.rl.dqnconfig.DQNConfig]) and the run's settings
([`TrainConfig`][rainuav.rl.config.TrainConfig]), their checks, their TOML form and the random
streams derived from the run's one seed."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rainuav._checks import check_field_kinds
from rainuav._io import plain, read_toml
from rainuav.errors import InvalidInputError
from rainuav.nav.task import NavConfig
from rainuav.rl.dqnconfig import DQNConfig
from rainuav.rl.seeds import random_streams
from rainuav.world import WorldSpec, check_spec

__all__ = [
    "MAX_EXTENDS",
    "PRESETS_RENAMED",
    "PRESET_DIR",
    "RENAMED",
    "SECTIONS",
    "DQNConfig",
    "TrainConfig",
    "check_config",
    "field_name",
    "flat",
    "flat_fields",
    "load_config",
    "preset_fields",
    "preset_learner",
    "preset_names",
    "random_streams",
    "read_config",
    "resolve_config",
    "to_dict",
]


@dataclass
class TrainConfig(WorldSpec):
    """Everything a training run depends on: the world's spec
    ([`rainuav.world.WorldSpec`][rainuav.world.WorldSpec]: scenario, weather, task), the run's
    settings below and the learner's hyperparameters (``dqn``). One docstring line per field = one
    CLI flag."""

    preset: str = ""
    """The preset the run starts from: '' (the tuned defaults: docs/record/learning.md),
    a preset shipped with the package ('paper-learner': Algorithm 1 and Table I literally; 'storms';
    'storm-levels') or a TOML file of fields; the fields given beside it win
    ([`resolve_config()`][rainuav.rl.config.resolve_config])."""
    seed: int = 0
    """Seed of every random choice (python, numpy, torch, environment)."""
    device: str = "auto"
    """'auto' (CUDA when available), 'cpu' or 'cuda'."""
    out: str = "runs/paper"
    """Output directory."""
    checkpoint_every: int = 250
    """Episodes between checkpoints."""
    eval_starts: int = 200
    """Greedy evaluation starts (fixed, seeded by eval_seed)."""
    eval_seed: int = 12345
    """Seed of the evaluation starts."""
    stages: int = 4
    """Training stages at which a few greedy trajectories are recorded for stages.png."""
    validate_every: int = 100
    """Episodes between greedy checks on held-out validation starts (0: none)."""
    validate_starts: int = 100
    """Validation starts (seeded by eval_seed + 2; not the evaluation starts)."""
    time_budget_s: float = 0.0
    """Wall-clock budget of the training, s: it ends at the first finished episode past it
    (0: none; the schedules still run over dqn.episodes). For comparisons at equal budget."""
    replan_every: int = 10
    """Moves between re-plans of the replanning baseline reported beside a run in a moving
    weather (rainuav.nav.baselines.replans)."""
    storm_episodes: int = 32
    """Episodes flown in one storm of a storm pool before it is renewed (--storm-pool)."""
    keep_best: bool = False
    """Evaluate and save the network with the best validation score (success, then excess
    cost), not the final one."""
    dqn: DQNConfig = field(default_factory=DQNConfig)
    """Agent hyperparameters."""


MAX_SEED = 2**63 - 1
"""The largest seed: torch seeds with a 64-bit integer and numpy's SeedSequence takes any
non-negative one; 0..2^63-1 is what both, and every file format, hold exactly."""
MAX_STARTS = 10_000
"""The most evaluation or validation starts. Each costs one exact plan (47 ms of the 2-core
machine for the `uma` and `paper` presets) and, with the network's and the straight line's
flights, about 80 ms of evaluation (benches/hostile_corpus.py: 2000 starts in 159 s), so
10 000 take about 13 minutes, with a progress bar; the success rate's standard error is then
at most 0.5 points, and more starts would mostly add time."""
MAX_LANES = 4096
"""The most UAVs in flight at once during training (each is its own Python N-step window;
the tuned learner flies 16)."""


def check_config(cfg: TrainConfig) -> None:
    """Checks a run's configuration before anything is built.

    Args:
        cfg: The run's [`TrainConfig`][rainuav.rl.config.TrainConfig].

    Raises:
        InvalidInputError: The first field of the wrong kind or outside its allowed range, named.
    """
    if not isinstance(cfg.dqn, DQNConfig):
        raise InvalidInputError(f"dqn must be a DQNConfig (got {type(cfg.dqn).__name__})")
    check_field_kinds(cfg)
    check_field_kinds(cfg.dqn, "dqn.")
    d = cfg.dqn
    checks = [
        ("episodes", d.episodes >= 1, ">= 1"),
        ("target_sync_episodes", d.target_sync_episodes >= 1, ">= 1"),
        ("eps0", 0 <= d.eps0 <= 1, "in [0, 1]"),
        ("eps_decay", 0 < d.eps_decay <= 1, "in (0, 1]"),
        ("replay_capacity", d.replay_capacity >= d.batch_size, ">= batch_size"),
        ("batch_size", d.batch_size >= 1, ">= 1"),
        ("gamma", 0 < d.gamma <= 1, "in (0, 1]"),
        ("n_step", d.n_step >= 1, ">= 1"),
        ("lr", 0 < d.lr < math.inf, "> 0"),
        ("lr_final", 0 <= d.lr_final < math.inf, ">= 0 (0: lr throughout)"),
        ("average_from", 0 <= d.average_from <= 1, "in [0, 1]"),
        ("hidden", d.hidden >= 1, ">= 1"),
        ("fourier", d.fourier >= 0, ">= 0"),
        ("lanes", 1 <= d.lanes <= MAX_LANES, f"in 1..{MAX_LANES}"),
        ("goal_features", d.goal_features >= 0, ">= 0"),
        ("conv", 1 <= d.conv <= 256, "in 1..256"),
        ("goal_starts", 0 <= d.goal_starts <= 1, "in [0, 1]"),
        ("level_starts", 0 <= d.level_starts <= 1, "in [0, 1]"),
        ("task_goals", 0 <= d.task_goals <= 1, "in [0, 1]"),
        ("shaping", 0 <= d.shaping < math.inf, ">= 0 and finite"),
        ("sir_weight", 0 <= d.sir_weight < math.inf, ">= 0 and finite"),
        ("train_every", d.train_every >= 1, ">= 1"),
        ("learning_starts", d.learning_starts >= 0, ">= 0"),
        ("reward_scale", 0 < d.reward_scale < math.inf, "> 0"),
        ("grad_clip", 0 <= d.grad_clip < math.inf, ">= 0 and finite"),
        ("loss", d.loss in ("huber", "mse"), "'huber' or 'mse'"),
        (
            "preset",
            cfg.preset in ("", *preset_names()) or Path(cfg.preset).is_file(),
            f"'', one of {preset_names()} or a TOML file",
        ),
        ("seed", 0 <= cfg.seed <= MAX_SEED, f"in 0..{MAX_SEED} (2^63 - 1)"),
        ("eval_seed", 0 <= cfg.eval_seed <= MAX_SEED, f"in 0..{MAX_SEED} (2^63 - 1)"),
        ("eval_starts", 1 <= cfg.eval_starts <= MAX_STARTS, f"in 1..{MAX_STARTS}"),
        ("validate_every", cfg.validate_every >= 0, ">= 0"),
        ("time_budget_s", 0 <= cfg.time_budget_s < math.inf, ">= 0 and finite"),
        ("validate_starts", 1 <= cfg.validate_starts <= MAX_STARTS, f"in 1..{MAX_STARTS}"),
        ("checkpoint_every", cfg.checkpoint_every >= 1, ">= 1"),
        ("device", cfg.device in ("auto", "cpu", "cuda"), "'auto', 'cpu' or 'cuda'"),
        ("replan_every", cfg.replan_every >= 1, ">= 1"),
        ("storm_episodes", cfg.storm_episodes >= 1, ">= 1"),
        ("shield", not (d.shield and cfg.altitudes_m), "false with altitudes_m (the plane's)"),
    ]
    for name, ok, allowed in checks:
        if not ok:
            value = getattr(d, name) if hasattr(d, name) else getattr(cfg, name)
            raise InvalidInputError(f"{name} must be {allowed} (got {value!r})")
    check_spec(cfg)


PRESET_DIR = Path(__file__).with_name("preset_files")
"""Where the presets shipped with the package live, one TOML file each (``NAME.toml``)."""


def preset_names() -> list[str]:
    """The presets shipped with the package.

    Returns:
        Their names (`paper-learner`, `storms`, `storm-levels`), sorted.
    """
    return sorted(p.stem for p in PRESET_DIR.glob("*.toml"))


SECTIONS: dict[str, type] = {"task": NavConfig, "dqn": DQNConfig}
"""The tables of a run's fields (``[task]``, ``[dqn]`` in its file; ``task.NAME``, ``dqn.NAME``
flat and on the command line)."""
RENAMED = {"rain_rate": "rain_rate_mm_h", "altitudes": "altitudes_m"}
"""Fields read under their earlier names in run files and checkpoints written before the rename
(the command line takes today's names alone)."""
PRESETS_RENAMED = {"paper": "paper-learner"}
"""Presets read under their earlier names in run files and checkpoints (``paper``, the paper's
learner, is ``paper-learner``: ``paper`` alone names the scenario)."""


def _names(cls: type) -> set[str]:
    return {f.name for f in dataclasses.fields(cls)}


def field_name(key: str) -> str | None:
    """The flat name a key names in any form [`flat_fields()`][rainuav.rl.config.flat_fields] reads.

    Itself, a task field without its table (`max_steps`) or a [`RENAMED`][rainuav.rl.config.RENAMED]
    field; `goal_x_m` and `goal_y_m` are parts of `task.goal_m`.

    Args:
        key: A field's name as a file or a flag gives it.

    Returns:
        The flat name (`scenario`, `task.max_steps`, `dqn.lr`), or None where it names no field.
    """
    if key in ("goal_x_m", "goal_y_m"):
        return "task.goal_m"
    section, _, name = key.rpartition(".")
    if section:
        return key if section in SECTIONS and name in _names(SECTIONS[section]) else None
    if name in _names(NavConfig):
        return f"task.{name}"
    name = RENAMED.get(name, name)
    return name if name in _names(TrainConfig) - set(SECTIONS) else None


def flat_fields(data: dict[str, Any], where: str) -> dict[str, Any]:
    """The fields of a run's TOML table as flat names (`scenario`, `task.max_steps`, `dqn.lr`).

    The `[task]` and `[dqn]` sub-tables, or names already flat; earlier forms are read too
    ([`field_name()`][rainuav.rl.config.field_name]): the [`RENAMED`][rainuav.rl.config.RENAMED]
    fields, a task field at the top (`max_steps`) and the destination as `goal_x_m` / `goal_y_m`.

    Args:
        data: The table, as read from TOML.
        where: What the errors name (the file).

    Returns:
        The fields by flat name.

    Raises:
        InvalidInputError: An unknown name, a sub-table that is not a table, or a field given twice
            (under two names).
    """
    out: dict[str, Any] = {}
    unknown: list[str] = []
    goal: dict[int, Any] = {}

    def put(key: str, value: Any) -> None:
        name = field_name(key)
        if name is None:
            unknown.append(key)
        elif name in out:
            raise InvalidInputError(f"{where}: {name} is given twice (under two names)")
        else:
            out[name] = value

    for key, value in data.items():
        if key in SECTIONS:
            if not isinstance(value, dict):
                raise InvalidInputError(f"{where}: [{key}] must be a table")
            for k, v in value.items():
                put(f"{key}.{k}", v)
        elif key in ("goal_x_m", "goal_y_m"):
            goal[key == "goal_y_m"] = value
        else:
            put(key, value)
    if goal:
        default = NavConfig().goal_m
        put("task.goal_m", (goal.get(0, default[0]), goal.get(1, default[1])))
    if unknown:
        unknown.sort(key=lambda k: ("." in k, k))  # the run's own first, then the tables'
        raise InvalidInputError(f"{where}: unknown field(s) {unknown}")
    if out.get("preset") in PRESETS_RENAMED:  # a run of an earlier release
        out["preset"] = PRESETS_RENAMED[out["preset"]]
    return out


MAX_EXTENDS = 100
"""The most presets one ``extends`` chain may link."""


def preset_fields(name_or_path: str | Path, _seen: tuple[str, ...] = ()) -> dict[str, Any]:
    """The fields a preset sets, flat (`"scenario"`, `"dqn.lr"`).

    A shipped preset by name ([`preset_names()`][rainuav.rl.config.preset_names]) or a TOML file of
    the form of a run's `config.toml` (some fields only), which may start from another preset
    (`extends = "NAME"`, its own fields winning; a run's `config.toml` starts from the `preset` it
    records).

    Args:
        name_or_path: A preset's name or a TOML file.
        _seen: The presets already read on the way (a chain of `extends` is bounded).

    Returns:
        The fields by flat name.

    Raises:
        InvalidInputError: An unknown name, a bad file, or an `extends` that chains too far or names
            no preset.
    """
    text = str(name_or_path)
    path = PRESET_DIR / f"{text}.toml" if text in preset_names() else Path(text)
    if text in PRESETS_RENAMED and not path.is_file():
        raise InvalidInputError(
            f"preset {text!r} is now {PRESETS_RENAMED[text]!r} (must be one of {preset_names()} "
            "or a TOML file)"
        )
    if not path.is_file():
        raise InvalidInputError(
            f"preset must be one of {preset_names()} or a TOML file (got {text!r}: no such file)"
        )
    data = read_toml(path, "preset")
    if "preset" in data:  # a run's config.toml as a preset: the preset it records is its base
        if "extends" in data:
            raise InvalidInputError(f"preset {path}: give extends or preset, not both")
        data["extends"] = data.pop("preset") or None
    base = data.pop("extends", None)
    base = PRESETS_RENAMED.get(base, base)  # a file written before a rename
    if base is not None and (not isinstance(base, str) or base in (*_seen, text)):
        raise InvalidInputError(f"preset {path}: extends must name another preset (got {base!r})")
    if base is not None and len(_seen) + 1 >= MAX_EXTENDS:
        raise InvalidInputError(
            f"preset {path}: extends chains more than {MAX_EXTENDS} presets (join some)"
        )
    if base is not None and base not in preset_names() and not Path(base).is_absolute():
        near = path.parent / base  # a preset's extends is read from the preset's own folder
        if near.is_file():
            base = str(near)
    fields = {} if base is None else preset_fields(base, (*_seen, text))
    return {**fields, **flat_fields(data, f"preset {path}")}


def preset_learner(name_or_path: str | Path) -> dict[str, Any]:
    """The `[dqn]` fields a preset sets.

    Args:
        name_or_path: A preset's name or a TOML file.

    Returns:
        The learner's fields, by name without `dqn.`.
    """
    return {k[4:]: v for k, v in preset_fields(name_or_path).items() if k.startswith("dqn.")}


def resolve_config(fields: dict[str, Any]) -> TrainConfig:
    """The run's configuration from flat fields: the defaults, then the preset, then the fields.

    The one place where a preset and overrides meet (the `train` command, studies, a run's
    `config.toml` read back); the result records the preset's name.

    Args:
        fields: Flat fields (TrainConfig names, `task.<name>` and `dqn.<name>`; the earlier forms
            [`flat_fields()`][rainuav.rl.config.flat_fields] reads too); `fields["preset"]` names
            the preset ([`preset_fields()`][rainuav.rl.config.preset_fields]).

    Returns:
        The [`TrainConfig`][rainuav.rl.config.TrainConfig], checked.

    Raises:
        InvalidInputError: A field of the wrong kind or out of range, or an unknown preset.
    """
    given = flat_fields(fields, "configuration")
    preset = given.get("preset") or ""
    merged = {**(preset_fields(preset) if preset else {}), **given}
    tables: dict[str, dict[str, Any]] = {name: {} for name in SECTIONS}
    top = {}
    for key, value in merged.items():
        section, _, name = key.rpartition(".")
        if section:
            tables[section][name] = value
        else:
            top[key] = value
    try:
        made = {name: cls(**tables[name]) for name, cls in SECTIONS.items()}
        return TrainConfig(**top, **made)
    except TypeError as err:
        raise InvalidInputError(f"configuration: {err}") from err


def flat(cfg: TrainConfig) -> dict[str, Any]:
    """The fields of a configuration, flat, as `resolve_config()` takes them.

    Args:
        cfg: The configuration.

    Returns:
        Its fields by flat name (`task.<name>`, `dqn.<name>`), unset fields left out.
    """
    return flat_fields(to_dict(cfg), "configuration")


def to_dict(cfg: TrainConfig) -> dict[str, Any]:
    """A run's configuration as plain data, its `task` and `dqn` as tables.

    Args:
        cfg: The configuration.

    Returns:
        A TOML-ready dict (unset fields left out).
    """
    return plain(cfg)


def read_config(path: str | Path) -> dict[str, Any]:
    """The fields of a TOML file, flat ([`flat_fields()`][rainuav.rl.config.flat_fields]).

    Args:
        path: The file.

    Returns:
        The fields by flat name.

    Raises:
        InvalidInputError: A missing or malformed file, or unknown names (the file named).
    """
    return flat_fields(read_toml(path, "config file"), f"config file {path}")


def load_config(path: str | Path) -> TrainConfig:
    """A run's configuration from a TOML file (a run's `config.toml`): its fields over its preset's.

    Args:
        path: The file.

    Returns:
        The [`TrainConfig`][rainuav.rl.config.TrainConfig].

    Raises:
        InvalidInputError: A file that cannot be read, or fields out of range (named).
    """
    return resolve_config(read_config(path))
