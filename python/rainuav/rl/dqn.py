"""The dueling double DQN with multi-step returns (the paper's Algorithm 1), in torch.

Reads top to bottom: the network, the N-step sliding window, the replay memory, the double-Q target
and the agent (observe, act, learn, sync). Hyperparameters:
[`DQNConfig`][rainuav.rl.config.DQNConfig]. Every choice beyond the paper's Table I, and what it
measured, is in ``docs/guide/learning.md``."""

from __future__ import annotations

import functools
import math
from collections import deque
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
import torch
from torch import nn

from rainuav.nav.views import WeatherView
from rainuav.rl.config import DQNConfig, random_streams
from rainuav.rl.networks import MoveGeometry, PositionEncoder, WeatherEncoder

Encoder = PositionEncoder | WeatherEncoder
"""How an env's observation becomes the network's input, and the network
([`rainuav.rl.networks`][rainuav.rl.networks])."""

__all__ = ["Agent", "Encoder", "NStepWindow", "Replay", "best_action", "double_q_target"]


def best_action(q: np.ndarray, allowed: np.ndarray | None = None) -> np.ndarray:
    """Argmax of the (N, A) values ``q``, among the ``allowed`` (N, A) actions when given."""
    if allowed is not None:
        q = np.where(allowed, q, -np.inf)
    return q.argmax(axis=1)


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
        i = self.pos
        self.obs[i], self.action[i], self.ret[i] = obs, a, ret
        self.next_obs[i], self.discount[i], self.done[i] = next_obs, disc, float(done)
        self.pos = (self.pos + 1) % self.capacity
        self.size = min(self.size + 1, self.capacity)

    def sample(self, rng: np.random.Generator, batch: int) -> dict[str, np.ndarray]:
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
        """The memory's filled rows and counters, as a checkpoint saves them (the rows not yet
        filled are zeros and are not written: a short run's checkpoint holds what it collected,
        not the whole capacity)."""
        n = self.size
        return {
            **{k: getattr(self, k)[:n].copy() for k in self._ARRAYS},
            "size": self.size,
            "pos": self.pos,
        }

    def load_state_dict(self, d: dict[str, Any]) -> None:
        """Restores a [`state_dict()`][rainuav.rl.dqn.Replay.state_dict] (or the whole arrays, as
        older checkpoints hold them); arrays of another shape or type, or counters out of range,
        raise ValueError (a checkpoint is checked before it is trusted)."""
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


def double_q_target(
    q_next_online: torch.Tensor,
    q_next_target: torch.Tensor,
    ret: torch.Tensor,
    discount: torch.Tensor,
    done: torch.Tensor,
) -> torch.Tensor:
    """Double-Q target ``R + gamma^k (1 - done) Q_target(s', argmax_a Q_online(s', a))`` from
    the two networks' Q-values at s' (B, A)."""
    a_star = q_next_online.argmax(dim=1, keepdim=True)
    return ret + discount * (1.0 - done) * q_next_target.gather(1, a_star).squeeze(1)


def memory_needed(
    cfg: DQNConfig, view: WeatherView | None = None, levels: bool = False
) -> dict[str, int]:
    """Bytes the agent of ``cfg`` allocates, by the field that sets them: ``hidden`` (the
    float32 weights of the network, seven times over: online, target, gradients, Adam's two
    moments, the weight average and a copy while reporting) and ``replay_capacity`` (the
    replay's arrays). ``levels``: altitude as a decision (the level an input, six actions);
    ``view``: the weather observation where the env gives it (its network
    is built on the CPU to count its weights, a few ms). Computed from the sizes, so a run
    that cannot fit is refused before anything is built."""
    h = cfg.hidden
    if view is None:
        n_smooth = (3 if cfg.time_aware else 2) + int(levels)
        obs_dim = n_smooth + 2 * cfg.goal_features
        d_in = obs_dim + n_smooth * 2 * cfg.fourier
        params = d_in * h + h + h * h + h + (h + 1) + (6 if levels else 4) * (h + 1)
    else:
        geometry = MoveGeometry((1.0, 1.0), 1.0, 1.0)
        enc = WeatherEncoder(cfg, view, (1.0, 1.0), geometry, 6 if levels else 4)
        obs_dim = enc.dim
        params = sum(p.numel() for p in enc.make_net().parameters())
    return {
        "dqn.hidden": 7 * 4 * params,
        "dqn.replay_capacity": cfg.replay_capacity * (2 * 4 * obs_dim + 8 + 3 * 4),
    }


class Agent:
    """Online and target networks, replay, optimiser and the exploration schedule."""

    def __init__(self, cfg: DQNConfig, seed: int, device: torch.device, encoder: Encoder) -> None:
        """``seed``: the run's seed (the network's initial weights; exploration and replay sampling
        draw from its ``"agent"`` stream,
        [`rainuav.rl.config.random_streams()`][rainuav.rl.config.random_streams]); ``encoder``: how
        the env's observations become the network's input, and the network
        ([`rainuav.rl.networks`][rainuav.rl.networks])."""
        self.cfg = cfg
        self.device = device
        self.encoder = encoder
        self.obs_dim = encoder.dim
        self.n_actions = encoder.n_actions
        torch.manual_seed(seed)
        self.online = encoder.make_net().to(device)
        self.target = encoder.make_net().to(device)
        self.target.load_state_dict(self.online.state_dict())
        self.replay = Replay(cfg.replay_capacity, self.obs_dim)
        self.rng = np.random.default_rng(random_streams(seed)["agent"])
        self.updates = 0
        # Running mean of the online weights (``average_from``): the reported network.
        self.average: dict[str, torch.Tensor] | None = None
        self.n_averaged = 0

    @functools.cached_property
    def opt(self) -> torch.optim.Adam:
        """The optimiser, made when first used: a network only flown never makes one (torch's
        first optimiser imports its compiler, about 1.5 s of a command on 2 cores). The fused
        Adam kernel: one call instead of ~10 per parameter tensor (timed in BENCHMARKS.md,
        training section)."""
        return torch.optim.Adam(self.online.parameters(), lr=self.cfg.lr, fused=True)

    def epsilon(self, episode: Any) -> Any:
        """eps0 * eps_decay^episode (works on arrays of episode indices)."""
        return self.cfg.eps0 * self.cfg.eps_decay ** np.asarray(episode, dtype=np.float64)

    def observe(self, env_obs: Any, t: Any) -> np.ndarray:
        """The network's (N, dim) input from a batch of the env's observations after ``t``
        moves (the encoder's)."""
        return self.encoder(env_obs, t)

    def act(
        self, obs: np.ndarray, episodes: np.ndarray, explore_among: np.ndarray | None = None
    ) -> np.ndarray:
        """Epsilon-greedy actions for a batch of UAVs, each at its own episode's epsilon.
        Always draws one uniform and one action per UAV, so the random stream does not
        depend on the network's choices. ``explore_among`` (N, A) bool: the actions an
        exploring UAV draws from (uniformly; default all); the greedy choice is the
        network's own, among all actions."""
        n = len(obs)
        explore = self.rng.random(n) < self.epsilon(episodes)
        if explore_among is None:
            random_a = self.rng.integers(self.n_actions, size=n)
        else:
            k = np.floor(self.rng.random(n) * explore_among.sum(axis=1))
            random_a = np.argmax(np.cumsum(explore_among, axis=1) > k[:, None], axis=1)
        return np.where(explore, random_a, self.greedy(obs))

    def q_values(self, obs: np.ndarray) -> np.ndarray:
        """The online network's (N, A) action values."""
        with torch.inference_mode():
            x = torch.as_tensor(np.atleast_2d(obs), dtype=torch.float32, device=self.device)
            return self.online(x).cpu().numpy()

    def greedy(self, obs: np.ndarray, allowed: np.ndarray | None = None) -> np.ndarray:
        """The action of highest Q, among the ``allowed`` (N, A) ones when given."""
        return best_action(self.q_values(obs), allowed)

    def learn(self) -> float | None:
        if self.replay.size < max(self.cfg.learning_starts, self.cfg.batch_size):
            return None
        b = self.replay.sample(self.rng, self.cfg.batch_size)
        t = {k: torch.as_tensor(v, device=self.device) for k, v in b.items()}
        n = len(b["obs"])
        # One online forward for s and s' (the s' half, detached, picks the double-Q action).
        q_all = self.online(torch.cat([t["obs"], t["next_obs"]]))
        q = q_all[:n].gather(1, t["action"][:, None]).squeeze(1)
        with torch.no_grad():
            y = double_q_target(
                q_all[n:],
                self.target(t["next_obs"]),
                t["ret"] / self.cfg.reward_scale,
                t["discount"],
                t["done"],
            )
        if self.cfg.loss == "mse":
            loss = nn.functional.mse_loss(q, y)
        else:
            loss = nn.functional.smooth_l1_loss(q, y)
        self.opt.zero_grad(set_to_none=True)
        loss.backward()
        if self.cfg.grad_clip > 0:
            nn.utils.clip_grad_norm_(self.online.parameters(), self.cfg.grad_clip, foreach=True)
        self.opt.step()
        self.updates += 1
        return float(loss.detach())

    def schedule(self, finished: int) -> None:
        """The schedules after ``finished`` episodes: the learning rate
        ([`anneal()`][rainuav.rl.dqn.Agent.anneal]), the target network's sync every
        ``target_sync_episodes``, and the running mean of the weights past ``average_from``."""
        self.anneal(finished)
        if finished % self.cfg.target_sync_episodes == 0:
            self.sync()
        if finished > self.cfg.average_from * self.cfg.episodes:
            self.accumulate_average()

    def anneal(self, finished: int) -> None:
        """Sets the learning rate for ``finished`` episodes done: cosine from ``lr`` to
        ``lr_final`` over the run (``lr_final = 0``: ``lr`` throughout)."""
        c = self.cfg
        final = c.lr_final or c.lr
        frac = min(finished / c.episodes, 1.0)
        lr = final + (c.lr - final) * 0.5 * (1.0 + math.cos(math.pi * frac))
        for group in self.opt.param_groups:
            group["lr"] = lr

    def sync(self) -> None:
        self.target.load_state_dict(self.online.state_dict())

    def accumulate_average(self) -> None:
        """Adds the online weights to their running mean (one sample)."""
        with torch.no_grad():
            self.n_averaged += 1
            if self.average is None:
                self.average = {k: v.detach().clone() for k, v in self.online.state_dict().items()}
                return
            for k, v in self.online.state_dict().items():
                self.average[k] += (v - self.average[k]) / self.n_averaged

    def reported_weights(self) -> dict[str, torch.Tensor]:
        """The weights the run reports: the running mean once averaging has begun, else the
        online network's."""
        return self.online.state_dict() if self.average is None else self.average

    @contextmanager
    def reporting(self) -> Iterator[None]:
        """Within: the online network holds
        [`reported_weights()`][rainuav.rl.dqn.Agent.reported_weights] (for greedy checks); its own
        weights are restored after."""
        if self.average is None:
            yield
            return
        own = {k: v.detach().clone() for k, v in self.online.state_dict().items()}
        self.online.load_state_dict(self.average)
        try:
            yield
        finally:
            self.online.load_state_dict(own)

    def state_dict(self) -> dict[str, Any]:
        return {
            "online": self.online.state_dict(),
            "target": self.target.state_dict(),
            "opt": self.opt.state_dict(),
            "replay": self.replay.state_dict(),
            "rng": self.rng.bit_generator.state,
            "updates": self.updates,
            "average": self.average,
            "n_averaged": self.n_averaged,
        }

    def load_state_dict(self, d: dict[str, Any], *, to_fly: bool = False) -> None:
        """Restores a saved agent; ``to_fly``: only what flying reads (the networks and the
        weight average), not the optimiser, the replay or the exploration's stream."""
        self.online.load_state_dict(d["online"])
        self.target.load_state_dict(d["target"])
        if not to_fly:
            self.opt.load_state_dict(d["opt"])
            self.replay.load_state_dict(d["replay"])
            self.rng.bit_generator.state = d["rng"]
        self.updates = int(d["updates"])
        # Checkpoints from before weight averaging hold neither.
        average, n_averaged = d.get("average"), d.get("n_averaged", 0)
        if average is not None:
            own = self.online.state_dict()
            ok = isinstance(average, dict) and set(average) == set(own)
            if not ok or any(
                not isinstance(average[k], torch.Tensor) or average[k].shape != v.shape
                for k, v in own.items()
            ):
                raise ValueError("average must hold the online network's tensors")
            average = {k: v.to(self.device) for k, v in average.items()}
        self.average, self.n_averaged = average, int(n_averaged)
