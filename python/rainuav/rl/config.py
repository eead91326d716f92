"""What a training run depends on: the learner's hyperparameters
([`DQNConfig`][rainuav.rl.config.DQNConfig]) and the run's settings
([`TrainConfig`][rainuav.rl.config.TrainConfig]), their checks, their TOML form and the random
streams derived from the run's one seed."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rainuav._checks import check_field_kinds
from rainuav._io import plain, read_toml
from rainuav.errors import InvalidInputError
from rainuav.nav.task import NavConfig
from rainuav.world import WorldSpec, check_spec

__all__ = [
    "MAX_EXTENDS",
    "PRESET_DIR",
    "RENAMED",
    "RESUME_MAY_DIFFER",
    "SECTIONS",
    "DQNConfig",
    "TrainConfig",
    "check_config",
    "config_diff",
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
class DQNConfig:
    """Hyperparameters of the dueling double DQN (defaults: the paper's Table I where given)."""

    episodes: int = 3000
    """Training episodes (Table I)."""
    target_sync_episodes: int = 5
    """N_update: episodes between target-network syncs (Table I)."""
    eps0: float = 0.5
    """Initial exploration rate (Table I)."""
    eps_decay: float = 0.998
    """Per-episode decay of the exploration rate, eps0 * eps_decay^episode (Table I)."""
    replay_capacity: int = 100_000
    """Replay memory size C (Table I)."""
    batch_size: int = 16
    """Minibatch size B (Table I)."""
    gamma: float = 0.998
    """Discount factor."""
    n_step: int = 3
    """N1: length of the multi-step window."""
    lr: float = 1e-3
    """Adam learning rate at the start."""
    lr_final: float = 3e-5
    """Learning rate after the last episode (cosine decay from lr over the episodes; 0: a
    constant learning rate, lr throughout)."""
    average_from: float = 0.8
    """Fraction of the episodes after which the reported network is the running mean of the
    online weights, one sample per finished episode (weight averaging); 1: the final online
    network. Training itself is unchanged: the online network still acts and learns, and the
    run reports the last online network's figures beside the mean (``online_*``)."""
    hidden: int = 128
    """Width of the two hidden layers."""
    fourier: int = 8
    """Sine/cosine frequencies per input in the state features (0: none)."""
    reward_scale: float = 100.0
    """Rewards are divided by this inside the learner."""
    grad_clip: float = 10.0
    """Gradient-norm clip (0: none)."""
    loss: str = "huber"
    """TD loss: 'huber' (smooth L1) or 'mse' (the paper's squared error)."""
    learning_starts: int = 1000
    """Transitions stored before learning starts."""
    train_every: int = 4
    """Environment steps (transitions, summed over lanes) per gradient step."""
    lanes: int = 16
    """UAVs flown at once, each its own episode (1: the paper's one-at-a-time loop)."""
    time_aware: bool = False
    """Append t / max_steps to the observation and stop bootstrapping at the time limit."""
    goal_features: int = 4
    """Goal-relative inputs tanh(d / (step * 4^k)), k < goal_features, per axis (0: none)."""
    conv: int = 16
    """Channels of the first convolution of a weather-reading network (the second has twice
    as many)."""
    move_features: bool = False
    """A weather-reading network also reads, for each move, the destination's geometry after
    it (arrival, progress toward the destination), into its body and straight into the
    advantage head ([`rainuav.rl.networks.WeatherQNet`][rainuav.rl.networks.WeatherQNet])."""
    goal_maps: bool = False
    """A weather-reading network also sees the destination drawn on its grids: on the local window
    how much nearer each point is to it, on the whole area each cell's distance to it and to the UAV
    (extra input channels of the convolutions;
    [`rainuav.rl.networks.WeatherQNet.goal_channels()`][rainuav.rl.networks.WeatherQNet.goal_channels])."""
    goal_starts: float = 0.25
    """Fraction of the training episodes that start near the destination (uniform in the
    square of half side ``GOAL_START_MOVES`` moves around it, outside the arrival disc); the
    rest, and every validation and evaluation flight, start uniform in the area."""
    task_goals: float = 0.0
    """Where the env draws a destination per episode, the fraction of the training episodes
    flown to the task's own destination instead (a training mixture: validation and
    evaluation flights keep the env's draws)."""
    shaping: float = 1.0
    """Weight of the potential-based shaping -(steps to the goal); 0: the plain rewards."""
    sir_weight: float = 1.25
    """Factor on the SIR part of each reward (b + 1) inside the learner; 1: the env's rewards."""
    level_starts: float = 0.0
    """Among flight levels, the share of the training flights that take off at a level drawn
    uniformly among those flyable at the start (the rest, and every validation and evaluation
    flight, at the lowest flyable level)."""
    shield: bool = False
    """Also report greedy flights that keep to moves that stay in the area and can still
    arrive in max_steps, and avoid positions they already visited while they can
    (rainuav.nav.shield), as shielded_*; the headline stays the network alone."""


@dataclass
class TrainConfig(WorldSpec):
    """Everything a training run depends on: the world's spec
    ([`rainuav.world.WorldSpec`][rainuav.world.WorldSpec]: scenario, weather, task), the run's
    settings below and the learner's hyperparameters (``dqn``). One docstring line per field = one
    CLI flag."""

    preset: str = ""
    """The preset the run starts from: '' (the tuned defaults: docs/record/learning.md),
    a preset shipped with the package ('paper': Algorithm 1 and Table I literally; 'storms';
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
    """Raises InvalidInputError naming the first field of the wrong kind or outside its
    allowed range."""
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
    """The presets shipped with the package (``paper``, ``storms``, ``storm-levels``)."""
    return sorted(p.stem for p in PRESET_DIR.glob("*.toml"))


SECTIONS: dict[str, type] = {"task": NavConfig, "dqn": DQNConfig}
"""The tables of a run's fields (``[task]``, ``[dqn]`` in its file; ``task.NAME``, ``dqn.NAME``
flat and on the command line)."""
RENAMED = {"rain_rate": "rain_rate_mm_h", "altitudes": "altitudes_m"}
"""Fields read under their earlier names (run files and checkpoints written before the rename,
and the flags' short forms)."""


def _names(cls: type) -> set[str]:
    return {f.name for f in dataclasses.fields(cls)}


def field_name(key: str) -> str | None:
    """The flat name (``scenario``, ``task.max_steps``, ``dqn.lr``) that ``key`` names in any
    form [`flat_fields()`][rainuav.rl.config.flat_fields] reads: itself, a task field without
    its table (``max_steps``) or a [`RENAMED`][rainuav.rl.config.RENAMED] field; ``goal_x_m``
    and ``goal_y_m`` are parts of ``task.goal_m``. None: no field."""
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
    """The fields of a run's TOML table (``[task]`` and ``[dqn]`` sub-tables, or names already
    flat) as flat names (``scenario``, ``task.max_steps``, ``dqn.lr``). Earlier forms are read
    too ([`field_name()`][rainuav.rl.config.field_name]): the
    [`RENAMED`][rainuav.rl.config.RENAMED] fields, a task field at the top (``max_steps``) and
    the destination as ``goal_x_m`` / ``goal_y_m``. Unknown names, and a field given twice,
    raise InvalidInputError naming ``where``."""
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
    return out


MAX_EXTENDS = 100
"""The most presets one ``extends`` chain may link."""


def preset_fields(name_or_path: str | Path, _seen: tuple[str, ...] = ()) -> dict[str, Any]:
    """The fields a preset sets, flat (``"scenario"``, ``"dqn.lr"``): a shipped preset by name
    ([`preset_names()`][rainuav.rl.config.preset_names]) or a TOML file of the form of a run's
    ``config.toml`` (some fields only), which may start from another preset (``extends =
    "NAME"``, its own fields winning; a run's ``config.toml`` starts from the ``preset`` it
    records). An unknown name or a bad file raises InvalidInputError."""
    text = str(name_or_path)
    path = PRESET_DIR / f"{text}.toml" if text in preset_names() else Path(text)
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
    """The [dqn] fields a preset sets (names without ``dqn.``)."""
    return {k[4:]: v for k, v in preset_fields(name_or_path).items() if k.startswith("dqn.")}


def resolve_config(fields: dict[str, Any]) -> TrainConfig:
    """The run's configuration from flat ``fields`` (TrainConfig names, ``task.<name>`` and
    ``dqn.<name>`` for the task's and the learner's; the earlier forms that
    [`flat_fields()`][rainuav.rl.config.flat_fields] reads too): the defaults, then the preset
    that ``fields["preset"]`` names ([`preset_fields()`][rainuav.rl.config.preset_fields]),
    then ``fields`` themselves. The one place where a preset and overrides meet (the ``train``
    command, studies, a run's ``config.toml`` read back); the result records the preset's
    name."""
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
    """The fields of ``cfg`` flat (``task.<name>``, ``dqn.<name>``), as
    [`resolve_config()`][rainuav.rl.config.resolve_config] takes them (unset fields left
    out)."""
    return flat_fields(to_dict(cfg), "configuration")


def to_dict(cfg: TrainConfig) -> dict[str, Any]:
    """A plain dict of the run, its ``task`` and ``dqn`` as tables (TOML-ready: unset fields are
    left out)."""
    return plain(cfg)


def read_config(path: str | Path) -> dict[str, Any]:
    """The fields of a TOML file, flat ([`flat_fields()`][rainuav.rl.config.flat_fields]); a
    missing or malformed file and unknown names raise InvalidInputError naming the file."""
    return flat_fields(read_toml(path, "config file"), f"config file {path}")


def load_config(path: str | Path) -> TrainConfig:
    """A TrainConfig from a TOML file (a run's ``config.toml``): its fields over its preset's."""
    return resolve_config(read_config(path))


RESUME_MAY_DIFFER = ("device", "out", "time_budget_s")
"""Fields a resumed run may change (the rest must equal the checkpoint's): the device, the
folder's path (a run folder moved or copied elsewhere resumes where it now is; its results do
not depend on where it lives) and the wall-clock budget (a run its budget stopped, on a slower
machine, continues with a larger one to the episodes it was given, as if it had never
stopped)."""


def config_diff(saved: dict[str, Any], cfg: TrainConfig, ignore: tuple[str, ...] = ()) -> list[str]:
    """The fields (``task.x``, ``dqn.x`` for the task's and the learner's) where ``cfg`` differs
    from the ``saved`` dict of a run (in any form [`flat_fields()`][rainuav.rl.config.flat_fields]
    reads), as ``"name: saved -> given"``; ``ignore`` names fields allowed to differ."""

    def same_form(d: dict[str, Any]) -> dict[str, Any]:  # a point read back is a list
        return {k: tuple(v) if isinstance(v, list) else v for k, v in d.items()}

    old = same_form(flat_fields(saved, "saved configuration"))
    new = same_form(flat(cfg))
    return [
        f"{key}: {old.get(key)!r} -> {new.get(key)!r}"
        for key in sorted(set(old) | set(new))
        if key not in ignore and old.get(key) != new.get(key)
    ]


def random_streams(seed: int) -> dict[str, np.random.SeedSequence]:
    """Independent seed sequences for every random choice of a run, all from ``seed``
    (``SeedSequence.spawn``): ``"agent"`` (exploration and replay sampling) and ``"env"``
    (training starts). Seeding both generators with ``seed`` itself would make them draw the
    same stream."""
    agent, env = np.random.SeedSequence(seed).spawn(2)
    return {"agent": agent, "env": env}
