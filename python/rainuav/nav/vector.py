"""A Gymnasium vector environment over the batched stepper: ``num_envs`` UAVs on one map, each its
own episode, stepped by one call
([`rainuav.nav.batch.BatchStepper`][rainuav.nav.batch.BatchStepper]), with exactly the scalar
environment's transitions.

Autoreset (Gymnasium's ``metadata["autoreset_mode"]``): ``NEXT_STEP`` (Gymnasium's default, what
CleanRL expects): the step after a UAV's episode ends resets it, ignores its action and returns its
new start with reward 0; ``SAME_STEP``: the ending step already returns the new start, and the last
observation of the finished episode is ``info["final_obs"]``. ``gym.make_vec("rainuav/UAVNav-v0",
num_envs=N, vectorization_mode="vector_entry_point")`` builds one ([`rainuav.envs`][rainuav.envs]).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import numpy.typing as npt
from gymnasium.vector import AutoresetMode

from rainuav._checks import as_real_array, check_fits
from rainuav.errors import InvalidInputError
from rainuav.nav.env import UAVNavEnv

__all__ = ["UAVNavVectorEnv", "check_num_envs"]


BYTES_PER_ENV = 512
"""Memory one UAV of the vector env takes, bytes, rounded up: its state (start, offset, step,
flags: 41 bytes) and its share of a step's batched arrays (observation, reward, flags, infos
and the stepper's temporaries, about 300 bytes)."""


def check_num_envs(num_envs: Any) -> int:
    """The number of UAVs of a vector env, if it is allowed.

    Args:
        num_envs: The number asked for.

    Returns:
        `num_envs`, an integer >= 1 whose UAVs fit in memory.

    Raises:
        InvalidInputError: Not an integer >= 1, or UAVs that would not fit (the GB named; refused
            before any allocation).
    """
    if isinstance(num_envs, bool) or not isinstance(num_envs, (int, np.integer)):
        raise InvalidInputError(f"num_envs must be an integer >= 1 (got {num_envs!r})")
    if num_envs < 1:
        raise InvalidInputError(f"num_envs must be an integer >= 1 (got {num_envs!r})")
    check_fits(f"num_envs = {num_envs}", BYTES_PER_ENV * int(num_envs), "use fewer UAVs")
    return int(num_envs)


class UAVNavVectorEnv(gym.vector.VectorEnv):
    """``num_envs`` UAVs flying the task of ``env`` (a [`UAVNavEnv`][rainuav.nav.env.UAVNavEnv]: its
    map and task; its own state is not used), batched."""

    def __init__(
        self,
        env: UAVNavEnv,
        num_envs: int,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
    ) -> None:
        """Several UAVs in one world, stepped as one batch (Gymnasium's `VectorEnv`).

        Args:
            env: A [`UAVNavEnv`][rainuav.nav.env.UAVNavEnv] on one level, its task's fixed
                destination.
            num_envs: How many UAVs.
            autoreset_mode: Gymnasium's autoreset mode: "NextStep" or "SameStep".

        Raises:
            InvalidInputError: An env among levels or with random destinations, or another autoreset
                mode.
        """
        if not isinstance(env, UAVNavEnv) or env.level_axis:
            raise InvalidInputError(
                f"env must be a UAVNavEnv on one level (got {type(env).__name__})"
            )
        check_num_envs(num_envs)
        if env.random_goal:
            raise InvalidInputError(
                "random_goal: the vector env flies the task's fixed destination (use the scalar "
                "env, or the batched stepper with one destination per UAV)"
            )
        mode = AutoresetMode(autoreset_mode)
        if mode == AutoresetMode.DISABLED:
            raise InvalidInputError("autoreset_mode must be NEXT_STEP or SAME_STEP")
        self.env = env
        self.num_envs = int(num_envs)
        self.metadata = {"autoreset_mode": mode}
        self.single_observation_space = env.observation_space
        self.single_action_space = env.action_space
        self.observation_space = gym.vector.utils.batch_space(env.observation_space, num_envs)
        self.action_space = gym.vector.utils.batch_space(env.action_space, num_envs)
        n = self.num_envs
        self._start = np.zeros((n, 2))
        self._offset = np.zeros((n, 2), dtype=np.int64)
        self._t = np.zeros(n, dtype=np.int64)
        self._ended = np.zeros(n, dtype=bool)
        self._rng = np.random.default_rng()
        self._ready = False  # reset() starts the first episodes

    # -- helpers ----------------------------------------------------------------------------
    def _launch(self, mask: np.ndarray, options: dict[str, Any] | None = None) -> None:
        """New episodes for the UAVs in ``mask``: from ``options["start_m"]`` ((2,) or
        (num_envs, 2)), the task's fixed start, or uniform starts."""
        start = (options or {}).get("start_m", self.env.cfg.start_m)
        for k in np.flatnonzero(mask):
            if start is None:
                self._start[k] = self.env.sample_start(self._rng)
            else:
                s = np.asarray(start, dtype=np.float64)
                self._start[k] = s[k] if s.ndim == 2 else s
        self._offset[mask] = 0
        self._t[mask] = 0
        self._ended[mask] = False

    def _position(self) -> np.ndarray:
        return self._start + self.env.cfg.step_m * self._offset

    def _infos(self, signal: np.ndarray, arrived: np.ndarray) -> dict[str, Any]:
        pos = self._position()
        t_s = self.env.stepper.time_s(self._t)
        serving = self.env.field.serving_cell(pos[:, 0], pos[:, 1], t_s)
        assert self.env.cfg.min_db is not None  # resolved by UAVNavEnv
        out: dict[str, Any] = {
            "signal_db": signal,
            "serving_cell": serving,
            "position_m": pos,
            "outage": signal < self.env.cfg.min_db,
            "arrived": arrived,
            "t_s": t_s,
        }
        every = np.ones(self.num_envs, dtype=bool)
        return {**out, **{f"_{k}": every for k in out}}

    # -- gymnasium API ----------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Starts every UAV's episode.

        Args:
            seed: Seeds the UAVs' generator (once, then it carries on).
            options: `start_m`: one start (2,) or one a UAV (num_envs, 2), m.

        Returns:
            `(observations, info)`, batched.

        Raises:
            InvalidInputError: Options that are not a dict, or starts of the wrong shape.
        """
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        if options is not None and not isinstance(options, dict):
            raise InvalidInputError(f"options must be a dict (got {type(options).__name__})")
        if options and "start_m" in options:
            s = as_real_array("options['start_m']", options["start_m"])
            if s.shape not in ((2,), (self.num_envs, 2)) or not np.all(np.isfinite(s)):
                raise InvalidInputError(
                    f"options['start_m'] must be (2,) or ({self.num_envs}, 2) (got {s.shape})"
                )
        self._launch(np.ones(self.num_envs, dtype=bool), options)
        self._ready = True
        pos = self._position()
        signal = self.env.field(pos[:, 0], pos[:, 1], 0.0)
        obs = self.env.observe(pos, self._t)
        return obs, self._infos(signal, np.zeros(self.num_envs, dtype=bool))

    def step(
        self, actions: npt.ArrayLike
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """One move of every UAV; a finished episode restarts as the autoreset mode says.

        Args:
            actions: One move a UAV (num_envs,), integers in 0..3.

        Returns:
            `(observations, rewards, terminated, truncated, info)`, batched.

        Raises:
            InvalidInputError: `step()` before `reset()`, or actions of the wrong number or range.
        """
        a = np.asarray(actions)
        integers = np.issubdtype(a.dtype, np.integer)  # no silent rounding of 1.7 or 0.5
        if a.shape != (self.num_envs,) or not integers or not np.all((a >= 0) & (a < 4)):
            raise InvalidInputError(
                f"actions must be {self.num_envs} integers in 0..3 (got {a.dtype} "
                f"{a.shape}: {np.array2string(a.ravel()[:8], separator=', ')})"
            )
        if not self._ready:
            raise InvalidInputError("step() before reset(): call reset() to start the episodes")
        a = a.astype(np.int64)
        n = self.num_envs
        reward = np.zeros(n)
        terminated = np.zeros(n, dtype=bool)
        truncated = np.zeros(n, dtype=bool)
        arrived = np.zeros(n, dtype=bool)
        signal = np.zeros(n)
        resetting = self._ended.copy()  # NEXT_STEP: these only reset on this call
        moving = ~resetting
        if moving.any():
            t = self._t[moving]
            r = self.env.step_batch(
                self._start[moving], self._offset[moving], np.zeros_like(t), t, a[moving]
            )
            self._offset[moving], self._t[moving] = r["offset"], r["t"]
            reward[moving] = r["reward"]
            terminated[moving], truncated[moving] = r["terminated"], r["truncated"]
            arrived[moving] = r["arrived"]
            signal[moving] = r["signal_db"]  # at the (clamped) new position and instant
        ended = terminated | truncated
        pos = self._position()
        # A UAV that left the area sits at the clamped position (the scalar env's state).
        x0, x1, y0, y1 = self.env.field.extent
        pos = np.stack([np.clip(pos[:, 0], x0, x1), np.clip(pos[:, 1], y0, y1)], axis=1)
        obs = self.env.observe(pos, self._t)
        infos: dict[str, Any] = {}
        if self.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP:
            fresh = resetting
            self._launch(resetting)
            self._ended = ended
        else:  # SAME_STEP
            fresh = ended
            if ended.any():
                infos["final_obs"] = obs.copy()
                infos["_final_obs"] = ended.copy()
            self._launch(ended)
        if fresh.any():  # new episodes: their starts, at time 0
            pos = np.where(fresh[:, None], self._position(), pos)
            obs = self.env.observe(pos, self._t)
            signal[fresh] = self.env.field(pos[fresh, 0], pos[fresh, 1], 0.0)
        return obs, reward, terminated, truncated, {**self._infos(signal, arrived), **infos}
