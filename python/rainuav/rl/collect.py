"""Flying the agent: the UAVs in flight during training ([`Lanes`][rainuav.rl.collect.Lanes]),
batched greedy flights from given starts
([`greedy_rollouts()`][rainuav.rl.collect.greedy_rollouts]). Every flight goes through the
interface both environments share (``observe_batch``, ``step_batch``, ``exploration_moves``,
``start_level_at``): a UAV's state is its start, its offset in moves, its level (0 on one level)
and its clock ``t`` (moves on one level; ticks among levels,
[`rainuav.nav.levels`][rainuav.nav.levels])."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from rainuav.nav.env import UAVNavEnv
from rainuav.nav.shield import shield_moves
from rainuav.nav.training import positions
from rainuav.rl.dqn import Agent, NStepWindow, best_action
from rainuav.rl.setup import torch_settings

__all__ = ["Lanes", "greedy_rollouts"]


@dataclass
class Lanes:
    """The UAVs in flight: each lane runs one episode at a time (its own start, offset from
    the start in steps, clock (moves; ticks among levels), episode index, return so far,
    destination, world, level and N-step window)."""

    start: np.ndarray
    offset: np.ndarray
    t: np.ndarray
    episode: np.ndarray
    ret: np.ndarray
    active: np.ndarray
    goal: np.ndarray
    world: np.ndarray
    level: np.ndarray
    windows: list[NStepWindow]

    @classmethod
    def empty(cls, k: int, n_step: int, gamma: float) -> Lanes:
        """The lanes of `k` UAVs, none in flight.

        Args:
            k: How many lanes.
            n_step: The N-step windows' length.
            gamma: Their discount.

        Returns:
            The [`Lanes`][rainuav.rl.collect.Lanes].
        """
        return cls(
            start=np.zeros((k, 2)),
            offset=np.zeros((k, 2), dtype=np.int64),
            t=np.zeros(k, dtype=np.int64),
            episode=np.zeros(k, dtype=np.int64),
            ret=np.zeros(k),
            active=np.zeros(k, dtype=bool),
            goal=np.zeros((k, 2)),
            world=np.zeros(k, dtype=np.int64),
            level=np.zeros(k, dtype=np.int64),
            windows=[NStepWindow(n_step, gamma) for _ in range(k)],
        )

    def state_dict(self) -> dict[str, Any]:
        """The lanes as plain arrays and lists (a checkpoint must not pickle classes of `__main__`).

        Returns:
            The arrays by field, and each window's buffer.
        """
        d: dict[str, Any] = {
            f.name: getattr(self, f.name).copy()
            for f in dataclasses.fields(self)
            if f.name != "windows"
        }
        d["windows"] = [list(w.buf) for w in self.windows]
        return d

    def load_state_dict(self, d: dict[str, Any]) -> None:
        """Restores a `state_dict()` (a checkpoint from before levels has none: every lane on level
        0).

        Args:
            d: The saved state.

        Raises:
            ValueError: Arrays of another shape or type, or windows of another number.
        """
        d = {"level": np.zeros_like(self.level), **d}
        for f in dataclasses.fields(self):
            mine, v = getattr(self, f.name), d[f.name]
            if f.name == "windows":
                if not isinstance(v, list) or len(v) != len(mine):
                    raise ValueError(f"lanes.windows must be a list of {len(mine)}")
            elif not isinstance(v, np.ndarray) or v.shape != mine.shape or v.dtype != mine.dtype:
                raise ValueError(f"lanes.{f.name} must be a {mine.dtype} array of {mine.shape}")
        for name, value in d.items():
            if name == "windows":
                for w, buf in zip(self.windows, value, strict=True):
                    w.buf.clear()
                    w.buf.extend(buf)
            else:
                setattr(self, name, value)

    def launch(
        self, k: int, start: np.ndarray, episode: int, goal: np.ndarray, world: int = 0,
        level: int = 0,
    ) -> None:  # fmt: skip
        """Starts a new episode in a lane.

        Args:
            k: The lane.
            start: The start (2,), m.
            episode: The episode's index.
            goal: The destination (2,), m.
            world: The world of a bank.
            level: The level it takes off at.
        """
        self.start[k] = start
        self.level[k] = level
        self.goal[k] = goal
        self.world[k] = world
        self.offset[k] = 0
        self.t[k] = 0
        self.episode[k] = episode
        self.ret[k] = 0.0
        self.active[k] = True


def greedy_rollouts(
    agent: Agent,
    env: UAVNavEnv,
    starts: np.ndarray,
    shield: bool | None = None,
    goals: np.ndarray | None = None,
) -> list[dict[str, Any]]:
    """Greedy episodes from every start at once.

    The batched stepper gives exactly the scalar environment's transitions. Runs under training's
    torch settings (one CPU thread: the networks are tiny, and two threads beside another job spin
    for the core: 60 ms a one-UAV decision).

    Args:
        agent: The agent.
        env: The environment.
        starts: The starts (N, 2), m.
        shield: Keep to the moves [`shield_moves()`][rainuav.nav.shield.shield_moves] allows (the
            plane's); None: `agent.cfg.shield`.
        goals: Each flight's destination (N, 2); None: the task's.

    Returns:
        One dict a start: `return`, `steps`, `path` (T+1, 2), `levels` and `ticks` (T+1,: each
        point's level and clock; zeros and the move count on one level), `signal` (T,) along the
        path, `reached` and `overridden` (moves where the shield replaced the network's choice).
    """
    with torch_settings(agent.device):
        return _rollouts(agent, env, starts, agent.cfg.shield if shield is None else shield, goals)


def _rollouts(
    agent: Agent, env: UAVNavEnv, starts: np.ndarray, shield: bool, goals: np.ndarray | None
) -> list[dict[str, Any]]:
    starts = np.asarray(starts, dtype=np.float64).reshape(-1, 2)
    n = len(starts)
    goal = None if goals is None else np.asarray(goals, dtype=np.float64).reshape(n, 2)
    off = np.zeros((n, 2), dtype=np.int64)
    lv = np.array([env.start_level_at(s) for s in starts], dtype=np.int64)
    levels: list[list[int]] = [[int(v)] for v in lv]
    ticks: list[list[int]] = [[0] for _ in range(n)]
    visited: list[set[tuple[int, int]]] = [{(0, 0)} for _ in range(n)]  # lattice offsets
    t = np.zeros(n, dtype=np.int64)
    live = np.ones(n, dtype=bool)
    ret = np.zeros(n)
    reached = np.zeros(n, dtype=bool)
    overridden = np.zeros(n, dtype=np.int64)
    paths: list[list[np.ndarray]] = [[s.copy()] for s in starts]
    signal: list[list[float]] = [[] for _ in range(n)]
    shield = shield and env.terms().altitudes_m is None  # the shield is the plane's
    while live.any():
        idx = np.flatnonzero(live)
        pos = positions(env, starts[idx], off[idx])
        g = None if goal is None else goal[idx]
        q = agent.q_values(agent.observe(env.observe_batch(pos, lv[idx], t[idx], g), t[idx]))
        a = best_action(q)
        if shield:
            allowed = shield_moves(env, pos, t[idx], off[idx], [visited[k] for k in idx], g)
            free, a = a, best_action(q, allowed)
            overridden[idx] += a != free
        r = env.step_batch(starts[idx], off[idx], lv[idx], t[idx], a, g)
        off[idx], lv[idx], t[idx] = r["offset"], r["level"], r["t"]
        ret[idx] += r["reward"]
        for j, k in enumerate(idx):
            visited[k].add((int(off[k, 0]), int(off[k, 1])))
            paths[k].append(r["position"][j].copy())
            levels[k].append(int(lv[k]))
            ticks[k].append(int(t[k]))
            signal[k].append(float(r["signal_db"][j]))
        end = r["terminated"] | r["truncated"]
        reached[idx[r["arrived"]]] = True
        live[idx[end]] = False
    return [
        {
            "return": float(ret[k]),
            "steps": len(paths[k]) - 1,
            "path": np.array(paths[k]),
            "levels": np.array(levels[k], dtype=np.int64),
            "ticks": np.array(ticks[k], dtype=np.int64),
            "signal": np.array(signal[k]),
            "reached": bool(reached[k]),
            "overridden": int(overridden[k]),
        }
        for k in range(n)
    ]
