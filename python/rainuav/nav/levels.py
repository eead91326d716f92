"""The navigation task in three dimensions: altitude as a decision.

The UAV flies on a stack of levels (one signal per flight altitude, lowest first; each a map
or maps in time, each with its not-flyable pixels) and has six moves: the plane's four on its
level ([`rainuav.nav.task`][rainuav.nav.task]) and a climb or a descent of one level.

- **Clock.** The flight's clock ticks once per horizontal move (``move_s`` seconds). A climb lasts
  the gap over ``climb_m_s`` and a descent the gap over ``descend_m_s``, rounded up to whole ticks
  ([`level_durations()`][rainuav.nav.levelfield.level_durations]; the defaults, 15 m gaps and 1 s
  moves: 3 and 5). A move lands at the tick its duration later and reads the signal there and then.
- **Rewards.** A move earns its duration in ticks times the base reward where and when it
  lands (``-1 - mu shortfall`` by default): the flight's cost is its time plus the weighted
  shortfall, each move weighted by how long it lasts. Leaving the area, climbing above the
  highest level or descending below the lowest, or entering a not-flyable cell of a level
  ends the flight with ``out_of_bounds_penalty`` (the UAV stays where it was, on its level,
  for a move out of the band). Arriving within ``tol_m`` of the destination's horizontal
  position, at any level, pays ``goal_reward`` (the landing is the autopilot's).
- **Horizon.** ``max_steps`` ticks: the flight is cut when its clock reaches it (one level:
  ``max_steps`` moves, the plane's task, same returns: tested).
- **Observation.** Position scaled to [0, 1]^2, the level over the highest level index (0 on
  one level), and where the signal moves the clock over ``max_steps``. ``info`` adds
  ``altitude_m`` and ``level`` to the plane's keys. With ``observation="weather"`` the
  [`WeatherView`][rainuav.nav.views.WeatherView] of every level (one layer a level: the signal now
  around the UAV and over the area), its position, destination, clock and level; then
  ``random_goal`` draws a destination per flight, and a field of banks (a storm pool among
  levels) a world per flight, as ``UAVNavEnv`` does.

The exact optimum of this task is
[`rainuav.nav.planner.optimal_levels()`][rainuav.nav.planner.optimal_levels]
(``rainuav_core::planlevels``), which reads the signal operation for operation as
[`LevelStepper`][rainuav.nav.levelfield.LevelStepper] does; its plans replayed here earn its returns
(tested)."""

from __future__ import annotations

import dataclasses
from typing import Any

import gymnasium as gym
import numpy as np

from rainuav._checks import as_real_array
from rainuav.errors import InvalidInputError
from rainuav.nav.env import DEFAULT_MIN_DB, OBSERVATIONS
from rainuav.nav.levelfield import (
    CLIMB_M_S,
    DESCEND_M_S,
    LEVEL_ACTIONS,
    LevelField,
    LevelStepper,
    level_durations,
)
from rainuav.nav.task import NavConfig, check_config
from rainuav.nav.views import WeatherView, sample_goal, sample_start_for

__all__ = [
    "CLIMB_M_S",
    "DESCEND_M_S",
    "LEVEL_ACTIONS",
    "LevelField",
    "LevelStepper",
    "UAVLevelsEnv",
    "level_durations",
]


class UAVLevelsEnv(gym.Env):
    """UAV navigation with altitude as a decision (module docstring): ``Discrete(6)``."""

    metadata = {"render_modes": []}  # noqa: RUF012 - gymnasium's convention

    def __init__(
        self,
        field: LevelField,
        config: NavConfig | None = None,
        *,
        climb_m_s: float = CLIMB_M_S,
        descend_m_s: float = DESCEND_M_S,
        start_level: int | None = None,
        observation: str = "position",
        view: WeatherView | None = None,
        random_goal: bool = False,
    ) -> None:
        """The levels' ``field`` and the task ``config`` (``min_db`` None: 10 dB or the
        caller's); ``start_level``: where every flight starts (default: the lowest level
        flyable at the start). ``observation``, ``view`` (its ``layers`` set to the levels)
        and ``random_goal`` as ``UAVNavEnv``'s."""
        super().__init__()
        if not isinstance(field, LevelField):
            raise InvalidInputError(f"field must be a LevelField (got {type(field).__name__})")
        cfg = config or NavConfig()
        self.cfg = dataclasses.replace(
            cfg, min_db=DEFAULT_MIN_DB if cfg.min_db is None else cfg.min_db
        )
        check_config(self.cfg, field.extent)
        if self.cfg.reward == "chance":
            raise InvalidInputError("reward 'chance' flies one map, not several levels")
        self.field = field
        self.climb, self.descend = level_durations(
            field.altitudes_m, self.cfg, climb_m_s, descend_m_s
        )
        self.climb_m_s, self.descend_m_s = float(climb_m_s), float(descend_m_s)
        if start_level is not None and not (
            isinstance(start_level, int | np.integer) and 0 <= start_level < field.levels
        ):
            raise InvalidInputError(
                f"start_level must be an integer in 0..{field.levels - 1} (got {start_level!r})"
            )
        self.start_level = start_level
        if observation not in OBSERVATIONS:
            raise InvalidInputError(
                f"observation must be one of {OBSERVATIONS} (got {observation!r})"
            )
        if observation != "weather" and (random_goal or field.banked):
            raise InvalidInputError(
                "random_goal and a bank of worlds need observation='weather' (the position "
                "alone does not show the destination or the storm)"
            )
        self.observation, self.random_goal = observation, bool(random_goal)
        self.view = None
        if observation == "weather":
            self.view = dataclasses.replace(view or WeatherView(), layers=field.levels)
        self.stepper = LevelStepper(field, self.cfg, self.climb, self.descend)
        if self.view is not None:
            self.observation_space: gym.spaces.Space = self.view.space()
        else:
            dims = 4 if field.varies else 3
            self.observation_space = gym.spaces.Box(0.0, 1.0, shape=(dims,), dtype=np.float32)
        self.action_space = gym.spaces.Discrete(LEVEL_ACTIONS)
        self._goal = np.asarray(self.cfg.goal_m, dtype=np.float64)[None]
        self._world = np.zeros(1, dtype=np.int64)
        self._start = np.zeros((1, 2))
        self._offset = np.zeros((1, 2), dtype=np.int64)
        self._level = np.zeros(1, dtype=np.int64)
        self._tick = np.zeros(1, dtype=np.int64)
        self._pos = np.zeros(2)
        self._ready = False

    def observe(
        self, pos: Any, level: Any, tick: Any = 0, goal: Any = None, world: Any = None
    ) -> Any:
        """Position scaled to [0, 1]^2, the level over the highest index, and where the
        signal moves the clock over ``max_steps`` (float32; works on batches). With the
        weather observation the view's dict for the destinations ``goal`` (N, 2; default the
        task's) and the worlds ``world`` (N,) of a field of banks."""
        if self.view is not None:
            return self._weather(pos, level, tick, goal, world)
        x0, x1, y0, y1 = self.field.extent
        p = np.asarray(pos, dtype=np.float64)
        xy = (p - np.array([x0, y0])) / np.array([x1 - x0, y1 - y0])
        top = max(self.field.levels - 1, 1)
        parts = [xy, (np.asarray(level, dtype=np.float64) / top)[..., None]]
        if self.field.varies:
            parts.append((np.asarray(tick, dtype=np.float64) / self.cfg.max_steps)[..., None])
        lead = np.broadcast_shapes(*(q.shape[:-1] for q in parts))
        return np.concatenate([np.broadcast_to(q, (*lead, q.shape[-1])) for q in parts], -1).astype(
            np.float32
        )

    def _weather(self, pos: Any, level: Any, tick: Any, goal: Any, world: Any) -> Any:
        assert self.view is not None and self.cfg.min_db is not None
        p = np.asarray(pos, dtype=np.float64)
        one = p.ndim == 1
        p = p.reshape(-1, 2)
        n = len(p)
        t_s = self.stepper.time_s(np.broadcast_to(np.asarray(tick), (n,)))[:, None]
        w = np.broadcast_to(np.asarray(0 if world is None else world), (n,))[:, None]
        field = self.field

        def sample(x: np.ndarray, y: np.ndarray) -> np.ndarray:
            return field.every_level(x, y, t_s, w)

        area = field.at_points(self.view.area_points(field.extent), t_s[:, 0], w[:, 0])
        g = self.cfg.goal_m if goal is None else goal
        frac = np.broadcast_to(np.asarray(tick), (n,)).astype(np.float32)
        frac /= np.float32(self.cfg.max_steps)
        top = max(field.levels - 1, 1)
        lv = np.broadcast_to(np.asarray(level, dtype=np.float32), (n,)) / np.float32(top)
        obs = self.view.observe(sample, field.extent, p, frac, g, self.cfg.min_db, area, lv)
        return {k: v[0] for k, v in obs.items()} if one else obs

    def draw_task(
        self, rng: np.random.Generator, goal: Any = None
    ) -> tuple[np.ndarray, np.ndarray, int]:
        """A new flight's (start, destination, world), as ``UAVNavEnv.draw_task`` draws them:
        the world uniform among a bank's, the destination (``goal``, drawn where
        ``random_goal``, else the task's), the start (flyable at some level)."""
        world = int(rng.integers(self.field.worlds)) if self.field.banked else 0
        if goal is None and not self.random_goal:
            return self.sample_start(rng), np.asarray(self.cfg.goal_m, dtype=np.float64), world
        g = sample_goal(rng, self.field.extent) if goal is None else np.asarray(goal, float)
        for _ in range(1000):
            p = sample_start_for(rng, self.field.extent, g, self.cfg)
            if self.field.flyable(*p).any():
                return p, g, world
        raise InvalidInputError(f"no flyable start within reach of the destination {tuple(g)}")

    def lowest_flyable(self, x: float, y: float) -> int:
        """The lowest level the UAV may fly at over ``(x, y)``."""
        ok = self.field.flyable(x, y)
        if not ok.any():
            raise InvalidInputError(f"({x:g}, {y:g}) is not flyable at any level")
        return int(np.flatnonzero(ok)[0])

    def sample_start(self, rng: np.random.Generator) -> np.ndarray:
        """Uniform in the area, farther than ``tol_m`` from the destination and flyable at
        some level."""
        x0, x1, y0, y1 = self.field.extent
        g = np.asarray(self.cfg.goal_m)
        for _ in range(100_000):
            p = np.array([rng.uniform(x0, x1), rng.uniform(y0, y1)])
            if np.hypot(*(p - g)) > self.cfg.tol_m and self.field.flyable(*p).any():
                return p
        raise InvalidInputError(
            f"no flyable start farther than tol_m = {self.cfg.tol_m} m "
            f"from the destination in the area {self.field.extent}"
        )

    @property
    def altitudes_m(self) -> np.ndarray:
        """The flight levels' altitudes, m, lowest first (the altitude axis)."""
        return self.field.altitudes_m

    def observe_batch(
        self, pos: Any, level: Any, t: Any, goal: Any = None, world: Any = None
    ) -> Any:
        """The observation of UAVs at ``pos`` (N, 2) on ``level`` (N,) at tick ``t`` (N,),
        heading for ``goal`` in the worlds ``world``
        ([`observe()`][rainuav.nav.levels.UAVLevelsEnv.observe])."""
        return self.observe(pos, level, t, goal, world)

    def step_batch(
        self, start: Any, offset: Any, level: Any, t: Any, action: Any, goal: Any = None,
        world: Any = None,
    ) -> dict[str, np.ndarray]:  # fmt: skip
        """One move of every UAV (the batched stepper's result, ``t`` the new clock in ticks)."""
        r = self.stepper.step(start, offset, level, t, action, goal, world)
        r["t"] = r.pop("tick")
        return r

    def exploration_moves(self, level: Any) -> np.ndarray | None:
        """(N, 6) bool: the moves an exploring UAV among levels draws from: every move but a
        climb from the highest level and a descent from the lowest (each would end the flight
        at once: random moves would end a sixth of the early flights at the lowest level, before
        they learn anything; the network's own choices are never restricted)."""
        level = np.asarray(level)
        ok = np.ones((len(level), 6), dtype=bool)
        ok[:, 4] = level < self.field.levels - 1
        ok[:, 5] = level > 0
        return ok

    def start_level_at(self, p: Any) -> int:
        """The level a flight from ``p`` starts at: ``start_level`` where given, else the
        lowest flyable there."""
        if self.start_level is not None:
            return int(self.start_level)
        return self.lowest_flyable(float(p[0]), float(p[1]))

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Starts an episode at time 0 and returns the observation and ``info``, as
        [`UAVNavEnv.reset()`][rainuav.nav.env.UAVNavEnv.reset] does; the start also has a
        level (``options["start_level"]``, an index into the altitudes, flyable at the start;
        default [`start_level_at()`][rainuav.nav.levels.UAVLevelsEnv.start_level_at])."""
        super().reset(seed=seed)
        opts = options or {}
        p = opts.get("start_m", self.cfg.start_m)
        goal, world = np.asarray(self.cfg.goal_m, dtype=np.float64), 0
        if self.view is not None:  # the destination and world of the flight, then its start
            given = opts.get("goal_m")
            if given is not None:
                given = self._inside("options['goal_m']", given)
            drawn, goal, world = self.draw_task(self.np_random, given)
            p = drawn if p is None else p
            if "world" in opts:
                world = self._world_option(opts["world"])
        elif opts.get("goal_m") is not None:
            raise InvalidInputError("options['goal_m'] needs observation='weather'")
        if p is None:
            p = self.sample_start(self.np_random)
        p = self._inside("options['start_m']", p)
        level = opts.get("start_level")
        if level is None:
            level = self.start_level_at(p)
        if not (isinstance(level, int | np.integer) and 0 <= level < self.field.levels):
            raise InvalidInputError(
                f"options['start_level'] must be an integer in 0..{self.field.levels - 1}"
            )
        if self.field.blocked(p[0], p[1], level):
            raise InvalidInputError(
                f"the start ({p[0]:g}, {p[1]:g}) is not flyable at level {level} "
                f"({self.field.altitudes_m[level]:g} m); the lowest it may be flown at is level "
                f"{self.lowest_flyable(p[0], p[1])}"
            )
        self._start = p[None].copy()
        self._offset = np.zeros((1, 2), dtype=np.int64)
        self._level = np.array([int(level)])
        self._tick = np.zeros(1, dtype=np.int64)
        self._goal, self._world = goal[None].copy(), np.array([int(world)], dtype=np.int64)
        self._pos = p.copy()
        self._ready = True
        signal = float(self.field(p[0], p[1], 0.0, int(level), int(world)))
        return self.observe(p, level, 0, self._goal, self._world), self._info(signal)

    def _inside(self, name: str, value: Any) -> np.ndarray:
        p = as_real_array(name, value)
        x0, x1, y0, y1 = self.field.extent
        if p.shape != (2,) or not (x0 <= p[0] <= x1 and y0 <= p[1] <= y1):
            raise InvalidInputError(f"{name} must be (x, y) inside the area (got {value!r})")
        return p

    def _world_option(self, value: Any) -> int:
        n = self.field.worlds
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or not 0 <= value < n:
            raise InvalidInputError(f"options['world'] must be an integer in 0..{n - 1}")
        return int(value)

    def _info(self, signal: float, arrived: bool = False) -> dict[str, Any]:
        assert self.cfg.min_db is not None
        t_s = float(self.stepper.time_s(self._tick)[0])
        lv = int(self._level[0])
        info = {
            "signal_db": signal,
            "serving_cell": int(self.field.serving_cell(self._pos[0], self._pos[1], t_s, lv)),
            "position_m": self._pos.copy(),
            "level": lv,
            "altitude_m": float(self.field.altitudes_m[lv]),
            "outage": bool(signal < self.cfg.min_db),
            "arrived": arrived,
            "t_s": t_s,
        }
        if self.view is not None:
            info["goal_m"] = self._goal[0].copy()
            info["world"] = int(self._world[0])
        return info

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """One move: the plane's four (0-3) or a climb (4) or descent (5) of one level, which lasts
        its duration in moves and earns that many times the move's reward. Returns ``(observation,
        reward, terminated, truncated, info)`` as
        [`UAVNavEnv.step()`][rainuav.nav.env.UAVNavEnv.step] does."""
        ok = isinstance(action, int | np.integer) and not isinstance(action, bool)
        if isinstance(action, np.ndarray) and action.shape == () and action.dtype.kind in "iu":
            action, ok = int(action), True
        if not ok or not 0 <= int(action) < LEVEL_ACTIONS:
            raise InvalidInputError(f"action must be one integer in 0..5 (got {action!r})")
        if not self._ready:
            raise InvalidInputError("step() before reset(): call reset() to start an episode")
        r = self.stepper.step(self._start, self._offset, self._level, self._tick,
                              np.array([int(action)]), self._goal, self._world)  # fmt: skip
        self._offset, self._level, self._tick = r["offset"], r["level"], r["tick"]
        self._pos = r["position"][0].copy()
        return (
            self.observe(self._pos, self._level[0], self._tick[0], self._goal, self._world),
            float(r["reward"][0]),
            bool(r["terminated"][0]),
            bool(r["truncated"][0]),
            self._info(float(r["signal_db"][0]), bool(r["arrived"][0])),
        )
