"""The Gymnasium environment: fly a UAV on a lattice over a SINR (or SIR) map to a destination, on
one flight level (four moves) or, given a field with flight levels (a
[`SignalField`][rainuav.nav.field.SignalField] with ``altitudes_m``), among them (six: a climb and a
descent besides; [`rainuav.nav.levels`][rainuav.nav.levels]). One class.

Its specification (spaces, reward, episode end, ids): [the guide's navigation
page][the-environments-specification]. Besides (the planner and the tests rely on them;
[physics reference, section 6][6-the-navigation-task]):

- Signal at a position: bilinear interpolation of the map (H, W) whose sample [i, j] sits at
  ``x = x_min + (j + 0.5) (x_max - x_min) / W``, ``y = y_min + (i + 0.5) (y_max - y_min) / H``;
  beyond the outermost centres the edge values hold. ``min_db`` defaults to the map's own
  threshold (``RadioMap.default_min_db``), else 10 dB.
- Time: a move takes ``step_m / speed_m_s`` s (a climb or descent its whole ticks) and earns the
  signal at the new position and the instant it ends; every episode takes off at time 0.
- Positions are kept as the start plus an integer number of steps in x and y, so every visited
  point lies exactly on the start's lattice (the exact planner's state space).

``gym.make("rainuav/UAVNav-v0", scenario="uma", rain_rate_mm_h=50)`` builds the map first
([`rainuav.envs`][rainuav.envs]); this class takes a map."""

from __future__ import annotations

import dataclasses
import warnings
from typing import Any

import gymnasium as gym
import numpy as np
import numpy.typing as npt

from rainuav._checks import as_real_array
from rainuav.errors import InvalidInputError
from rainuav.nav.batch import BatchStepper
from rainuav.nav.batched import BatchedFlights
from rainuav.nav.field import SignalField
from rainuav.nav.levelfield import (
    CLIMB_M_S,
    DESCEND_M_S,
    LEVEL_ACTIONS,
    LevelStepper,
    level_durations,
    signal_field,
)
from rainuav.nav.task import LoiteringWarning, NavConfig, check_action, check_config, make_config
from rainuav.nav.views import WeatherView

__all__ = ["DEFAULT_MIN_DB", "OBSERVATIONS", "UAVNavEnv", "check_action", "signal_field"]

OBSERVATIONS = ("position", "weather")
"""What the UAV observes: its position (and the time where the signal moves), or the weather around
it and over the area with its position, time and destination
([`rainuav.nav.views.WeatherView`][rainuav.nav.views.WeatherView])."""

DEFAULT_MIN_DB = 10.0
"""The outage threshold of a map that names none (the paper's minimum SIR), dB."""


def _index(name: str, value: Any, n: int) -> int:
    """``value`` as an index in ``0..n-1`` (an integer, not a bool), else one line naming it."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or not 0 <= value < n:
        raise InvalidInputError(f"{name} must be an integer in 0..{n - 1} (got {value!r})")
    return int(value)


class UAVNavEnv(BatchedFlights, gym.Env):
    """UAV navigation over a SINR or SIR map, on one level or among several.

    Registered as ``rainuav/UAVNav-v0`` (``Discrete(4)``) and, among flight levels, as
    ``rainuav/UAVLevels-v0`` (``Discrete(6)``). Its spaces, reward, starting state, episode end
    and ``info``: [the environment's specification][the-environments-specification] (the
    guide's navigation page). The moves are deterministic, so
    [`planner.optimal()`][rainuav.nav.planner.optimal] gives the exact optimum from any start.

    Examples:
        ```python
        from rainuav.nav import UAVNavEnv, planner
        from rainuav.radio import build_radio_map, presets

        env = UAVNavEnv(build_radio_map(presets.uma(engine="ray")), goal_m=(1400.0, 1600.0))
        obs, info = env.reset(seed=0)
        plan = planner.optimal(env, info["position_m"])
        print(len(plan.actions), "moves to the destination, return", round(plan.return_, 1))
        ```
    """

    metadata = {"render_modes": []}  # noqa: RUF012 - gymnasium's convention

    # Long: the environment's constructor checks and resolves every input in one place (a map, raw
    # arrays or a field; the task; the observation; the levels), as Gymnasium's environments do.
    def __init__(
        self,
        radio_map: Any = None,
        sinr_db: npt.ArrayLike | None = None,
        sir_db: npt.ArrayLike | None = None,
        extent_m: tuple[float, float, float, float] | None = None,
        *,
        signal: str | None = None,
        min_db: float | None = None,
        config: NavConfig | None = None,
        field: SignalField | None = None,
        observation: str = "position",
        view: WeatherView | None = None,
        random_goal: bool = False,
        climb_m_s: float = CLIMB_M_S,
        descend_m_s: float = DESCEND_M_S,
        start_level: int | None = None,
        **task: Any,
    ) -> None:
        """Builds the environment over a map and a task.

        Args:
            radio_map: A built map of any kind ([`RadioMap`][rainuav.radio.RadioMap], in time or of
                every level) or a [`Signal`][rainuav.signals.Signal], read through its
                `as_signal()`.
            sinr_db: A raw SINR array, dB, in place of a map (with ``extent_m``).
            sir_db: A raw SIR array, dB (with ``extent_m``).
            extent_m: ``(x_min, x_max, y_min, y_max)`` of a raw array, m.
            signal: ``"sinr"`` or ``"sir"``: the signal flown (wins over ``config``).
            min_db: The outage threshold, dB (wins over ``config``).
            config: The whole task ([`NavConfig`][rainuav.nav.task.NavConfig]).
            field: A built field in place of a map: a signal in time, a bank of worlds (one
                drawn per episode), or either among flight levels.
            observation: One of [`OBSERVATIONS`][rainuav.nav.env.OBSERVATIONS].
            view: The weather's grids ([`WeatherView`][rainuav.nav.views.WeatherView]).
            random_goal: A destination drawn per episode (the weather observation shows it).
            climb_m_s: The climb speed among levels, m/s.
            descend_m_s: The descent speed among levels, m/s.
            start_level: The level every flight starts at (default: the lowest flyable).
            **task: Fields of [`NavConfig`][rainuav.nav.task.NavConfig] (``goal_m``,
                ``max_steps``, ...), over ``config``'s where both are given.

        Raises:
            InvalidInputError: An input not allowed (the message names it).
        """
        super().__init__()
        cfg = make_config(config, **task)
        if radio_map is not None:
            signal = signal or cfg.signal
        if field is not None:
            if radio_map is not None or sinr_db is not None or sir_db is not None:
                raise InvalidInputError("give field or a map, not both")
            if not isinstance(field, SignalField):
                raise InvalidInputError(f"field must be a SignalField (got {type(field).__name__})")
            self.field: SignalField = field
        else:
            self.field = signal_field(radio_map, sinr_db, sir_db, extent_m, signal)
        self.level_axis = self.field.altitudes_m is not None  # altitude as a decision
        if min_db is None:
            min_db = cfg.min_db
        if self.level_axis:
            self.cfg = dataclasses.replace(cfg, min_db=DEFAULT_MIN_DB if min_db is None else min_db)
            if self.cfg.reward == "chance":
                raise InvalidInputError("reward 'chance' flies one map, not several levels")
            self.banked = self.field.banked
        else:
            kind = self.field.name.removesuffix("_db")
            if min_db is None:
                default = getattr(radio_map, "default_min_db", None)
                min_db = default(kind) if callable(default) else DEFAULT_MIN_DB
            self.cfg = dataclasses.replace(cfg, signal=kind, min_db=min_db)
            if self.cfg.reward == "chance" and getattr(self.field, "outage_p", None) is None:
                raise InvalidInputError(
                    "reward 'chance' needs one map with outage probabilities (field=SignalField("
                    "..., outage_p=P); rainuav.world.world_from builds it from a map corrected by "
                    "measurements)"
                )
            self.banked = self.field.banked
        check_config(self.cfg, self.field.extent)
        if not self.level_axis and self.field.blocked(*self.cfg.goal_m):
            raise InvalidInputError(
                f"goal_m {tuple(self.cfg.goal_m)} lies where the UAV may not fly (terrain or "
                "obstacles within the clearance of the flight height)"
            )
        if self.cfg.reward == "linear":
            warnings.warn(
                "reward='linear' (-1 + mu * 10^(S/10)) is positive near a base station: the "
                "UAV can earn more by loitering than by arriving",
                LoiteringWarning,
                stacklevel=2,
            )
        if observation not in OBSERVATIONS:
            raise InvalidInputError(
                f"observation must be one of {OBSERVATIONS} (got {observation!r})"
            )
        if observation != "weather" and (random_goal or self.banked):
            raise InvalidInputError(
                "random_goal and a bank of worlds need observation='weather' (the position "
                "alone does not show the destination or the storm)"
            )
        self.observation, self.random_goal = observation, bool(random_goal)
        if self.level_axis:
            self.climb, self.descend = level_durations(
                self.field.altitudes_m, self.cfg, climb_m_s, descend_m_s
            )
            self.stepper: LevelStepper = LevelStepper(
                self.field, self.cfg, self.climb, self.descend
            )
        else:
            self.climb, self.descend = [], []
            self.stepper = BatchStepper(self.field, self.cfg)
        self.climb_m_s, self.descend_m_s = float(climb_m_s), float(descend_m_s)
        self.levels = self.stepper.field.levels
        if start_level is not None:
            start_level = _index("start_level", start_level, self.levels)
        self.start_level = start_level
        self.view = None
        if observation == "weather":
            self.view = dataclasses.replace(view or WeatherView(), layers=self.levels)
        if self.view is not None:
            self.observation_space: gym.spaces.Space = self.view.space()
        else:
            dims = 2 + int(self.level_axis) + int(self.field.varies)
            self.observation_space = gym.spaces.Box(0.0, 1.0, shape=(dims,), dtype=np.float32)
        self.action_space = gym.spaces.Discrete(LEVEL_ACTIONS if self.level_axis else 4)
        self._goal = np.asarray(self.cfg.goal_m, dtype=np.float64)[None]
        self._world = np.zeros(1, dtype=np.int64)
        self._start = np.zeros((1, 2))
        self._offset = np.zeros((1, 2), dtype=np.int64)
        self._level = np.zeros(1, dtype=np.int64)
        self._t = np.zeros(1, dtype=np.int64)
        self._pos = np.zeros(2)
        self._ready = False  # reset() starts the first episode

    @property
    def altitudes_m(self) -> np.ndarray | None:
        """The flight levels' altitudes, m, lowest first (the altitude axis); None: one level."""
        return self.field.altitudes_m

    @property
    def position_m(self) -> np.ndarray:
        return self._pos.copy()

    # -- gymnasium API ----------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Starts an episode at time 0.

        Args:
            seed: Seeds the environment's generator (Gymnasium's rule: once, then it carries on).
            options: Optional keys: `start_m` (x, y in metres, inside the area and flyable; default
                the task's `start_m`, else a start drawn from the generator); among levels
                `start_level` (an index into the altitudes, flyable at the start; default
                [`start_level_at()`][rainuav.nav.batched.BatchedFlights.start_level_at]); with
                `observation="weather"`, `goal_m` (a destination in place of the drawn one) and
                `world` (which storm of a bank).

        Returns:
            `(observation, info)`; `info` holds `signal_db` at the start, `serving_cell`,
            `position_m`, among levels `level` and `altitude_m`, `outage`, `arrived` and `t_s`.

        Raises:
            InvalidInputError: Options that are not a dict, or a start, level or destination that is
                not allowed (named).
        """
        super().reset(seed=seed)
        if options is not None and not isinstance(options, dict):
            raise InvalidInputError(f"options must be a dict (got {type(options).__name__})")
        opts = options or {}
        p = opts.get("start_m", self.cfg.start_m)
        if p is not None:
            p = self._inside("options['start_m']", p)
        goal = opts.get("goal_m")
        if goal is not None:
            goal = self._inside("options['goal_m']", goal)
        if self.view is None:
            if goal is not None:
                raise InvalidInputError("options['goal_m'] needs observation='weather'")
            p = self.sample_start(self.np_random) if p is None else p
            goal, world = np.asarray(self.cfg.goal_m, dtype=np.float64), 0
        else:
            drawn, goal, world = self.draw_task(self.np_random, goal)
            p = drawn if p is None else p
            if "world" in opts:
                world = _index(
                    "options['world']", opts["world"], self.field.worlds if self.banked else 1
                )
        level = opts.get("start_level")
        if level is None:
            level = self.start_level_at(p)
        level = _index("options['start_level']", level, self.levels)
        if self.level_axis and self.field.blocked(p[0], p[1], level):
            raise InvalidInputError(
                f"the start ({p[0]:g}, {p[1]:g}) is not flyable at level {level} "
                f"({self.field.altitudes_m[level]:g} m); the lowest it may be flown at is level "
                f"{self.lowest_flyable(p[0], p[1])}"
            )
        self._start = p[None].copy()
        self._goal, self._world = goal[None].copy(), np.array([int(world)], dtype=np.int64)
        self._offset = np.zeros((1, 2), dtype=np.int64)
        self._level = np.array([int(level)], dtype=np.int64)
        self._t = np.zeros(1, dtype=np.int64)
        self._pos = p.copy()
        self._ready = True
        obs = self.observe_batch(p, level, 0, self._goal, self._world)
        return obs, self._info(float(self.signal(p[0], p[1], 0.0, int(world), int(level))))

    def _inside(self, name: str, value: Any) -> np.ndarray:
        """``value`` as a point inside the area and, on one level, in a pixel it may fly."""
        p = as_real_array(name, value)
        x0, x1, y0, y1 = self.field.extent
        if p.shape != (2,) or not (x0 <= p[0] <= x1 and y0 <= p[1] <= y1):
            raise InvalidInputError(
                f"{name} must be (x, y) inside the area {self.field.extent} (got {value!r})"
            )
        if not self.level_axis and self.field.blocked(*p):
            raise InvalidInputError(
                f"{name} ({p[0]:g}, {p[1]:g}) lies where the UAV may not fly (terrain or "
                "obstacles within the clearance of the flight height)"
            )
        return p

    def _info(self, signal: float, arrived: bool = False) -> dict[str, Any]:
        assert self.cfg.min_db is not None  # resolved in __init__
        t_s = float(self.stepper.time_s(self._t)[0])
        x, y = self._pos
        lv = int(self._level[0])
        serving = int(self.field.serving_cell(x, y, t_s, lv))
        info: dict[str, Any] = {
            "signal_db": signal,
            "serving_cell": serving,
            "position_m": self._pos.copy(),
        }
        if self.level_axis:
            info["level"] = lv
            info["altitude_m"] = float(self.field.altitudes_m[lv])
        info.update(outage=bool(signal < self.cfg.min_db), arrived=arrived, t_s=t_s)
        if self.view is not None:
            info["goal_m"] = self._goal[0].copy()
            info["world"] = int(self._world[0])
        return info

    def step(self, action: npt.ArrayLike) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """One move.

        Args:
            action: An integer move ([the specification][the-environments-specification]: 0 east, 1
                north, 2 west, 3 south; among levels 4 climbs and 5 descends).

        Returns:
            `(observation, reward, terminated, truncated, info)`, `info` as
            [`reset()`][rainuav.nav.env.UAVNavEnv.reset]'s.

        Raises:
            InvalidInputError: `step()` before `reset()`, or an action outside the action space.
        """
        a = check_action(action, int(self.action_space.n))
        if not self._ready:
            raise InvalidInputError("step() before reset(): call reset() to start an episode")
        r = self.step_batch(self._start, self._offset, self._level, self._t, np.array([a]),
                            self._goal, self._world)  # fmt: skip
        self._offset, self._level, self._t = r["offset"], r["level"], r["t"]
        self._pos = r["position"][0].copy()
        return (
            self.observe_batch(self._pos, self._level[0], self._t[0], self._goal, self._world),
            float(r["reward"][0]),
            bool(r["terminated"][0]),
            bool(r["truncated"][0]),
            self._info(float(r["signal_db"][0]), bool(r["arrived"][0])),
        )
