"""Dueling double DQN with multi-step returns (the paper's Algorithm 1), in torch.

Reads top to bottom: the network, the N-step sliding window, the replay memory, and the agent
(act, learn, sync). Choices beyond the paper's Table I, and why:

- discount ``gamma = 0.99`` and ``n_step = 3`` (N1): the goal reward (2000) is up to ~300 moves
  away; 0.99^300 still leaves it worth ~100 against ~-300 of step costs, and 3-step returns
  propagate it 3x faster than 1-step returns without the variance of long windows;
- rewards are divided by ``reward_scale = 100`` inside the learner (targets of order 1-100
  rather than 1e4), Huber loss, Adam with learning rate 5e-4, gradient norm clipped at 10;
- the state (a position in [0, 1]^2) is expanded with ``fourier`` sine/cosine features per
  axis before two hidden layers of 128: plain coordinates make an MLP too smooth to follow a
  radio map's sharp coverage edges.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
from torch import nn

__all__ = ["Agent", "DQNConfig", "DuelingQNet", "NStepWindow", "Replay"]


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
    gamma: float = 0.99
    """Discount factor."""
    n_step: int = 3
    """N1: length of the multi-step window."""
    lr: float = 5e-4
    """Adam learning rate."""
    hidden: int = 128
    """Width of the two hidden layers."""
    fourier: int = 8
    """Sine/cosine frequencies per coordinate in the state features (0: raw coordinates)."""
    reward_scale: float = 100.0
    """Rewards are divided by this inside the learner."""
    grad_clip: float = 10.0
    """Gradient-norm clip."""
    learning_starts: int = 1000
    """Transitions stored before learning starts."""
    train_every: int = 1
    """Environment steps per gradient step."""


class DuelingQNet(nn.Module):
    """Q(s, a) = V(s) + A(s, a) - mean_a A(s, a) on Fourier features of the position."""

    def __init__(self, hidden: int = 128, fourier: int = 8, n_actions: int = 4) -> None:
        super().__init__()
        self.register_buffer("freqs", math.pi * torch.arange(1, fourier + 1, dtype=torch.float32))
        d_in = 2 + 4 * fourier
        self.body = nn.Sequential(
            nn.Linear(d_in, hidden), nn.ReLU(), nn.Linear(hidden, hidden), nn.ReLU()
        )
        self.value = nn.Linear(hidden, 1)
        self.advantage = nn.Linear(hidden, n_actions)

    def features(self, obs: torch.Tensor) -> torch.Tensor:
        if self.freqs.numel() == 0:
            return obs
        ang = obs[..., :, None] * self.freqs  # (B, 2, K)
        return torch.cat([obs, torch.sin(ang).flatten(-2), torch.cos(ang).flatten(-2)], dim=-1)

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        h = self.body(self.features(obs))
        adv = self.advantage(h)
        return self.value(h) + adv - adv.mean(dim=-1, keepdim=True)


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

    def state_dict(self) -> dict[str, Any]:
        return {
            k: getattr(self, k)
            for k in ("obs", "action", "ret", "next_obs", "discount", "done", "size", "pos")
        }

    def load_state_dict(self, d: dict[str, Any]) -> None:
        for k, v in d.items():
            setattr(self, k, v)


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


class Agent:
    """Online and target networks, replay, optimiser and the exploration schedule."""

    def __init__(self, cfg: DQNConfig, seed: int, device: torch.device) -> None:
        self.cfg = cfg
        self.device = device
        torch.manual_seed(seed)
        self.online = DuelingQNet(cfg.hidden, cfg.fourier).to(device)
        self.target = DuelingQNet(cfg.hidden, cfg.fourier).to(device)
        self.target.load_state_dict(self.online.state_dict())
        self.opt = torch.optim.Adam(self.online.parameters(), lr=cfg.lr)
        self.replay = Replay(cfg.replay_capacity)
        self.rng = np.random.default_rng(seed)
        self.updates = 0

    def epsilon(self, episode: int) -> float:
        return self.cfg.eps0 * self.cfg.eps_decay**episode

    def greedy(self, obs: np.ndarray) -> np.ndarray:
        with torch.no_grad():
            x = torch.as_tensor(np.atleast_2d(obs), dtype=torch.float32, device=self.device)
            return self.online(x).argmax(dim=1).cpu().numpy()

    def act(self, obs: np.ndarray, episode: int) -> int:
        if self.rng.random() < self.epsilon(episode):
            return int(self.rng.integers(4))
        return int(self.greedy(obs)[0])

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
        loss = nn.functional.smooth_l1_loss(q, y)
        self.opt.zero_grad(set_to_none=True)
        loss.backward()
        nn.utils.clip_grad_norm_(self.online.parameters(), self.cfg.grad_clip)
        self.opt.step()
        self.updates += 1
        return float(loss.detach())

    def sync(self) -> None:
        self.target.load_state_dict(self.online.state_dict())

    def state_dict(self) -> dict[str, Any]:
        return {
            "online": self.online.state_dict(),
            "target": self.target.state_dict(),
            "opt": self.opt.state_dict(),
            "replay": self.replay.state_dict(),
            "rng": self.rng.bit_generator.state,
            "updates": self.updates,
        }

    def load_state_dict(self, d: dict[str, Any]) -> None:
        self.online.load_state_dict(d["online"])
        self.target.load_state_dict(d["target"])
        self.opt.load_state_dict(d["opt"])
        self.replay.load_state_dict(d["replay"])
        self.rng.bit_generator.state = d["rng"]
        self.updates = d["updates"]
