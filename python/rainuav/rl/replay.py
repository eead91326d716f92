"""The replay of the DQN (the paper's Algorithm 1): the N-step sliding window and the replay
memory, in numpy ([`rainuav.rl.dqn`][rainuav.rl.dqn] learns from them)."""

from __future__ import annotations

from collections import deque
from typing import Any

import numpy as np

__all__ = ["NStepWindow", "Replay"]


class NStepWindow:
    """Algorithm 1's sliding window W of the last N1 transitions.

    ``push`` returns the transitions that leave the window, each as
    ``(obs, action, R, next_obs, discount, done)`` with ``R = sum_i gamma^i r_i`` over up to
    N1 rewards, ``next_obs`` the state to bootstrap from, ``discount = gamma^k`` (k rewards
    summed) and ``done`` whether the episode terminated (then there is no bootstrap). At an
    episode end the window flushes: terminated -> no bootstrap; truncated -> bootstrap from
    the last state.
    """

    def __init__(self, n: int, gamma: float) -> None:
        """An empty window.

        Args:
            n: N1, the rewards summed into one transition.
            gamma: The discount.

        Raises:
            ValueError: `n` below 1.
        """
        if n < 1:
            raise ValueError(f"n_step must be >= 1 (got {n})")
        self.n, self.gamma = n, gamma
        self.buf: deque[tuple[Any, int, float]] = deque()

    def _emit(self, next_obs: Any, done: bool) -> tuple[Any, int, float, Any, float, bool]:
        obs, a, _ = self.buf[0]
        ret = 0.0
        for i, (_, _, r) in enumerate(self.buf):
            ret += self.gamma**i * r
        disc = self.gamma ** len(self.buf)
        self.buf.popleft()
        return obs, a, ret, next_obs, disc, done

    def push(
        self,
        obs: Any,
        action: int,
        reward: float,
        next_obs: Any,
        terminated: bool,
        truncated: bool,
    ) -> list[tuple[Any, int, float, Any, float, bool]]:
        """Adds one move; returns the transitions that leave the window.

        At an episode's end the window flushes: terminated, no bootstrap; truncated, a bootstrap
        from the last state.

        Args:
            obs: The state moved from.
            action: The move.
            reward: Its reward.
            next_obs: The state moved to.
            terminated: The episode ended there (arrival, or leaving the area).
            truncated: The episode was cut there (the time limit).

        Returns:
            Each `(obs, action, R, next_obs, discount, done)`: `R = sum_i gamma^i r_i` over up to N1
            rewards, `next_obs` the state to bootstrap from, `discount = gamma^k` (k rewards
            summed), `done` whether the episode terminated.
        """
        self.buf.append((obs, action, reward))
        out = []
        if terminated or truncated:
            while self.buf:
                out.append(self._emit(next_obs, terminated))
        elif len(self.buf) == self.n:
            out.append(self._emit(next_obs, False))
        return out


class Replay:
    """Uniform replay memory of capacity C (a ring buffer)."""

    def __init__(self, capacity: int, obs_dim: int = 2) -> None:
        """An empty memory of fixed capacity.

        Args:
            capacity: The most transitions held (the oldest are overwritten).
            obs_dim: The network's input size.
        """
        self.capacity = capacity
        self.obs = np.zeros((capacity, obs_dim), np.float32)
        self.action = np.zeros(capacity, np.int64)
        self.ret = np.zeros(capacity, np.float32)
        self.next_obs = np.zeros((capacity, obs_dim), np.float32)
        self.discount = np.zeros(capacity, np.float32)
        self.done = np.zeros(capacity, np.float32)
        self.size = 0
        self.pos = 0

    def add(self, obs: Any, a: int, ret: float, next_obs: Any, disc: float, done: bool) -> None:
        """Stores one transition, overwriting the oldest once full.

        Args:
            obs: The state, the network's input.
            a: The move.
            ret: The n-step return.
            next_obs: The state to bootstrap from.
            disc: `gamma^k`.
            done: No bootstrap (the episode terminated).
        """
        i = self.pos
        self.obs[i], self.action[i], self.ret[i] = obs, a, ret
        self.next_obs[i], self.discount[i], self.done[i] = next_obs, disc, float(done)
        self.pos = (self.pos + 1) % self.capacity
        self.size = min(self.size + 1, self.capacity)

    def sample(self, rng: np.random.Generator, batch: int) -> dict[str, np.ndarray]:
        """A batch of stored transitions drawn uniformly, with replacement.

        Args:
            rng: The agent's generator.
            batch: How many.

        Returns:
            `obs`, `action`, `ret`, `next_obs`, `discount` and `done`, (batch, ...) each.
        """
        idx = rng.integers(0, self.size, size=batch)
        return {
            "obs": self.obs[idx],
            "action": self.action[idx],
            "ret": self.ret[idx],
            "next_obs": self.next_obs[idx],
            "discount": self.discount[idx],
            "done": self.done[idx],
        }

    _ARRAYS = ("obs", "action", "ret", "next_obs", "discount", "done")

    def state_dict(self) -> dict[str, Any]:
        """The memory's filled rows and counters, as a checkpoint saves them.

        The rows not yet filled are zeros and are not written: a short run's checkpoint holds what
        it collected, not the whole capacity.

        Returns:
            The arrays and `size`, `pos`.
        """
        n = self.size
        return {
            **{k: getattr(self, k)[:n].copy() for k in self._ARRAYS},
            "size": self.size,
            "pos": self.pos,
        }

    def load_state_dict(self, d: dict[str, Any]) -> None:
        """Restores a `state_dict()` (or the whole arrays, as older checkpoints hold them).

        A checkpoint is checked before it is trusted.

        Args:
            d: The saved state.

        Raises:
            ValueError: Arrays of another shape or type, or counters out of range.
        """
        size, pos = d["size"], d["pos"]
        if not all(isinstance(v, int | np.integer) for v in (size, pos)) or not (
            0 <= size <= self.capacity and 0 <= pos < self.capacity
        ):
            raise ValueError(f"replay size and pos must be integers in 0..{self.capacity}")
        for k in self._ARRAYS:
            mine, v = getattr(self, k), d[k]
            rows = {int(size), mine.shape[0]}
            if (
                not isinstance(v, np.ndarray)
                or v.dtype != mine.dtype
                or v.shape[1:] != mine.shape[1:]
                or v.shape[0] not in rows
            ):
                raise ValueError(
                    f"replay.{k} must be a {mine.dtype} array of {int(size)} or {mine.shape[0]} "
                    f"rows of shape {mine.shape[1:]}"
                )
        for k in self._ARRAYS:
            full = np.zeros_like(getattr(self, k))
            full[: len(d[k])] = d[k]
            setattr(self, k, full)
        self.size, self.pos = int(size), int(pos)
