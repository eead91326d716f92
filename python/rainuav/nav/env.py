"""Gymnasium environment: fly a UAV on a lattice over a SINR (or SIR) map to a destination.

Semantics (the planner and the tests rely on them; docs/physics.md section 6):

- Signal at a position: bilinear interpolation of the map (H, W) whose sample [i, j] sits at
  ``x = x_min + (j + 0.5) (x_max - x_min) / W``, ``y = y_min + (i + 0.5) (y_max - y_min) / H``;
  beyond the outermost centres the edge values hold. The map is a RadioMap's ``sinr_db``
  (``signal="sinr"``, default) or ``sir_db`` (``"sir"``, the paper's), or a raw array.
- Observation: position scaled to [0, 1]^2 (float32); where the signal changes in time (a
  [`rainuav.nav.field.SignalSeries`][rainuav.nav.field.SignalSeries]), a third entry, the moves so
  far over ``max_steps`` (the flight time over the horizon). Actions: 0 = +x, 1 = +y, 2 = -x, 3 =
  -y.
- Time: a move takes ``step_m / speed_m_s`` s and earns the signal at the new position and the
  instant it ends; every episode takes off at time 0 of the field.
- Moves and rewards: [`rainuav.nav.task`][rainuav.nav.task] (shortfall below ``min_db`` by default,
  ``goal_reward`` on arrival, ``out_of_bounds_penalty`` on leaving the area, truncated after
  ``max_steps``). ``min_db`` defaults to the map's own threshold (a preset's documented SINR
  threshold, ``RadioMap.default_min_db``), else 10 dB.
- ``info``: ``signal_db``, ``serving_cell`` (-1 where the map names none), ``position_m``,
  ``outage``, ``arrived`` and ``t_s`` (the flight time, s).
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
from rainuav.nav.field import SignalBank, SignalField, SignalSeries, blocked_at
from rainuav.nav.task import SIGNALS, LoiteringWarning, NavConfig, check_config, make_config
from rainuav.nav.views import WeatherView, sample_goal, sample_start_for

__all__ = ["DEFAULT_MIN_DB", "OBSERVATIONS", "UAVNavEnv", "check_action", "signal_field"]

OBSERVATIONS = ("position", "weather")
"""What the UAV observes: its position (and the time where the signal moves), or the weather around
it and over the area with its position, time and destination
([`rainuav.nav.views.WeatherView`][rainuav.nav.views.WeatherView])."""

DEFAULT_MIN_DB = 10.0
"""The outage threshold of a map that names none (the paper's minimum SIR), dB."""


def signal_field(
    radio_map: Any, sinr_db: Any, sir_db: Any, extent_m: Any, signal: str | None
) -> SignalField:
    """The field a task flies on: the ``signal`` map of ``radio_map``, or the one raw array
    given (``sinr_db`` or ``sir_db``, which then names the signal)."""
    if signal is not None and signal not in SIGNALS:
        raise InvalidInputError(f"signal must be one of {SIGNALS} (got {signal!r})")
    raw = {k: v for k, v in (("sinr", sinr_db), ("sir", sir_db)) if v is not None}
    if radio_map is not None:
        if raw:
            raise InvalidInputError(f"give radio_map or {next(iter(raw))}_db, not both")
        signal = signal or "sinr"
        values = getattr(radio_map, f"{signal}_db", None)
        if values is None:
            raise InvalidInputError(
                f"signal={signal!r}: radio_map has no {signal}_db (rebuild it with this version)"
            )
        serving = getattr(radio_map, "serving_cell", None)
        mask = getattr(radio_map, "not_flyable", None)
        return SignalField(values, radio_map.extent_m, f"{signal}_db", serving, mask)
    if len(raw) != 1:
        raise InvalidInputError("give radio_map, or exactly one of sinr_db and sir_db")
    kind, values = next(iter(raw.items()))
    if signal is not None and signal != kind:
        raise InvalidInputError(f"signal={signal!r} but the map given is {kind}_db")
    if extent_m is None:
        raise InvalidInputError(f"extent_m is required with {kind}_db")
    return SignalField(values, extent_m, f"{kind}_db")


def check_action(action: Any) -> int:
    """``action`` as an int if it is one integer in 0..3 (a Python or numpy integer, or a
    0-d integer array, as Gymnasium's ``Discrete(4)`` holds); anything else (a float such as
    1.7, a string, a bool) raises [`InvalidInputError`][rainuav.errors.InvalidInputError], never a
    silent rounding."""
    a = np.asarray(action) if isinstance(action, np.ndarray) else action
    if isinstance(a, np.ndarray):
        ok = a.shape == () and np.issubdtype(a.dtype, np.integer)
        a = a[()] if ok else a
    else:
        ok = isinstance(a, int | np.integer) and not isinstance(a, bool)
    if not ok or not 0 <= int(a) < 4:
        raise InvalidInputError(f"action must be one integer 0, 1, 2 or 3 (got {action!r})")
    return int(a)


class UAVNavEnv(gym.Env):
    """UAV navigation over a SINR or SIR map (registered as ``rainuav/UAVNav-v0``)."""

    metadata = {"render_modes": []}  # noqa: RUF012 - gymnasium's convention

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
        field: SignalField | SignalSeries | SignalBank | None = None,
        observation: str = "position",
        view: WeatherView | None = None,
        random_goal: bool = False,
        **task: Any,
    ) -> None:
        """A map (``radio_map``, one raw array with ``extent_m``, or a built ``field``: a signal in
        time, or a bank of worlds, one drawn per episode) and the task: a whole ``config``
        ([`NavConfig`][rainuav.nav.task.NavConfig]), its fields as keywords (``goal_m``,
        ``max_steps``, ...: over ``config``'s where both are given), and ``signal`` and ``min_db``
        (which win over both). ``observation``: [`OBSERVATIONS`][rainuav.nav.env.OBSERVATIONS]
        (``view`` sets the weather's grids); ``random_goal``: a destination per episode
        ([`rainuav.nav.views.sample_goal()`][rainuav.nav.views.sample_goal]; needs the weather
        observation, which shows it)."""
        super().__init__()
        cfg = make_config(config, **task)
        if radio_map is not None:
            signal = signal or cfg.signal
        if field is not None:
            if radio_map is not None or sinr_db is not None or sir_db is not None:
                raise InvalidInputError("give field or a map, not both")
            if not isinstance(field, SignalField | SignalSeries | SignalBank):
                kind = type(field).__name__
                raise InvalidInputError(
                    f"field must be a SignalField, SignalSeries or SignalBank (got {kind})"
                )
            self.field: SignalField | SignalSeries | SignalBank = field
        else:
            self.field = signal_field(radio_map, sinr_db, sir_db, extent_m, signal)
        kind = self.field.name.removesuffix("_db")
        if min_db is None:
            min_db = cfg.min_db
        if min_db is None:
            default = getattr(radio_map, "default_min_db", None)
            min_db = default(kind) if callable(default) else DEFAULT_MIN_DB
        self.cfg = dataclasses.replace(cfg, signal=kind, min_db=min_db)
        check_config(self.cfg, self.field.extent)
        if self.cfg.reward == "chance" and getattr(self.field, "outage_p", None) is None:
            raise InvalidInputError(
                "reward 'chance' needs one map with outage probabilities (field=SignalField(..., "
                "outage_p=P); rainuav.world.world_from builds it from a map corrected by "
                "measurements)"
            )
        if blocked_at(self.field, *self.cfg.goal_m):
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
        if random_goal and observation != "weather":
            raise InvalidInputError(
                "random_goal needs observation='weather' (the position alone does not show "
                "the destination)"
            )
        if isinstance(self.field, SignalBank) and observation != "weather":
            raise InvalidInputError("a bank of worlds needs observation='weather'")
        self.observation, self.random_goal = observation, bool(random_goal)
        self.view = (view or WeatherView()) if observation == "weather" else None
        self.stepper = BatchStepper(self.field, self.cfg)
        if self.view is not None:
            self.observation_space: gym.spaces.Space = self.view.space()
        else:
            dims = 3 if self.field.varies else 2
            self.observation_space = gym.spaces.Box(0.0, 1.0, shape=(dims,), dtype=np.float32)
        self.action_space = gym.spaces.Discrete(4)
        self._goal = np.asarray(self.cfg.goal_m, dtype=np.float64)[None]
        self._world = np.zeros(1, dtype=np.int64)
        self._start = np.zeros((1, 2))
        self._offset = np.zeros((1, 2), dtype=np.int64)
        self._t = np.zeros(1, dtype=np.int64)
        self._pos = np.zeros(2)
        self._ready = False  # reset() starts the first episode

    # -- many UAVs at once: the interface both environments share with the learner ---------
    altitudes_m: np.ndarray | None = None
    """The flight levels' altitudes, m (the altitude axis); None: the plane, one altitude."""

    def observe_batch(
        self, pos: Any, level: Any, t: Any, goal: Any = None, world: Any = None
    ) -> Any:
        """The observation of UAVs at ``pos`` (N, 2) after ``t`` (N,) moves (``level`` is 0 on
        the plane), heading for ``goal`` in the worlds ``world`` where the env shows the weather
        ([`observe()`][rainuav.nav.env.UAVNavEnv.observe])."""
        return self.observe(pos, t, goal, world)

    def step_batch(
        self, start: Any, offset: Any, level: Any, t: Any, action: Any, goal: Any = None,
        world: Any = None,
    ) -> dict[str, np.ndarray]:  # fmt: skip
        """One move of every UAV (the batched stepper's result, ``t`` the new clock, ``level``
        unchanged and ``duration`` 1 a move)."""
        r = self.stepper.step(start, offset, t, action, goal, world)
        r["level"] = np.asarray(level, dtype=np.int64)
        r["duration"] = np.ones(len(r["t"]), dtype=np.int64)
        return r

    def exploration_moves(self, level: Any) -> np.ndarray | None:
        """The moves an exploring UAV draws from: None, every move (the plane's four)."""
        return None

    def start_level_at(self, p: Any) -> int:
        """The level a flight from ``p`` takes off at: 0, the plane's one."""
        return 0

    # -- helpers ----------------------------------------------------------------------------
    def observe(self, pos: np.ndarray, t: Any = 0, goal: Any = None, world: Any = None) -> Any:
        """The observation at ``pos`` after ``t`` moves. Position observation: the position scaled
        to [0, 1]^2, float32 (works on (..., 2) arrays), and where the signal changes in time ``t``
        over ``max_steps``. Weather observation: the [`WeatherView`][rainuav.nav.views.WeatherView]
        dict for the destinations ``goal`` (N, 2; default the task's) and, in a bank, the ``world``
        (N,) each UAV flies; batched for (N, 2) positions, one for a (2,) position."""
        if self.view is not None:
            return self._weather(pos, t, goal, world)
        x0, x1, y0, y1 = self.field.extent
        lo = np.array([x0, y0])
        xy = ((np.asarray(pos) - lo) / np.array([x1 - x0, y1 - y0])).astype(np.float32)
        if not self.field.varies:
            return xy
        frac = np.asarray(t, dtype=np.float32) / np.float32(self.cfg.max_steps)
        frac = np.broadcast_to(frac, xy.shape[:-1])[..., None]
        return np.concatenate([xy, frac.astype(np.float32)], axis=-1)

    def _weather(self, pos: Any, t: Any, goal: Any, world: Any) -> dict[str, np.ndarray]:
        assert self.view is not None and self.cfg.min_db is not None
        p = np.asarray(pos, dtype=np.float64)
        one = p.ndim == 1
        p = p.reshape(-1, 2)
        t = np.broadcast_to(np.asarray(t), (len(p),))
        t_s = self.stepper.time_s(t)[:, None]
        w = np.broadcast_to(np.asarray(0 if world is None else world), (len(p),))[:, None]
        if isinstance(self.field, SignalBank):
            field = self.field

            def sample(x: np.ndarray, y: np.ndarray) -> np.ndarray:
                return field(x, y, t_s, w)
        else:

            def sample(x: np.ndarray, y: np.ndarray) -> np.ndarray:
                return self.field(x, y, t_s)

        grid = self.view.area_points(self.field.extent)
        area = self.field.at_points(grid, t_s[:, 0], w[:, 0])  # every slice sampled once
        g = self.cfg.goal_m if goal is None else goal
        frac = t.astype(np.float32) / np.float32(self.cfg.max_steps)
        obs = self.view.observe(sample, self.field.extent, p, frac, g, self.cfg.min_db, area)
        return {k: v[0] for k, v in obs.items()} if one else obs

    def sample_start(self, rng: np.random.Generator, goal: Any = None) -> np.ndarray:
        """Uniform in the area, farther than tol_m from the destination (``goal``, default
        the task's)."""
        x0, x1, y0, y1 = self.field.extent
        g = np.asarray(self.cfg.goal_m if goal is None else goal)
        for _ in range(100_000):
            p = np.array([rng.uniform(x0, x1), rng.uniform(y0, y1)])
            if np.hypot(*(p - g)) > self.cfg.tol_m and not blocked_at(self.field, *p):
                return p
        raise InvalidInputError(
            f"no flyable start farther than tol_m = {self.cfg.tol_m} m from the destination "
            f"in the area {self.field.extent}"
        )

    def draw_task(
        self, rng: np.random.Generator, goal: Any = None
    ) -> tuple[np.ndarray, np.ndarray, int]:
        """A new episode's (start, destination, world): the world uniform among a bank's (0
        otherwise), then the destination (``goal`` where given; drawn,
        [`sample_goal()`][rainuav.nav.views.sample_goal], where ``random_goal``; else the task's),
        then the start ([`sample_start()`][rainuav.nav.env.UAVNavEnv.sample_start], or within reach
        of a drawn destination)."""
        world = int(rng.integers(self.field.worlds)) if isinstance(self.field, SignalBank) else 0
        if goal is None and not self.random_goal:
            return self.sample_start(rng), np.asarray(self.cfg.goal_m, dtype=np.float64), world
        g = sample_goal(rng, self.field.extent) if goal is None else np.asarray(goal, float)
        return sample_start_for(rng, self.field.extent, g, self.cfg, self.field), g, world

    def signal(self, x: Any, y: Any, t_s: Any, world: Any = 0) -> Any:
        """The signal at ``(x, y)`` at ``t_s`` (in a bank, of world ``world``)."""
        if isinstance(self.field, SignalBank):
            return self.field(x, y, t_s, world)
        return self.field(x, y, t_s)

    @property
    def position_m(self) -> np.ndarray:
        return self._pos.copy()

    # -- gymnasium API ----------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Starts an episode at time 0 and returns the observation and ``info``.

        ``seed`` seeds the environment's generator (Gymnasium's rule: once, then it carries
        on). ``options``: ``start_m`` (x, y in metres, inside the area and flyable; default
        the task's ``start_m``, else a start drawn from the generator) and, with
        ``observation="weather"``, ``goal_m`` (a destination in place of the drawn one) and
        ``world`` (which storm of a bank). ``info`` holds ``signal_db`` at the start,
        ``serving_cell``, ``position_m``, ``outage``, ``arrived`` and ``t_s``."""
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
                world = self._world_option(opts["world"])
        self._start = p[None].copy()
        self._goal, self._world = goal[None].copy(), np.array([world], dtype=np.int64)
        self._offset = np.zeros((1, 2), dtype=np.int64)
        self._t = np.zeros(1, dtype=np.int64)
        self._pos = p.copy()
        self._ready = True
        obs = self.observe(p, 0, self._goal, self._world)
        return obs, self._info(float(self.signal(p[0], p[1], 0.0, world)))

    def _inside(self, name: str, value: Any) -> np.ndarray:
        p = as_real_array(name, value)
        x0, x1, y0, y1 = self.field.extent
        if p.shape != (2,) or not (x0 <= p[0] <= x1 and y0 <= p[1] <= y1):
            raise InvalidInputError(
                f"{name} must be (x, y) inside the area {self.field.extent} (got {value!r})"
            )
        if blocked_at(self.field, *p):
            raise InvalidInputError(
                f"{name} ({p[0]:g}, {p[1]:g}) lies where the UAV may not fly (terrain or "
                "obstacles within the clearance of the flight height)"
            )
        return p

    def _world_option(self, value: Any) -> int:
        n = self.field.worlds if isinstance(self.field, SignalBank) else 1
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or not 0 <= value < n:
            raise InvalidInputError(f"options['world'] must be an integer in 0..{n - 1}")
        return int(value)

    def _info(self, signal: float, arrived: bool = False) -> dict[str, Any]:
        assert self.cfg.min_db is not None  # resolved in __init__
        t_s = float(self.stepper.time_s(self._t)[0])
        serving = getattr(self.field, "serving_cell", None)
        info = {
            "signal_db": signal,
            "serving_cell": -1 if serving is None else int(serving(*self._pos, t_s)),
            "position_m": self._pos.copy(),
            "outage": bool(signal < self.cfg.min_db),
            "arrived": arrived,
            "t_s": t_s,
        }
        if self.view is not None:
            info["goal_m"] = self._goal[0].copy()
            info["world"] = int(self._world[0])
        return info

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """One move: ``action`` 0 = +x, 1 = +y, 2 = -x, 3 = -y (an integer). Returns
        ``(observation, reward, terminated, truncated, info)``: the reward of the task
        ([`rainuav.nav.task`][rainuav.nav.task]: -1 less the SINR shortfall where and when the
        move lands, the arrival reward, or the penalty for leaving the area or entering a pixel
        the UAV may not fly), ``terminated`` on arrival or leaving, ``truncated`` after
        ``max_steps`` moves; ``info`` as [`reset()`][rainuav.nav.env.UAVNavEnv.reset]'s."""
        a = check_action(action)
        if not self._ready:
            raise InvalidInputError("step() before reset(): call reset() to start an episode")
        if self.view is None:
            r = self.stepper.step(self._start, self._offset, self._t, np.array([a]))
        else:
            world = self._world if isinstance(self.field, SignalBank) else None
            r = self.stepper.step(
                self._start, self._offset, self._t, np.array([a]), self._goal, world
            )
        self._offset, self._t = r["offset"], r["t"]
        self._pos = r["position"][0].copy()
        signal = float(r["signal_db"][0])
        return (
            self.observe(self._pos, self._t[0], self._goal, self._world),
            float(r["reward"][0]),
            bool(r["terminated"][0]),
            bool(r["truncated"][0]),
            self._info(signal, bool(r["arrived"][0])),
        )
