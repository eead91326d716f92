"""``python -m rainuav.train``: learn to fly from any start to the destination (the main job).

With no arguments: the paper preset at 25 mm/h (radio map built or taken from the cache),
Table I hyperparameters, seed 0. Writes to ``--out`` (default ``runs/paper``):
``config.toml``, ``radiomap.npz``, ``log.csv``, TensorBoard events, ``checkpoint.pt`` (every
``checkpoint_every`` finished episodes; after an interruption, ``--resume`` with the same
configuration continues from it and reproduces the uninterrupted run), and at the end
``metrics.json`` (greedy policy from ``eval_starts`` seeded starts against the exact
planner; with ``shield``, also the network's numbers without it), ``policy.pt`` (the
evaluated network's weights), ``returns.png`` (with the greedy policy's success and gap on
held-out validation starts during training), ``trajectories.png`` and ``stages.png``. Every
flag is a field of :class:`TrainConfig` or :class:`rainuav.agent.DQNConfig` (``--help`` lists
them).
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import itertools
import json
import math
import os
import random
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import tomli_w
import tomllib
import torch

from rainuav import plan as planner
from rainuav._io import write_atomic
from rainuav.agent import Agent, DQNConfig, NStepWindow, best_action
from rainuav.env import MOVES, NavConfig, UAVNavEnv, base_reward
from rainuav.errors import InvalidInputError

__all__ = ["TrainConfig", "evaluate", "main", "train"]


@dataclass
class TrainConfig:
    """Everything a training run depends on (one docstring line per field = one CLI flag)."""

    scenario: str = "paper"
    """Preset scenario ('paper' or 'urban'), unless --scenario-file is given."""
    scenario_file: str = ""
    """A scenario TOML file (overrides --scenario)."""
    rain_rate: float = 25.0
    """Homogeneous rain rate, mm/h (0: clear air); -1 keeps the scenario's own weather."""
    mu: float = 10.0 / 43.0
    """Weight of the SIR term in the reward."""
    reward: str = "shortfall"
    """Reward form: 'shortfall', 'outage' or 'linear'."""
    max_steps: int = 300
    """Steps per episode (Table I)."""
    goal_x_m: float = 1400.0
    """Destination, east coordinate, m."""
    goal_y_m: float = 1600.0
    """Destination, north coordinate, m."""
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
    keep_best: bool = False
    """Evaluate and save the network with the smallest validation gap, not the final one."""
    dqn: DQNConfig = field(default_factory=DQNConfig)
    """Agent hyperparameters."""


# -- config plumbing --------------------------------------------------------------------------
def _field_docs(cls: type) -> dict[str, str]:
    """Attribute docstrings of a dataclass (the string literal after each field)."""
    import ast
    import inspect
    import textwrap

    tree = ast.parse(textwrap.dedent(inspect.getsource(cls)))
    docs: dict[str, str] = {}
    body = tree.body[0].body  # type: ignore[attr-defined]
    for a, b in itertools.pairwise(body):
        if (
            isinstance(a, ast.AnnAssign)
            and isinstance(b, ast.Expr)
            and isinstance(b.value, ast.Constant)
        ):
            docs[a.target.id] = str(b.value.value)  # type: ignore[union-attr]
    return docs


def _parse_bool(text: str) -> bool:
    if text.lower() in ("1", "true", "yes", "on"):
        return True
    if text.lower() in ("0", "false", "no", "off"):
        return False
    raise argparse.ArgumentTypeError(f"expected true or false (got {text!r})")


def build_parser() -> argparse.ArgumentParser:
    """CLI flags generated from TrainConfig and DQNConfig."""
    ap = argparse.ArgumentParser(
        prog="python -m rainuav.train",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument("--config", type=Path, help="a TOML file of TrainConfig fields")
    ap.add_argument("--resume", action="store_true", help="continue from OUT/checkpoint.pt")
    for cls, prefix in ((TrainConfig, ""), (DQNConfig, "")):
        docs = _field_docs(cls)
        for f in dataclasses.fields(cls):
            if f.name == "dqn":
                continue
            typ = {int: int, float: float, str: str, bool: _parse_bool}.get(type(f.default), str)
            ap.add_argument(
                f"--{prefix}{f.name.replace('_', '-')}",
                dest=f.name,
                type=typ,
                default=None,
                help=f"{docs.get(f.name, '')} (default {f.default})",
            )
    return ap


def _read_config(path: Path) -> tuple[dict[str, Any], dict[str, Any]]:
    """The TrainConfig fields and the [dqn] fields of a TOML file; unknown names raise."""
    data = tomllib.loads(Path(path).read_text())
    dqn = dict(data.pop("dqn", {}))
    unknown = sorted(set(data) - {f.name for f in dataclasses.fields(TrainConfig)}) + sorted(
        f"dqn.{k}" for k in set(dqn) - {f.name for f in dataclasses.fields(DQNConfig)}
    )
    if unknown:
        raise InvalidInputError(f"{path}: unknown field(s) {unknown}")
    return data, dqn


def config_from_args(args: argparse.Namespace) -> TrainConfig:
    base: dict[str, Any] = {}
    dqn_kw: dict[str, Any] = {}
    if args.config is not None:
        base, dqn_kw = _read_config(args.config)
    dqn_names = {f.name for f in dataclasses.fields(DQNConfig)}
    top_names = {f.name for f in dataclasses.fields(TrainConfig)} - {"dqn"}
    for name in dqn_names:
        if getattr(args, name, None) is not None:
            dqn_kw[name] = getattr(args, name)
    for name in top_names:
        if getattr(args, name, None) is not None:
            base[name] = getattr(args, name)
    return TrainConfig(**base, dqn=DQNConfig(**dqn_kw))


def validate(cfg: TrainConfig) -> None:
    """Raises InvalidInputError naming the first field outside its allowed range."""
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
        ("lr_final", 0 < d.lr_final < math.inf, "> 0"),
        ("hidden", d.hidden >= 1, ">= 1"),
        ("fourier", d.fourier >= 0, ">= 0"),
        ("lanes", d.lanes >= 1, ">= 1"),
        ("goal_features", d.goal_features >= 0, ">= 0"),
        ("shaping", 0 <= d.shaping < math.inf, ">= 0 and finite"),
        ("sir_weight", 0 <= d.sir_weight < math.inf, ">= 0 and finite"),
        ("train_every", d.train_every >= 1, ">= 1"),
        ("learning_starts", d.learning_starts >= 0, ">= 0"),
        ("reward_scale", 0 < d.reward_scale < math.inf, "> 0"),
        ("grad_clip", 0 < d.grad_clip < math.inf, "> 0"),
        ("max_steps", cfg.max_steps >= 1, ">= 1"),
        ("eval_starts", cfg.eval_starts >= 1, ">= 1"),
        ("validate_every", cfg.validate_every >= 0, ">= 0"),
        ("validate_starts", cfg.validate_starts >= 1, ">= 1"),
        ("checkpoint_every", cfg.checkpoint_every >= 1, ">= 1"),
        ("device", cfg.device in ("auto", "cpu", "cuda"), "'auto', 'cpu' or 'cuda'"),
        ("rain_rate", cfg.rain_rate == -1 or 0 <= cfg.rain_rate <= 500, "-1 or in [0, 500]"),
    ]
    for name, ok, allowed in checks:
        if not ok:
            value = getattr(d, name) if hasattr(d, name) else getattr(cfg, name)
            raise InvalidInputError(f"{name} must be {allowed} (got {value!r})")


def to_dict(cfg: TrainConfig) -> dict[str, Any]:
    return dataclasses.asdict(cfg)


# -- environment ------------------------------------------------------------------------------
def make_scenario(cfg: TrainConfig) -> Any:
    from rainuav import scenarios
    from rainuav.scenario import Scenario

    if cfg.scenario_file:
        scn = Scenario.from_toml(cfg.scenario_file)
    else:
        if cfg.scenario not in scenarios.PRESETS:
            raise InvalidInputError(f"scenario must be one of {sorted(scenarios.PRESETS)}")
        scn = scenarios.PRESETS[cfg.scenario]()
    if cfg.rain_rate != -1:
        scn = scenarios.with_rain(scn, cfg.rain_rate)
    return scn


def make_env(cfg: TrainConfig, sir_db: np.ndarray, extent: Any) -> UAVNavEnv:
    nav = NavConfig(
        goal_m=(cfg.goal_x_m, cfg.goal_y_m), mu=cfg.mu, reward=cfg.reward, max_steps=cfg.max_steps
    )
    return UAVNavEnv(sir_db=sir_db, extent_m=extent, config=nav)


def make_agent(cfg: TrainConfig, env: UAVNavEnv, device: torch.device) -> Agent:
    """An agent for ``env``: the time limit, the destination and one move in observation
    units."""
    x0, x1, y0, y1 = env.field.extent
    s = env.cfg.step_m
    goal = tuple(env.observe(np.asarray(env.cfg.goal_m))[:2].tolist())
    return Agent(
        cfg.dqn, cfg.seed, device, cfg.max_steps, goal=goal, step=(s / (x1 - x0), s / (y1 - y0))
    )


def pick_device(name: str) -> torch.device:
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    if name == "cuda" and not torch.cuda.is_available():
        raise InvalidInputError("device 'cuda' requested but CUDA is not available")
    return torch.device(name)


def seed_everything(seed: int) -> None:
    random.seed(seed)
    torch.manual_seed(seed)
    torch.use_deterministic_algorithms(True, warn_only=True)


# -- evaluation -------------------------------------------------------------------------------
def unvisited_moves(offset: np.ndarray, visited: Sequence[set[tuple[int, int]]]) -> np.ndarray:
    """(N, 4) bool: the moves from lattice ``offset`` (N, 2) to an offset not in ``visited``,
    each flight's set of visited offsets."""
    steps = MOVES.tolist()
    return np.array(
        [
            [(ox + dx, oy + dy) not in seen for dx, dy in steps]
            for (ox, oy), seen in zip(offset.tolist(), visited, strict=True)
        ],
        dtype=bool,
    ).reshape(-1, 4)


def shield_moves(
    env: UAVNavEnv,
    pos: np.ndarray,
    t: np.ndarray,
    offset: np.ndarray,
    visited: Sequence[set[tuple[int, int]]],
) -> np.ndarray:
    """(N, 4) bool: the moves the shield allows. First the safe moves (still in the area and
    able to arrive within ``max_steps``, :meth:`rainuav.env.BatchStepper.safe_actions`); among
    them, the moves to a position the flight has not visited (``visited``: each flight's
    lattice offsets so far), where there is one. The second rule applies where every move
    costs at least 1 (``"shortfall"`` and ``"outage"`` with ``mu >= 0``, ``"linear"`` with
    ``mu <= 0``): cutting a loop out of a path then gains at least its length, so an optimal
    flight never revisits a position and the rule only removes moves no optimal flight makes.
    Elsewhere (the paper's ``"linear"`` with ``mu > 0``: loitering can pay) only the first
    rule applies."""
    allowed = env.stepper.safe_actions(pos, t)
    loops_can_pay = env.cfg.mu > 0 if env.cfg.reward == "linear" else env.cfg.mu < 0
    if loops_can_pay:
        return allowed
    fresh = allowed & unvisited_moves(offset, visited)
    return np.where(fresh.any(axis=1, keepdims=True), fresh, allowed)


def greedy_rollouts(
    agent: Agent, env: UAVNavEnv, starts: np.ndarray, shield: bool | None = None
) -> list[dict[str, Any]]:
    """Greedy episodes from every start at once (the batched stepper gives exactly the scalar
    environment's transitions), one dict per start: ``return``, ``steps``, ``path`` (T+1, 2),
    ``sir`` (T,), ``reached`` and ``overridden`` (moves where the shield replaced the
    network's choice). ``shield``: keep to the moves :func:`shield_moves` allows (default:
    ``agent.cfg.shield``)."""
    shield = agent.cfg.shield if shield is None else shield
    starts = np.asarray(starts, dtype=np.float64).reshape(-1, 2)
    n = len(starts)
    off = np.zeros((n, 2), dtype=np.int64)
    visited: list[set[tuple[int, int]]] = [{(0, 0)} for _ in range(n)]  # lattice offsets
    t = np.zeros(n, dtype=np.int64)
    live = np.ones(n, dtype=bool)
    ret = np.zeros(n)
    reached = np.zeros(n, dtype=bool)
    overridden = np.zeros(n, dtype=np.int64)
    paths: list[list[np.ndarray]] = [[s.copy()] for s in starts]
    sirs: list[list[float]] = [[] for _ in range(n)]
    while live.any():
        idx = np.flatnonzero(live)
        pos = starts[idx] + env.cfg.step_m * off[idx]
        q = agent.q_values(agent.observe(env.observe(pos), t[idx]))
        a = best_action(q)
        if shield:
            allowed = shield_moves(env, pos, t[idx], off[idx], [visited[k] for k in idx])
            free, a = a, best_action(q, allowed)
            overridden[idx] += a != free
        r = env.stepper.step(starts[idx], off[idx], t[idx], a)
        off[idx], t[idx] = r["offset"], r["t"]
        ret[idx] += r["reward"]
        for j, k in enumerate(idx):
            visited[k].add((int(off[k, 0]), int(off[k, 1])))
            paths[k].append(r["position"][j].copy())
            sirs[k].append(float(r["sir_db"][j]))
        end = r["terminated"] | r["truncated"]
        reached[idx[r["arrived"]]] = True
        live[idx[end]] = False
    return [
        {
            "return": float(ret[k]),
            "steps": int(t[k]),
            "path": np.array(paths[k]),
            "sir": np.array(sirs[k]),
            "reached": bool(reached[k]),
            "overridden": int(overridden[k]),
        }
        for k in range(n)
    ]


def eval_starts(env: UAVNavEnv, n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.array([env.sample_start(rng) for _ in range(n)], dtype=np.float64).reshape(-1, 2)


def relative_gap(optimum: np.ndarray, returns: np.ndarray) -> np.ndarray:
    """Per start, the share of the exact optimum's return the policy gave up."""
    return (optimum - returns) / np.maximum(np.abs(optimum), 1e-9)


def evaluate(agent: Agent, env: UAVNavEnv, starts: np.ndarray) -> tuple[dict[str, Any], list]:
    """Greedy policy from every start against the exact planner. With the shield on, also
    the share of flights it steered and the same network's numbers without it."""
    rolls = greedy_rollouts(agent, env, starts)
    plans = planner.optimal_many(env, starts)
    rets = np.array([r["return"] for r in rolls])
    opt = np.array([p.return_ for p in plans])
    gap = relative_gap(opt, rets)
    shielded: dict[str, Any] = {}
    if agent.cfg.shield:
        free = greedy_rollouts(agent, env, starts, shield=False)
        free_gap = relative_gap(opt, np.array([r["return"] for r in free]))
        shielded = {
            "shielded_flights": float(np.mean([r["overridden"] > 0 for r in rolls])),
            "unshielded_success_rate": float(np.mean([r["reached"] for r in free])),
            "unshielded_mean_gap_to_optimal": float(free_gap.mean()),
        }
    sirs = np.concatenate([r["sir"] for r in rolls])
    metrics = {
        "success_rate": float(np.mean([r["reached"] for r in rolls])),
        "mean_return": float(rets.mean()),
        "mean_steps": float(np.mean([r["steps"] for r in rolls])),
        "mean_sir_db": float(sirs.mean()),
        "outage_share": float(np.mean(sirs < env.cfg.sir_min_db)),
        "mean_gap_to_optimal": float(gap.mean()),
        "median_gap_to_optimal": float(np.median(gap)),
        "worst_gap_to_optimal": float(gap.max()),
        "optimal_mean_return": float(opt.mean()),
        "straight_line_mean_return": float(
            np.mean([planner.straight_line(env, s).return_ for s in starts])
        ),
        "eval_starts": len(starts),
        **shielded,
    }
    return metrics, rolls


# -- plots ------------------------------------------------------------------------------------
def plot_trajectories(env: UAVNavEnv, rolls: list, path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 5.4))
    x0, x1, y0, y1 = env.field.extent
    im = ax.imshow(
        env.field.sir_db, origin="lower", extent=(x0, x1, y0, y1), cmap="RdYlGn", vmin=-10, vmax=30
    )
    fig.colorbar(im, ax=ax, label="SIR [dB]")
    for r in rolls:
        ax.plot(r["path"][:, 0], r["path"][:, 1], "-", color="k", lw=0.8, alpha=0.7)
        ax.plot(r["path"][0, 0], r["path"][0, 1], "rx", ms=6)
    ax.plot(*env.cfg.goal_m, "b^", ms=10, label="destination")
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title)
    fig.tight_layout()
    write_atomic(path, lambda t: fig.savefig(t, dpi=110, format="png"))
    plt.close(fig)


def plot_returns(
    returns: list[float],
    path: Path,
    validation: Sequence[tuple[int, float, float]] = (),
    window: int = 50,
) -> None:
    """The training returns and their moving average; beside them, when given, the greedy
    policy's success and mean gap on the validation starts."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    r = np.asarray(returns)
    both = len(validation) > 0
    fig, axes = plt.subplots(1, 2 if both else 1, figsize=(11 if both else 6.4, 4), squeeze=False)
    ax = axes[0, 0]
    ax.plot(r, color="0.8", lw=0.5, label="episode return")
    if len(r) >= window:
        ma = np.convolve(r, np.ones(window) / window, mode="valid")
        ax.plot(np.arange(window - 1, len(r)), ma, "b", label=f"moving average ({window})")
    ax.set_xlabel("episode")
    ax.set_ylabel("return")
    ax.legend()
    if both:
        ep, success, gap = (np.array(v) for v in zip(*validation, strict=True))
        ax = axes[0, 1]
        ax.plot(ep, 100 * success, "g.-", label="success, %")
        ax.plot(ep, 100 * np.minimum(gap, 1.0), "r.-", label="mean gap to optimum, % (cut at 100)")
        ax.set_xlabel("episode")
        ax.set_ylim(0, 105)
        ax.set_title("greedy policy on the validation starts")
        ax.legend(loc="center right", fontsize="small")
    fig.tight_layout()
    write_atomic(path, lambda t: fig.savefig(t, dpi=110, format="png"))
    plt.close(fig)


def plot_stages(env: UAVNavEnv, stages: list[tuple[int, list]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = max(1, len(stages))
    fig, axs = plt.subplots(1, n, figsize=(3.6 * n, 3.6), squeeze=False)
    x0, x1, y0, y1 = env.field.extent
    for ax, (ep, rolls) in zip(axs[0], stages, strict=False):
        ax.imshow(
            env.field.sir_db,
            origin="lower",
            extent=(x0, x1, y0, y1),
            cmap="RdYlGn",
            vmin=-10,
            vmax=30,
        )
        for r in rolls:
            ax.plot(r["path"][:, 0], r["path"][:, 1], "k-", lw=0.8)
            ax.plot(r["path"][0, 0], r["path"][0, 1], "rx")
        ax.plot(*env.cfg.goal_m, "b^")
        ax.set_title(f"after {ep} episodes")
        ax.set_xticks([])
        ax.set_yticks([])
    fig.tight_layout()
    write_atomic(path, lambda t: fig.savefig(t, dpi=100, format="png"))
    plt.close(fig)


# -- training ---------------------------------------------------------------------------------
def _save_checkpoint(path: Path, state: dict[str, Any]) -> None:
    def write(tmp: Path) -> None:
        torch.save(state, tmp)

    write_atomic(path, write)


def learner_ends(d: DQNConfig, r: dict[str, np.ndarray]) -> np.ndarray:
    """Where the learner's episode ends (no bootstrap): arrival or leaving the area, and for
    a time-aware learner, which knows there are no moves left, also the time limit."""
    return r["terminated"] | (r["truncated"] & d.time_aware)


def learning_reward(
    env: UAVNavEnv, d: DQNConfig, pos: np.ndarray, r: dict[str, np.ndarray]
) -> np.ndarray:
    """The reward the learner stores for the moves ``pos -> r["position"]`` of a batch step.

    The env's reward with its SIR part ``b + 1`` weighted by ``sir_weight``, plus the
    potential-based shaping term (zero potential where :func:`learner_ends`). Discounting
    and the destination reward make the learner value time above the SIR: a move later
    costs ``(1 - gamma) gamma^k R_des`` of the destination reward on top of its -1, several
    times the undiscounted price of a move at gamma 0.998. Weighting the SIR part up
    restores the balance of the undiscounted return the policy is judged by; a position-only
    policy then loops from a few starts, which the shield breaks (1.25 by default; see
    :mod:`rainuav.agent`)."""
    reward = r["reward"]
    if d.sir_weight != 1.0:
        reward = reward + (d.sir_weight - 1.0) * (base_reward(r["sir_db"], env.cfg) + 1.0)
    return reward + shaping_term(env, d, pos, r["position"], learner_ends(d, r))


def shaping_term(
    env: UAVNavEnv, d: DQNConfig, pos: np.ndarray, new_pos: np.ndarray, ended: np.ndarray
) -> np.ndarray:
    """Potential-based shaping ``gamma Phi(s') - Phi(s)`` (Ng, Harada and Russell, ICML 1999).

    ``Phi(s) = shaping * V_straight(s)``: the discounted return of flying straight to the
    destination ignoring the SIR, ``-(1 - gamma^k) / (1 - gamma) + gamma^k R_des`` with ``k``
    the moves still needed (lattice distance minus the tolerance); ``Phi = 0`` where the
    learner's episode ends (``ended``): after arrival or leaving the area, and for a
    time-aware learner also at the time limit. Summed over an episode the terms telescope to
    ``-Phi(s_0)`` (a truncation the learner bootstraps through keeps ``gamma^T Phi(s_T)``,
    which its bootstrap value offsets), so the optimal policy is unchanged, while the
    learner now sees 0 for a move that keeps the straight-line pace and a clear loss for one
    that does not, instead of 2000 points at the end of a 300-move episode: it only has to
    learn how the SIR bends the straight route."""
    if d.shaping == 0.0:
        return np.zeros(len(pos))
    c = env.cfg
    goal = np.asarray(c.goal_m)

    def phi(p: np.ndarray) -> np.ndarray:
        k = np.maximum(np.abs(p - goal).sum(axis=1) - c.tol_m, 0.0) / c.step_m
        g = d.gamma**k
        steps = k if d.gamma == 1.0 else (1.0 - g) / (1.0 - d.gamma)
        return d.shaping * (-steps + g * c.goal_reward)

    return d.gamma * np.where(ended, 0.0, phi(new_pos)) - phi(pos)


@dataclass
class _Lanes:
    """The UAVs in flight: each lane runs one episode at a time (its own start, offset from
    the start in steps, step count, episode index, return so far and N-step window)."""

    start: np.ndarray
    offset: np.ndarray
    t: np.ndarray
    episode: np.ndarray
    ret: np.ndarray
    active: np.ndarray
    windows: list[NStepWindow]

    @classmethod
    def empty(cls, k: int, n_step: int, gamma: float) -> _Lanes:
        return cls(
            start=np.zeros((k, 2)),
            offset=np.zeros((k, 2), dtype=np.int64),
            t=np.zeros(k, dtype=np.int64),
            episode=np.zeros(k, dtype=np.int64),
            ret=np.zeros(k),
            active=np.zeros(k, dtype=bool),
            windows=[NStepWindow(n_step, gamma) for _ in range(k)],
        )

    def state_dict(self) -> dict[str, Any]:
        """Plain arrays and lists (a checkpoint must not pickle classes of ``__main__``)."""
        d: dict[str, Any] = {
            f.name: getattr(self, f.name).copy()
            for f in dataclasses.fields(self)
            if f.name != "windows"
        }
        d["windows"] = [list(w.buf) for w in self.windows]
        return d

    def load_state_dict(self, d: dict[str, Any]) -> None:
        for name, value in d.items():
            if name == "windows":
                for w, buf in zip(self.windows, value, strict=True):
                    w.buf.clear()
                    w.buf.extend(buf)
            else:
                setattr(self, name, value)

    def launch(self, k: int, start: np.ndarray, episode: int) -> None:
        self.start[k] = start
        self.offset[k] = 0
        self.t[k] = 0
        self.episode[k] = episode
        self.ret[k] = 0.0
        self.active[k] = True


@dataclass
class Validation:
    """Greedy checks during training: every ``validate_every`` finished episodes the greedy
    policy flies from held-out validation starts (never the evaluation starts), and the
    history of (episodes, success, mean gap to the optimum) and the online weights with the
    smallest gap are kept. With ``keep_best`` those weights are the run's result (early
    stopping); measured, that pays at a constant learning rate, whose greedy policy swings
    from check to check (final network 97% success and 21.5% mean gap, best-on-validation
    99.5% and 9.1%), but not with the default decay (seeds 0 / 1 / 2, mean gap of the final
    network 5.4 / 5.5 / 6.0%, of the best-on-validation one 5.8 / 5.5 / 7.5%: the last
    networks differ by less than 100 validation starts resolve)."""

    starts: np.ndarray
    optimum: np.ndarray
    best_gap: float = math.inf
    best_at: int = 0
    best_online: dict[str, torch.Tensor] | None = None
    history: list[tuple[int, float, float]] = field(default_factory=list)

    def check(self, agent: Agent, env: UAVNavEnv, finished: int) -> tuple[float, float]:
        """Flies the greedy policy from the validation starts; returns (success, mean gap)."""
        rolls = greedy_rollouts(agent, env, self.starts)
        rets = np.array([r["return"] for r in rolls])
        gap = float(np.mean(relative_gap(self.optimum, rets)))
        success = float(np.mean([r["reached"] for r in rolls]))
        self.history.append((finished, success, gap))
        if gap < self.best_gap:
            self.best_gap, self.best_at = gap, finished
            self.best_online = {
                k: v.detach().cpu().clone() for k, v in agent.online.state_dict().items()
            }
        return success, gap

    def state_dict(self) -> dict[str, Any]:
        return {
            "best_gap": self.best_gap,
            "best_at": self.best_at,
            "best_online": self.best_online,
            "history": list(self.history),
        }

    def load_state_dict(self, d: dict[str, Any]) -> None:
        self.best_gap, self.best_at = d["best_gap"], d["best_at"]
        self.best_online, self.history = d["best_online"], list(d["history"])


def train(
    cfg: TrainConfig,
    *,
    resume: bool = False,
    progress: bool = True,
    radio_map: Any = None,
    stop_after: int | None = None,
) -> dict[str, Any]:
    """Runs the whole job and returns the metrics. ``radio_map`` (a RadioMap) replaces the
    scenario's map (tests use small synthetic maps). ``stop_after`` ends the call, as an
    interruption would, at the first checkpoint with at least that many finished episodes
    (``resume=True`` then continues exactly); it returns ``{}``."""
    validate(cfg)
    out = Path(cfg.out)
    out.mkdir(parents=True, exist_ok=True)
    from rainuav.radiomap import RadioMap

    map_path = out / "radiomap.npz"
    if radio_map is not None:
        rm = radio_map
        rm.save(map_path)
    elif resume and map_path.exists():
        rm = RadioMap.load(map_path)
    else:
        rm = make_scenario(cfg).radio_map(cache=True, progress=progress)
        rm.save(map_path)
    write_atomic(out / "config.toml", lambda t: t.write_text(tomli_w.dumps(to_dict(cfg))))
    env = make_env(cfg, rm.sir_db, rm.extent_m)
    device = pick_device(cfg.device)
    if device.type == "cpu":
        # The networks are tiny: one thread is faster than two (no synchronisation) and
        # keeps CPU runs bit-reproducible.
        torch.set_num_threads(1)
    seed_everything(cfg.seed)
    agent = make_agent(cfg, env, device)
    env.reset(seed=cfg.seed)
    d = cfg.dqn
    lanes = _Lanes.empty(min(d.lanes, d.episodes), d.n_step, d.gamma)
    val_starts = eval_starts(
        env, cfg.validate_starts if cfg.validate_every else 0, cfg.eval_seed + 2
    )
    checks = Validation(
        val_starts, np.array([p.return_ for p in planner.optimal_many(env, val_starts)])
    )
    started, returns, successes, stages = 0, [], [], []
    train_seconds, pending = 0.0, 0  # pending: transitions not yet paid for by a gradient step
    ckpt = out / "checkpoint.pt"
    if resume:
        if not ckpt.exists():
            raise InvalidInputError(f"--resume: no checkpoint at {ckpt}")
        st = torch.load(ckpt, weights_only=False)
        agent.load_state_dict(st["agent"])
        env.np_random.bit_generator.state = st["env_rng"]
        lanes.load_state_dict(st["lanes"])
        started = st["started"]
        returns, successes = st["returns"], st["successes"]
        stages, train_seconds = st["stages"], st["train_seconds"]
        pending = st["pending"]
        checks.load_state_dict(st["validation"])
        random.setstate(st["py_rng"])
        torch.set_rng_state(st["torch_rng"])
    else:
        for k in range(len(lanes.t)):
            lanes.launch(k, env.sample_start(env.np_random), started)
            started += 1
    stage_every = max(1, d.episodes // max(cfg.stages, 1))
    stage_starts = eval_starts(env, 5, cfg.eval_seed + 1)
    from torch.utils.tensorboard import SummaryWriter

    tb = SummaryWriter(str(out / "tb"))
    log_path = out / "log.csv"
    new_log = not (resume and log_path.exists())
    log_fh = log_path.open("w" if new_log else "a", newline="")
    log = csv.writer(log_fh)
    if new_log:
        log.writerow(["finished", "episode", "return", "steps", "reached", "epsilon", "seconds"])
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=d.episodes, initial=len(returns), desc="train", unit="ep")
    t0 = time.perf_counter()
    step_m = env.cfg.step_m
    losses: list[float] = []
    stopped = False
    try:
        while lanes.active.any():
            idx = np.flatnonzero(lanes.active)
            pos = lanes.start[idx] + step_m * lanes.offset[idx]
            obs = agent.observe(env.observe(pos), lanes.t[idx])
            act = agent.act(obs, lanes.episode[idx])
            r = env.stepper.step(lanes.start[idx], lanes.offset[idx], lanes.t[idx], act)
            lanes.offset[idx], lanes.t[idx] = r["offset"], r["t"]
            lanes.ret[idx] += r["reward"]
            nobs = agent.observe(env.observe(r["position"]), r["t"])
            stop = learner_ends(d, r)
            learn_r = learning_reward(env, d, pos, r)
            for j, k in enumerate(idx):
                for tr in lanes.windows[k].push(
                    obs[j], int(act[j]), float(learn_r[j]), nobs[j], bool(stop[j]),
                    bool(r["truncated"][j]),
                ):  # fmt: skip
                    agent.replay.add(*tr)
            pending += len(idx)
            for _ in range(pending // d.train_every):
                loss = agent.learn()
                if loss is not None:
                    losses.append(loss)
            pending %= d.train_every
            finished_before = len(returns)
            for j in np.flatnonzero(r["terminated"] | r["truncated"]):
                k = idx[j]
                reached = bool(r["arrived"][j])
                returns.append(float(lanes.ret[k]))
                successes.append(reached)
                n_done = len(returns)
                eps = float(agent.epsilon(lanes.episode[k]))
                log.writerow(
                    [
                        n_done,
                        int(lanes.episode[k]),
                        f"{lanes.ret[k]:.4f}",
                        int(lanes.t[k]),
                        int(reached),
                        f"{eps:.5f}",
                        f"{time.perf_counter() - t0 + train_seconds:.2f}",
                    ]
                )
                tb.add_scalar("return", lanes.ret[k], n_done)
                tb.add_scalar("epsilon", eps, n_done)
                agent.anneal(n_done)
                if n_done % d.target_sync_episodes == 0:
                    agent.sync()
                if n_done % stage_every == 0:
                    # Greedy rollouts from given starts draw nothing from the training rng.
                    stages.append((n_done, greedy_rollouts(agent, env, stage_starts)))
                if cfg.validate_every and n_done % cfg.validate_every == 0:
                    success, gap = checks.check(agent, env, n_done)
                    tb.add_scalar("validation/success", success, n_done)
                    tb.add_scalar("validation/mean_gap", gap, n_done)
                if started < d.episodes:
                    lanes.launch(k, env.sample_start(env.np_random), started)
                    started += 1
                else:
                    lanes.active[k] = False
            n_done = len(returns)
            if n_done == finished_before:
                continue
            if losses:
                tb.add_scalar("loss", float(np.mean(losses)), n_done)
                losses.clear()
            if bar is not None:
                bar.set_postfix(
                    ret=f"{np.mean(returns[-100:]):.0f}",
                    success=f"{np.mean(successes[-100:]):.2f}",
                    eps=f"{agent.epsilon(started - 1):.3f}",
                )
                bar.update(n_done - finished_before)
            crossed = n_done // cfg.checkpoint_every > finished_before // cfg.checkpoint_every
            if crossed or n_done == d.episodes:
                log_fh.flush()
                _save_checkpoint(
                    ckpt,
                    {
                        "agent": agent.state_dict(),
                        "env_rng": env.np_random.bit_generator.state,
                        "lanes": lanes.state_dict(),
                        "started": started,
                        "returns": returns,
                        "successes": successes,
                        "stages": stages,
                        "pending": pending,
                        "validation": checks.state_dict(),
                        "train_seconds": time.perf_counter() - t0 + train_seconds,
                        "py_rng": random.getstate(),
                        "torch_rng": torch.get_rng_state(),
                        "config": to_dict(cfg),
                    },
                )
                if stop_after is not None and n_done >= stop_after and n_done < d.episodes:
                    stopped = True
                    break
    finally:
        if bar is not None:
            bar.close()
        log_fh.close()
        tb.close()
    if stopped:
        return {}
    train_seconds += time.perf_counter() - t0
    return finish(cfg, agent, env, returns, stages, train_seconds, out, checks)


def evaluate_run_policy(
    cfg: TrainConfig, agent: Agent, env: UAVNavEnv, checks: Validation
) -> tuple[dict[str, Any], list]:
    """Evaluates the run's policy from the evaluation starts: the final network, or with
    ``keep_best`` the best on validation (loaded into ``agent``; the final network's numbers
    are then added as ``final_*``)."""
    starts = eval_starts(env, cfg.eval_starts, cfg.eval_seed)
    metrics, rolls = evaluate(agent, env, starts)
    metrics["selected_at_episode"] = cfg.dqn.episodes
    if cfg.keep_best and checks.best_online is not None and checks.best_at != cfg.dqn.episodes:
        final = metrics
        agent.online.load_state_dict(checks.best_online)
        metrics, rolls = evaluate(agent, env, starts)
        metrics["selected_at_episode"] = checks.best_at
        for key in ("success_rate", "mean_return", "mean_gap_to_optimal", "worst_gap_to_optimal"):
            metrics[f"final_{key}"] = final[key]
    return metrics, rolls


def finish(
    cfg: TrainConfig,
    agent: Agent,
    env: UAVNavEnv,
    returns: list[float],
    stages: list,
    train_seconds: float,
    out: Path,
    checks: Validation,
) -> dict[str, Any]:
    """Evaluates the run (:func:`evaluate_run_policy`), saves the evaluated network's weights
    to ``policy.pt`` and writes ``metrics.json`` and the figures."""
    metrics, rolls = evaluate_run_policy(cfg, agent, env, checks)
    policy = {k: v.detach().cpu() for k, v in agent.online.state_dict().items()}
    _save_checkpoint(out / "policy.pt", {"online": policy, "config": to_dict(cfg)})
    metrics["training_seconds"] = train_seconds
    metrics["episodes"] = cfg.dqn.episodes
    metrics["device"] = str(agent.device)
    text = json.dumps(metrics, indent=2)
    write_atomic(out / "metrics.json", lambda t: t.write_text(text + "\n"))
    plot_returns(returns, out / "returns.png", checks.history)
    plot_trajectories(
        env,
        rolls[:40],
        out / "trajectories.png",
        f"greedy policy, success {100 * metrics['success_rate']:.0f}%",
    )
    if stages:
        plot_stages(env, stages, out / "stages.png")
    return metrics


def load_config(path: Path) -> TrainConfig:
    """A TrainConfig from a run's config.toml."""
    data, dqn = _read_config(path)
    return TrainConfig(**data, dqn=DQNConfig(**dqn))


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        cfg = config_from_args(args)
        metrics = train(cfg, resume=args.resume, progress=True)
    except InvalidInputError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    print(json.dumps(metrics, indent=2))
    print(f"wrote {Path(cfg.out).resolve()}")
    return 0


if __name__ == "__main__":
    os.environ.setdefault("MPLBACKEND", "Agg")
    sys.exit(main())
