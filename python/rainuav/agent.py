"""Dueling double DQN with multi-step returns (the paper's Algorithm 1), in torch.

Reads top to bottom: the network, the N-step sliding window, the replay memory, and the agent
(observe, act, learn, sync). Table I fixes the episodes, exploration schedule, target sync,
replay size and minibatch. Choices beyond it, each measured on the paper map (25 mm/h,
3000 episodes, greedy policy from 200 starts against the exact planner):

- ``gamma = 0.998``, ``n_step = 3`` (``n_step = 5``, seed 0: 97.5% success and a 9.5% mean
  gap at 25 mm/h, 100% and 5.6% in clear air, against 100% / 5.4% and 100% / 5.0%). The
  evaluation is undiscounted, so discounting biases the policy against detours; the exact
  finite-horizon optimum of the discounted task gives up 3.9% (0.998) or 4.7% (0.995) of
  the undiscounted optimum. Closer to 1 the bias vanishes (0.999: 0.2%) but the
  position-only policy then plans detours that do not fit in 300 moves, and learning
  slowed: 0.999 reached 50% success, 0.998 97%, 0.995 94.5% (constant learning rate). With
  the decay below, 0.999 still reached only 81.5%; the exact discounted optimum at 0.9985
  arrives from 95% of 60 starts, with a 9.2% mean gap (its median is 0.8%).
- Potential-based reward shaping inside the learner (``shaping``, see
  :func:`rainuav.train.shaping_term`): it leaves the optimal policy unchanged and tells the
  learner at every move whether it kept the straight-line pace to the goal. At gamma 0.99:
  after 600 episodes 59% success (1% with a plain distance potential, before the goal
  features below); after 3000, 84.5%, against 55.5% for the unshaped one-UAV-at-a-time
  learner of rainuav 0.1.
- Goal-relative input features ``tanh(d / (step 4^k))`` (``goal_features``): global features
  blur the 10 m arrival disc, and policies circled the goal 20-40 m away (without SIR
  costs, 600 episodes: 65.5% success with them, 58% without).
- Position (and time) also as ``fourier`` sine/cosine features, two hidden layers of 128.
- Rewards divided by ``reward_scale = 100`` inside the learner, Huber loss, Adam (fused),
  gradient norm clipped at 10.
- Learning rate 1e-3 decaying along a cosine to ``lr_final = 3e-5`` over the episodes. At a
  constant 1e-3 the greedy policy swung from check to check until the end (success on 100
  validation starts between 0.30 and 1.00 over the last 1000 episodes) and the final network
  reached 97% success with a 21.5% mean gap; decaying to 1e-4 gave 99.5% and 5.5%, to 3e-5
  100% and 5.4% (final networks, seed 0; seeds 1 and 2 at 3e-5: 100% / 5.5%, 99.5% / 6.0%).
- ``lanes = 16`` UAVs fly at once (each its own episode and epsilon; Table I's 3000 episodes
  in total) and ``train_every = 4``: one gradient step of 16 samples per 4 transitions. A
  quarter of the paper's replay ratio, and 4x faster; twice as many gradient steps
  (``train_every = 2``) did not learn better (gamma 0.995: 88% against 94.5% success; with the
  decay to 1e-4: 83% and a 25.4% mean gap against 99.5% and 5.5%, taking 476 s, not 243 s).
- ``time_aware`` (off by default; Pardo et al., ICML 2018): appends t / max_steps to the input
  and ends bootstrapping at the time limit, which makes the exact finite-horizon optimum
  representable, but learned more slowly within 3000 episodes (success at gamma 0.999: 28%
  at a constant learning rate, 52% with the decay; at 0.998 with ``sir_weight = 2``, where
  the exact time-aware optimum gives up only 0.01%, 73%, or 80.5% with the time fraction kept
  out of the Fourier features; at gamma 1, 1.5%).
- ``sir_weight = 1.25``: weights the SIR part of each reward inside the learner
  (:func:`rainuav.train.learning_reward`). Discounting makes a later arrival cost
  ``(1 - gamma) gamma^k R_des`` on top of the -1 per move, so with the env's rewards (weight
  1) the learner overpays for time and cuts through weak SIR; the exact time-aware optimum of
  the discounted task gives up 3.9% of the undiscounted optimum at weight 1, 0.17% at 1.5 and
  0.01% at 2 (60 starts). A stationary (position-only) policy cannot use all of that: without
  the clock it plans some detours that do not fit in 300 moves, or loops, which the shield
  below handles. Learned (3000 episodes, greedy from the 200 evaluation starts, mean gap with
  the shield; the network alone in parentheses), at 25 mm/h seeds 0 / 1 / 2 and in clear air
  seeds 0 / 1 / 2: weight 1.25, 4.7% / 3.7% / 4.8% and 4.6% / 4.3% / 4.4% (alone 91.5-100%
  success, 4.6-15.3% mean gap); weight 1, 5.4% / 5.5% / 5.3% and 5.0% / 5.5% / 6.4% (alone
  99-100%, 5.0-8.1%); weight 1.5, 3.6% / 9.1% at 25 mm/h seeds 0 / 1 and 3.1% in clear air
  (alone 68.5-91%). Weight 1.25 is the only one under 5% in every run, and only with the
  shield: alone, weight 1 is better. The exact stationary optimum of the weighted discounted
  task, flown with the shield, gives up 3.7% (weight 1), 2.5% (1.25) and 0.6% (1.5) of the
  undiscounted optimum (tabular value iteration, 60 starts at 25 mm/h): the learned weight
  1.25 policies sit 1.1-2.2 points above the 25 mm/h floor.
- ``shield = True`` (Alshiekh et al., AAAI 2018): greedy flights keep to the moves after which
  the UAV is still in the area and can still arrive within ``max_steps``
  (:meth:`rainuav.env.BatchStepper.safe_actions`), and among those to moves onto a position
  the flight has not visited yet, where one exists (:func:`rainuav.train.shield_moves`). The
  first rule sends a wandering flight home when its slack runs out; the second breaks a loop
  where it closes. With ``mu >= 0`` every reward but ``"linear"`` costs at least 1 per move,
  so an optimal flight never revisits a position and the second rule only removes moves that
  no optimal flight makes (where loops can pay, ``"linear"`` or a negative ``mu``, it is
  off). The shield acts on evaluation and validation
  flights, not while learning: with the first rule in the training flights the stationary
  learner saw loops end in arrivals and learned to loop (weight 1.5: 100% success after 299.8
  moves on average, 73% mean gap). ``metrics.json`` reports how many flights it steered and
  the network's numbers without it (``unshielded_*``). Exact check (tabular value
  iteration, weight 1, 60 starts): the stationary discounted optimum arrives from 98.3% with
  a 6.1% mean gap, with the first rule 100% and 3.7%. The second rule, on the trained
  networks above: weight 1.25, 25 mm/h seed 0, 5.9% -> 4.7% (seed 2, 6.4% -> 4.8%); weight
  1, clear air seed 1, 5.9% -> 5.5%, and no change where the network does not loop.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
from torch import nn

__all__ = ["Agent", "DQNConfig", "DuelingQNet", "NStepWindow", "Replay", "best_action"]


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
    """Learning rate after the last episode (cosine decay from lr over the episodes)."""
    hidden: int = 128
    """Width of the two hidden layers."""
    fourier: int = 8
    """Sine/cosine frequencies per input in the state features (0: none)."""
    reward_scale: float = 100.0
    """Rewards are divided by this inside the learner."""
    grad_clip: float = 10.0
    """Gradient-norm clip."""
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
    shaping: float = 1.0
    """Weight of the potential-based shaping -(steps to the goal); 0: the plain rewards."""
    sir_weight: float = 1.25
    """Factor on the SIR part of each reward (b + 1) inside the learner; 1: the env's rewards."""
    shield: bool = True
    """Greedy flights keep to moves that stay in the area and can still arrive in max_steps,
    and avoid positions they already visited while they can (rainuav.train.shield_moves)."""


def best_action(q: np.ndarray, allowed: np.ndarray | None = None) -> np.ndarray:
    """Argmax of the (N, 4) values ``q``, among the ``allowed`` (N, 4) actions when given."""
    if allowed is not None:
        q = np.where(allowed, q, -np.inf)
    return q.argmax(axis=1)


class DuelingQNet(nn.Module):
    """Q(s, a) = V(s) + A(s, a) - mean_a A(s, a).

    All inputs enter as they are, and the first ``smooth_dim`` (the position and the time
    fraction) also as ``fourier`` sine/cosine frequencies; two hidden ReLU layers feed the
    value and advantage heads.
    """

    def __init__(
        self,
        hidden: int = 128,
        fourier: int = 8,
        n_actions: int = 4,
        obs_dim: int = 2,
        smooth_dim: int | None = None,
    ) -> None:
        super().__init__()
        self.register_buffer("freqs", math.pi * torch.arange(1, fourier + 1, dtype=torch.float32))
        self.smooth_dim = obs_dim if smooth_dim is None else smooth_dim
        d_in = obs_dim + self.smooth_dim * 2 * fourier
        self.body = nn.Sequential(
            nn.Linear(d_in, hidden), nn.ReLU(), nn.Linear(hidden, hidden), nn.ReLU()
        )
        self.value = nn.Linear(hidden, 1)
        self.advantage = nn.Linear(hidden, n_actions)

    def features(self, obs: torch.Tensor) -> torch.Tensor:
        parts = [obs]
        if self.freqs.numel():
            ang = obs[:, : self.smooth_dim, None] * self.freqs  # (B, smooth_dim, K)
            parts += [torch.sin(ang).flatten(-2), torch.cos(ang).flatten(-2)]
        return torch.cat(parts, dim=-1)

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

    def __init__(
        self,
        cfg: DQNConfig,
        seed: int,
        device: torch.device,
        horizon: int,
        *,
        goal: tuple[float, float],
        step: tuple[float, float],
    ) -> None:
        """``horizon``: the episode's step limit; ``goal`` and ``step``: the destination and
        one move in the environment's observation units ([0, 1]^2)."""
        self.cfg = cfg
        self.device = device
        self.horizon = horizon
        self.goal = np.asarray(goal, dtype=np.float32)
        self.goal_scale = (
            np.asarray(step, dtype=np.float32)[:, None] * 4.0 ** np.arange(cfg.goal_features)
        ).astype(np.float32)  # (2, K)
        self.n_smooth = 3 if cfg.time_aware else 2
        self.obs_dim = self.n_smooth + 2 * cfg.goal_features
        torch.manual_seed(seed)
        self.online = self.make_net().to(device)
        self.target = self.make_net().to(device)
        self.target.load_state_dict(self.online.state_dict())
        # The fused Adam kernel is one call instead of ~10 per parameter tensor: timed alone,
        # its step takes 108 us against 344 us for the default (of a 1.6 ms gradient step).
        self.opt = torch.optim.Adam(self.online.parameters(), lr=cfg.lr, fused=True)
        self.replay = Replay(cfg.replay_capacity, self.obs_dim)
        self.rng = np.random.default_rng(seed)
        self.updates = 0

    def make_net(self) -> DuelingQNet:
        c = self.cfg
        return DuelingQNet(
            c.hidden,
            c.fourier,
            obs_dim=self.obs_dim,
            smooth_dim=self.n_smooth,
        )

    def epsilon(self, episode: Any) -> Any:
        """eps0 * eps_decay^episode (works on arrays of episode indices)."""
        return self.cfg.eps0 * self.cfg.eps_decay ** np.asarray(episode, dtype=np.float64)

    def observe(self, env_obs: np.ndarray, t: Any) -> np.ndarray:
        """The agent's input from the environment's (N, 2) observation: the position, then
        t / horizon when time-aware, then the goal-relative features (functions of the
        position and the fixed destination, so no information the environment does not give;
        they let the network resolve the 10 m arrival disc, which global features blur)."""
        env_obs = np.atleast_2d(np.asarray(env_obs, dtype=np.float32))
        parts = [env_obs]
        if self.cfg.time_aware:
            frac = (np.asarray(t, dtype=np.float32) / self.horizon).reshape(-1, 1)
            parts.append(np.broadcast_to(frac, (len(env_obs), 1)))
        if self.cfg.goal_features:
            rel = (env_obs - self.goal)[:, :, None] / self.goal_scale  # (N, 2, K)
            parts.append(np.tanh(rel).reshape(len(env_obs), -1))
        return np.concatenate(parts, axis=1).astype(np.float32)

    def act(self, obs: np.ndarray, episodes: np.ndarray) -> np.ndarray:
        """Epsilon-greedy actions for a batch of UAVs, each at its own episode's epsilon.
        Always draws one uniform and one action per UAV, so the random stream does not
        depend on the network's choices."""
        n = len(obs)
        explore = self.rng.random(n) < self.epsilon(episodes)
        random_a = self.rng.integers(4, size=n)
        return np.where(explore, random_a, self.greedy(obs))

    def q_values(self, obs: np.ndarray) -> np.ndarray:
        """The online network's (N, 4) action values."""
        with torch.no_grad():
            x = torch.as_tensor(np.atleast_2d(obs), dtype=torch.float32, device=self.device)
            return self.online(x).cpu().numpy()

    def greedy(self, obs: np.ndarray, allowed: np.ndarray | None = None) -> np.ndarray:
        """The action of highest Q, among the ``allowed`` (N, 4) ones when given."""
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
        loss = nn.functional.smooth_l1_loss(q, y)
        self.opt.zero_grad(set_to_none=True)
        loss.backward()
        nn.utils.clip_grad_norm_(self.online.parameters(), self.cfg.grad_clip, foreach=True)
        self.opt.step()
        self.updates += 1
        return float(loss.detach())

    def anneal(self, finished: int) -> None:
        """Sets the learning rate for ``finished`` episodes done: cosine from ``lr`` to
        ``lr_final`` over the run."""
        c = self.cfg
        frac = min(finished / c.episodes, 1.0)
        lr = c.lr_final + (c.lr - c.lr_final) * 0.5 * (1.0 + math.cos(math.pi * frac))
        for group in self.opt.param_groups:
            group["lr"] = lr

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
