"""The parts a learner is built from: how an environment's observation becomes the network's input
(an *encoder*), and the network. The DQN ([`rainuav.rl.dqn`][rainuav.rl.dqn]) takes any encoder and
never looks inside the observation.

- [`PositionEncoder`][rainuav.rl.networks.PositionEncoder] +
  [`DuelingQNet`][rainuav.rl.networks.DuelingQNet]: the single-map learner. The position (and the
  time where the signal moves), goal-relative features of the fixed destination, into an MLP with
  Fourier features.
- [`WeatherEncoder`][rainuav.rl.networks.WeatherEncoder] +
  [`WeatherQNet`][rainuav.rl.networks.WeatherQNet]: the learner that reads the weather
  (``UAVNavEnv(observation="weather")``, on one level or among several). The ``Dict``
  observation ([`rainuav.nav.views.WeatherView`][rainuav.nav.views.WeatherView]) is flattened in a
  fixed order for the replay; the network splits it again: two small convolutional stacks read the
  local window and the whole-area grid (one channel a level among levels), an MLP reads them with
  the position, the destination, the time (and the level) and goal-relative features.

An encoder has ``dim`` (floats per encoded observation), ``__call__(env_obs, t)`` (a batch
of the env's observations after ``t`` moves -> (N, dim) float32) and ``make_net()``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import torch
from torch import nn
from torch.nn import functional as F

from rainuav.errors import InvalidInputError
from rainuav.nav.views import WeatherView
from rainuav.rl.config import DQNConfig
from rainuav.rl.features import MoveGeometry, goal_features

__all__ = [
    "DuelingQNet",
    "MoveGeometry",
    "PositionEncoder",
    "WeatherEncoder",
    "WeatherQNet",
    "goal_features",
]


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
        """The network's layers.

        Args:
            hidden: The hidden layers' width.
            fourier: Sine/cosine frequencies of the smooth inputs.
            n_actions: The actions (4 on one level, 6 among levels).
            obs_dim: The input's size.
            smooth_dim: The first inputs that also enter as frequencies; None: `obs_dim`.
        """
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
        """The input with the smooth part's sine/cosine frequencies beside it.

        Args:
            obs: The input (B, obs_dim).

        Returns:
            (B, features).
        """
        parts = [obs]
        if self.freqs.numel():
            ang = obs[:, : self.smooth_dim, None] * self.freqs  # (B, smooth_dim, K)
            parts += [torch.sin(ang).flatten(-2), torch.cos(ang).flatten(-2)]
        return torch.cat(parts, dim=-1)

    def head(self, h: torch.Tensor) -> torch.Tensor:
        """The dueling head: `V(s) + A(s, a) - mean_a A(s, a)`.

        Args:
            h: The body's output (B, hidden).

        Returns:
            (B, A) action values.
        """
        adv = self.advantage(h)
        return self.value(h) + adv - adv.mean(dim=-1, keepdim=True)

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        """The action values of a batch of inputs.

        Args:
            obs: The input (B, obs_dim).

        Returns:
            (B, A).
        """
        return self.head(self.body(self.features(obs)))


class PositionEncoder:
    """The single-map learner's input: the env's (N, 2) position (among levels, then the
    level over the highest index; then the time where the signal moves), then t / horizon
    when time-aware and the env does not give it, then the goal-relative features
    ``tanh(d / (step 4^k))`` (functions of the position and the fixed destination, so
    nothing the environment does not give; they let the network resolve the 10 m arrival
    disc, which global features blur). ``n_actions``: 4 on one level, 6 among levels."""

    def __init__(
        self,
        cfg: DQNConfig,
        horizon: int,
        goal: tuple[float, float],
        step: tuple[float, float],
        env_dims: int = 2,
        *,
        gives_time: bool | None = None,
        n_actions: int = 4,
    ) -> None:
        """The single-map learner's input for an env.

        Args:
            cfg: The learner's settings.
            horizon: The task's `max_steps`.
            goal: The fixed destination, m.
            step: One move in the observation's units, per axis.
            env_dims: The env observation's size.
            gives_time: Whether the env's observation ends with the time; None: it has three
                dimensions (the plane's in time).
            n_actions: The actions (4 on one level, 6 among levels).
        """
        self.cfg, self.horizon, self.n_actions = cfg, horizon, n_actions
        self.goal = np.asarray(goal, dtype=np.float32)
        self.goal_scale = (
            np.asarray(step, dtype=np.float32)[:, None] * 4.0 ** np.arange(cfg.goal_features)
        ).astype(np.float32)  # (2, K)
        # The time is an input where the env gives it, or where the learner is time-aware.
        gives = env_dims == 3 if gives_time is None else gives_time
        self.adds_time = cfg.time_aware and not gives
        self.n_smooth = env_dims + int(self.adds_time)
        self.dim = self.n_smooth + 2 * cfg.goal_features

    def __call__(self, env_obs: Any, t: Any) -> np.ndarray:
        env_obs = np.atleast_2d(np.asarray(env_obs, dtype=np.float32))
        parts = [env_obs]
        if self.adds_time:
            frac = (np.asarray(t, dtype=np.float32) / self.horizon).reshape(-1, 1)
            parts.append(np.broadcast_to(frac, (len(env_obs), 1)))
        if self.cfg.goal_features:
            parts.append(goal_features(env_obs[:, :2] - self.goal, self.goal_scale))
        return np.concatenate(parts, axis=1).astype(np.float32)

    def make_net(self) -> nn.Module:
        """The network this input feeds.

        Returns:
            A [`DuelingQNet`][rainuav.rl.networks.DuelingQNet].
        """
        c = self.cfg
        return DuelingQNet(
            c.hidden, c.fourier, self.n_actions, obs_dim=self.dim, smooth_dim=self.n_smooth
        )


class WeatherQNet(DuelingQNet):
    """The dueling head on features of the weather: the flat observation (``WeatherView``
    order: position, goal, time, local window, whole-area grid) split into its parts; each
    grid through two 3x3 convolutions (``conv`` and ``2 conv`` channels, the second with
    stride 2; the area's first also strided), flattened; the position, destination and time
    with ``fourier`` sine/cosine frequencies, and goal-relative features at
    ``len(goal_scale)`` scales; two hidden ReLU layers of ``hidden``.

    With ``moves`` ([`MoveGeometry`][rainuav.rl.features.MoveGeometry]), for each of the four moves
    the destination as it would be after it: whether the move arrives, and how much nearer it brings
    the UAV (in moves, in [-1, 1]). They are functions of the position and the destination the
    observation holds (nothing the env does not show), fed to the body and, through one weight per
    feature shared by the moves, straight into the advantage: where destinations are drawn per
    flight the arrival disc is met at any offset from the lattice, and a network that must find the
    disc's edge from its other inputs circles it (docs/record/learning.md)."""

    def __init__(
        self,
        view: WeatherView,
        hidden: int,
        fourier: int,
        goal_scale: np.ndarray,
        conv: int = 16,
        moves: MoveGeometry | None = None,
        goal_maps: MoveGeometry | None = None,
        n_actions: int = 4,
    ) -> None:
        """The weather network's layers.

        Args:
            view: The env's weather view (the observation's parts).
            hidden: The hidden layers' width.
            fourier: Sine/cosine frequencies of the position, destination and time.
            goal_scale: The goal-relative features' scales.
            conv: The first convolution's channels.
            moves: The move features' geometry; None: none.
            goal_maps: The goal maps' geometry; None: none.
            n_actions: The actions (4 on one level, 6 among levels).
        """
        nv = view.vector  # position, goal, time (and the level among levels)
        super().__init__(hidden, fourier, n_actions, obs_dim=nv, smooth_dim=nv)
        self.window, self.area, self.layers, self.n_vec = view.window, view.area, view.layers, nv
        self.register_buffer("goal_scale", torch.as_tensor(goal_scale, dtype=torch.float32))

        def stack(first_stride: int, channels: int) -> nn.Sequential:
            return nn.Sequential(
                nn.Conv2d(channels, conv, 3, stride=first_stride, padding=1), nn.ReLU(),
                nn.Conv2d(conv, 2 * conv, 3, stride=2, padding=1), nn.ReLU(), nn.Flatten(),
            )  # fmt: skip

        self.goal_maps = goal_maps
        if goal_maps is not None:
            n = view.area
            c = (torch.arange(n, dtype=torch.float32) + 0.5) / n
            gy, gx = torch.meshgrid(c, c, indexing="ij")  # the area grid's cells, row-major
            # cells, window_m, map_span: the saved geometry (in every goal-maps checkpoint, so
            # kept for loading); forward reads the constants derived from them below.
            self.register_buffer("cells", torch.stack([gx.ravel(), gy.ravel()], dim=-1))
            off = torch.tensor(np.array(view.local_offsets()), dtype=torch.float32)
            self.register_buffer("window_m", off)
            self.register_buffer("map_span", torch.as_tensor(goal_maps.span_m, dtype=torch.float32))
            self.reach_m = max(view.window // 2, 1) * view.window_step_m
            # Constants of every decision, computed once (not saved: derived from the above).
            cells_m = self.cells * self.map_span
            for name, value in (
                ("cells_x", cells_m[:, 0]),
                ("cells_y", cells_m[:, 1]),
                ("window_x", off[:, 0]),
                ("window_y", off[:, 1]),
                ("diagonal", torch.hypot(*self.map_span)),
            ):
                self.register_buffer(name, value.contiguous(), persistent=False)
        extra = (1, 2) if goal_maps is not None else (0, 0)
        self.local = stack(1, view.layers + extra[0])
        self.whole = stack(2, view.layers + extra[1])

        def out(n: int, first: int) -> int:
            n = (n - 1) // first + 1
            return 2 * conv * ((n - 1) // 2 + 1) ** 2

        self.moves = moves
        d_moves = 0
        if moves is not None:
            self.register_buffer("span", torch.as_tensor(moves.span_m, dtype=torch.float32))
            shifts = np.zeros((n_actions, 2), dtype=np.float32)  # a climb or descent: none
            shifts[:4] = moves.shifts_m
            self.register_buffer("shifts", torch.as_tensor(shifts))
            self.move_gain = nn.Linear(MoveGeometry.per_move, 1, bias=False)
            d_moves = MoveGeometry.per_move * n_actions
        d_grid = out(self.window, 1) + out(self.area, 2)
        d_vec = nv + nv * 2 * fourier + 2 * goal_scale.shape[1] + d_moves
        self.body = nn.Sequential(
            nn.Linear(d_grid + d_vec, hidden), nn.ReLU(), nn.Linear(hidden, hidden), nn.ReLU()
        )

    def move_features(self, vec: torch.Tensor) -> torch.Tensor:
        """Per move, whether it arrives and how much nearer it brings the UAV.

        A climb or a descent: neither (it stays over the same point).

        Args:
            vec: The flat observations (B, D).

        Returns:
            (B, A, 2).
        """
        assert self.moves is not None
        rel = (vec[:, 2:4] - vec[:, 0:2]) * self.span  # (B, 2) metres to the destination
        after = torch.linalg.vector_norm(rel[:, None, :] - self.shifts, dim=-1)  # (B, 4)
        now = torch.linalg.vector_norm(rel, dim=-1, keepdim=True)
        arrive = (after <= self.moves.tol_m).to(vec.dtype)
        progress = ((now - after) / self.moves.step_m).clamp(-1.0, 1.0)
        return torch.stack([arrive, progress], dim=-1)

    def goal_channels(self, vec: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """The destination drawn on the grids.

        On the local window, how much nearer each of its points is to the destination than the UAV
        (in window half-widths, in [-1, 1]); on the whole area, each cell's distance to the
        destination and to the UAV (in area diagonals).

        Args:
            vec: The flat observations (B, D).

        Returns:
            `((B, 1, window, window), (B, 2, area, area))`.
        """
        ends = vec[:, 0:4].reshape(-1, 2, 2) * self.map_span  # (B, 2, 2): UAV, destination, m
        to_goal = ends[:, 1] - ends[:, 0]
        rx, ry = to_goal[:, 0:1], to_goal[:, 1:2]  # to the destination, m
        after = torch.hypot(rx - self.window_x, ry - self.window_y)
        near = ((torch.hypot(rx, ry) - after) / self.reach_m).clamp(-1.0, 1.0)
        p = ends.flip(1)  # destination, UAV
        area = torch.hypot(self.cells_x - p[..., 0:1], self.cells_y - p[..., 1:2]) / self.diagonal
        n, a = self.window, self.area
        return near.reshape(-1, 1, n, n), area.reshape(-1, 2, a, a)

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        # The layers are called as functions (ReLU in place): the same
        # operations as the modules' calls, bit for bit, with less overhead per call; a
        # decision is a few dozen small operations (benches/decision.py).
        """The action values of a batch of flat observations.

        Args:
            obs: The flat observations (B, D).

        Returns:
            (B, A).
        """
        nl, nv = self.layers, self.n_vec
        w2, a2 = nl * self.window**2, nl * self.area**2
        vec = obs[:, :nv]
        local = obs[:, nv : nv + w2].reshape(-1, nl, self.window, self.window)
        whole = obs[:, nv + w2 : nv + w2 + a2].reshape(-1, nl, self.area, self.area)
        if self.goal_maps is not None:
            near, area = self.goal_channels(vec)
            local, whole = torch.cat([local, near], dim=1), torch.cat([whole, area], dim=1)
        parts = [
            self.features(vec),
            goal_features(vec[:, 2:4] - vec[:, 0:2], self.goal_scale),
            _conv_stack(self.local, local),
            _conv_stack(self.whole, whole),
        ]
        mf = None if self.moves is None else self.move_features(vec)
        if mf is not None:
            parts.append(mf.flatten(1))
        l1, _, l2, _ = self.body
        h = F.linear(
            F.linear(torch.cat(parts, dim=1), l1.weight, l1.bias).relu_(), l2.weight, l2.bias
        )
        q = self.head(h.relu_())
        if mf is None:
            return q
        gain = F.linear(mf, self.move_gain.weight).squeeze(-1)  # (B, A)
        return q + gain - gain.mean(dim=-1, keepdim=True)  # the advantage's part only


def _conv_stack(stack: nn.Module, x: torch.Tensor) -> torch.Tensor:
    """A grid's two convolutions and ReLUs (the ``stack`` of
    [`WeatherQNet`][rainuav.rl.networks.WeatherQNet]), flattened."""
    c1, _, c2, _, _ = stack
    x = F.conv2d(x, c1.weight, c1.bias, c1.stride, c1.padding).relu_()
    return F.conv2d(x, c2.weight, c2.bias, c2.stride, c2.padding).relu_().flatten(1)


class WeatherEncoder:
    """The weather-reading learner's input: the env's ``Dict`` observation flattened
    ([`WeatherView.flat()`][rainuav.nav.views.WeatherView.flat]); the network splits it
    ([`WeatherQNet`][rainuav.rl.networks.WeatherQNet]). ``n_actions``: 4 on one level, 6 among
    levels."""

    def __init__(
        self,
        cfg: DQNConfig,
        view: WeatherView,
        step: tuple[float, float],
        moves: MoveGeometry | None = None,
        n_actions: int = 4,
    ) -> None:
        """The weather-reading learner's input for an env.

        Args:
            cfg: The learner's settings.
            view: The env's weather view.
            step: One move in the observation's units, per axis.
            moves: The env's geometry, for the move features and the goal maps.
            n_actions: The actions (4 on one level, 6 among levels).

        Raises:
            InvalidInputError: Goal maps or move features asked for without the env's geometry.
        """
        self.cfg, self.view, self.n_actions = cfg, view, n_actions
        if cfg.move_features and moves is None:
            raise InvalidInputError("move_features needs the env's geometry (MoveGeometry)")
        self.moves = moves if cfg.move_features else None
        if cfg.goal_maps and moves is None:
            raise InvalidInputError("goal_maps needs the env's geometry (MoveGeometry)")
        self.goal_maps = moves if cfg.goal_maps else None
        self.dim = sum(view.sizes.values())
        k = max(cfg.goal_features, 1)
        self.goal_scale = (np.asarray(step, np.float32)[:, None] * 4.0 ** np.arange(k)).astype(
            np.float32
        )

    def __call__(self, env_obs: Any, t: Any) -> np.ndarray:
        return self.view.flat(env_obs)

    def make_net(self) -> nn.Module:
        """The network this input feeds.

        Returns:
            A [`WeatherQNet`][rainuav.rl.networks.WeatherQNet].
        """
        c = self.cfg
        return WeatherQNet(
            self.view, c.hidden, c.fourier, self.goal_scale, c.conv, self.moves, self.goal_maps,
            self.n_actions,
        )  # fmt: skip
