"""The dueling double DQN with multi-step returns (the paper's Algorithm 1), in torch.

Reads top to bottom: the double-Q target, the memory a run needs, and the agent (observe, act,
learn, sync); the networks are [`rainuav.rl.networks`][rainuav.rl.networks], the N-step window and
the replay memory [`rainuav.rl.replay`][rainuav.rl.replay]. Hyperparameters:
[`DQNConfig`][rainuav.rl.dqnconfig.DQNConfig]. Every choice beyond the paper's Table I, and what it
measured, is in ``docs/record/learning.md``."""

from __future__ import annotations

import functools
import math
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
import numpy.typing as npt
import torch
from torch import nn

from rainuav.nav.views import WeatherView
from rainuav.rl.config import DQNConfig, random_streams
from rainuav.rl.networks import MoveGeometry, PositionEncoder, WeatherEncoder
from rainuav.rl.replay import NStepWindow, Replay

Encoder = PositionEncoder | WeatherEncoder
"""How an env's observation becomes the network's input, and the network
([`rainuav.rl.networks`][rainuav.rl.networks])."""

__all__ = ["Agent", "Encoder", "NStepWindow", "Replay", "best_action", "double_q_target"]


def best_action(q: np.ndarray, allowed: np.ndarray | None = None) -> np.ndarray:
    """The action of highest value for each row, among the allowed ones.

    Args:
        q: Action values (N, A).
        allowed: The actions to choose among (N, A) bool; None: all.

    Returns:
        (N,) actions.
    """
    if allowed is not None:
        q = np.where(allowed, q, -np.inf)
    return q.argmax(axis=1)


def double_q_target(
    q_next_online: torch.Tensor,
    q_next_target: torch.Tensor,
    ret: torch.Tensor,
    discount: torch.Tensor,
    done: torch.Tensor,
) -> torch.Tensor:
    """The double-Q target `R + gamma^k (1 - done) Q_target(s', argmax_a Q_online(s', a))`.

    Args:
        q_next_online: The online network's values at s' (B, A).
        q_next_target: The target network's values at s' (B, A).
        ret: The n-step returns (B,).
        discount: `gamma^k` (B,).
        done: 1 where there is no bootstrap (B,).

    Returns:
        (B,) targets.
    """
    a_star = q_next_online.argmax(dim=1, keepdim=True)
    return ret + discount * (1.0 - done) * q_next_target.gather(1, a_star).squeeze(1)


def memory_needed(
    cfg: DQNConfig, view: WeatherView | None = None, levels: bool = False
) -> dict[str, int]:
    """The bytes the agent of a configuration allocates, by the field that sets them.

    `dqn.hidden` is the float32 weights of the network, seven times over (online, target, gradients,
    Adam's two moments, the weight average and a copy while reporting); `dqn.replay_capacity` the
    replay's arrays. Computed from the sizes, so a run that cannot fit is refused before anything is
    built.

    Args:
        cfg: The learner's settings.
        view: The weather observation where the env gives it (its network is built on the CPU to
            count its weights, a few ms); None: the position observation.
        levels: Altitude as a decision (the level an input, six actions).

    Returns:
        Bytes by field name.
    """
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
    """The dueling double DQN's learner: online and target networks, replay, optimiser and
    exploration."""

    def __init__(self, cfg: DQNConfig, seed: int, device: torch.device, encoder: Encoder) -> None:
        """Builds the networks, the replay and the optimiser.

        Args:
            cfg: The learner's settings ([`DQNConfig`][rainuav.rl.dqnconfig.DQNConfig]).
            seed: The run's seed: the network's initial weights; exploration and replay sampling
                draw from its "agent" stream
                ([`random_streams()`][rainuav.rl.seeds.random_streams]).
            device: Where the networks run (CUDA when present, else the CPU).
            encoder: How the env's observations become the network's input, and the network
                ([`rainuav.rl.networks`][rainuav.rl.networks]).
        """
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
        """The optimiser, made when first used: the fused Adam kernel.

        A network only flown never makes one (torch's first optimiser imports its compiler, about
        1.5 s of a command on 2 cores); the fused kernel is one call instead of about 10 per
        parameter tensor (timed in BENCHMARKS.md, training section).

        Returns:
            The `torch.optim.Adam`.
        """
        return torch.optim.Adam(self.online.parameters(), lr=self.cfg.lr, fused=True)

    def epsilon(self, episode: npt.ArrayLike) -> Any:
        """The exploration rate after some episodes: `eps0 * eps_decay ** episode`.

        Args:
            episode: Episode indices (a number or an array).

        Returns:
            Epsilon, of the shape of `episode`.
        """
        return self.cfg.eps0 * self.cfg.eps_decay ** np.asarray(episode, dtype=np.float64)

    def observe(self, env_obs: npt.ArrayLike, t: npt.ArrayLike) -> np.ndarray:
        """The network's input from a batch of the env's observations.

        Args:
            env_obs: The env's observations of N UAVs.
            t: Each UAV's moves so far (N,).

        Returns:
            (N, dim) float32, as the encoder makes it.
        """
        return self.encoder(env_obs, t)

    def act(
        self, obs: np.ndarray, episodes: np.ndarray, explore_among: np.ndarray | None = None
    ) -> np.ndarray:
        """Epsilon-greedy actions for a batch of UAVs, each at its own episode's epsilon.

        One uniform and one action are always drawn per UAV, so the random stream does not depend on
        the network's choices; the greedy choice is the network's own, among all actions.

        Args:
            obs: The network's input (N, dim).
            episodes: Each UAV's episode index (N,).
            explore_among: The actions an exploring UAV draws from, uniformly, (N, A) bool; None:
                all.

        Returns:
            (N,) int64 actions.
        """
        n = len(obs)
        explore = self.rng.random(n) < self.epsilon(episodes)
        if explore_among is None:
            random_a = self.rng.integers(self.n_actions, size=n)
        else:
            k = np.floor(self.rng.random(n) * explore_among.sum(axis=1))
            random_a = np.argmax(np.cumsum(explore_among, axis=1) > k[:, None], axis=1)
        return np.where(explore, random_a, self.greedy(obs))

    def q_values(self, obs: np.ndarray) -> np.ndarray:
        """The online network's action values.

        Args:
            obs: The network's input (N, dim).

        Returns:
            (N, A) float action values.
        """
        with torch.inference_mode():
            x = torch.as_tensor(np.atleast_2d(obs), dtype=torch.float32, device=self.device)
            return self.online(x).cpu().numpy()

    def greedy(self, obs: np.ndarray, allowed: np.ndarray | None = None) -> np.ndarray:
        """The action of highest value for each UAV.

        Args:
            obs: The network's input (N, dim).
            allowed: The actions to choose among, (N, A) bool; None: all.

        Returns:
            (N,) int64 actions.
        """
        return best_action(self.q_values(obs), allowed)

    def learn(self) -> float | None:
        """One gradient step on a batch drawn from the replay, once it holds enough transitions.

        The target is double Q-learning's (the online network picks the next action, the target
        network values it) over the n-step return; the loss is Huber or squared error, with the
        gradient's norm clipped at `grad_clip`.

        Returns:
            The batch's loss, or None before `learning_starts` transitions (or a batch) are stored.
        """
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
        """The schedules after some episodes: learning rate, target sync and the weights' running
        mean.

        The learning rate follows [`anneal()`][rainuav.rl.dqn.Agent.anneal]; the target network is
        synchronised every `target_sync_episodes`; the running mean of the weights starts past
        `average_from`.

        Args:
            finished: The episodes finished so far.
        """
        self.anneal(finished)
        if finished % self.cfg.target_sync_episodes == 0:
            self.sync()
        if finished > self.cfg.average_from * self.cfg.episodes:
            self.accumulate_average()

    def anneal(self, finished: int) -> None:
        """Sets the learning rate: a cosine from `lr` to `lr_final` over the run.

        Args:
            finished: The episodes finished so far (`lr_final = 0`: `lr` throughout).
        """
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
        """The weights the run reports.

        Returns:
            The running mean of the online weights once averaging has begun, else the online
            network's weights.
        """
        return self.online.state_dict() if self.average is None else self.average

    @contextmanager
    def reporting(self) -> Iterator[None]:
        """A context in which the online network holds the reported weights (for greedy checks).

        Yields:
            Nothing; the online network's own weights are restored after.
        """
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
        """Everything a resumed run needs: the networks, optimiser, replay, random state and
        average.

        Returns:
            A dict of tensors, arrays and plain values (saved with `torch.save`, read with
            `weights_only=True`).
        """
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
        """Restores a saved agent.

        Args:
            d: What [`state_dict()`][rainuav.rl.dqn.Agent.state_dict] gave.
            to_fly: Restore only what flying reads (the networks and the weight average), not the
                optimiser, the replay or the exploration's stream.

        Raises:
            ValueError: A weight average that does not hold the online network's tensors.
        """
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
