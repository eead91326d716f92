"""The learner's hyperparameters: [`DQNConfig`][rainuav.rl.dqnconfig.DQNConfig], the ``[dqn]``
table of a run's file and the flags ``--dqn.NAME`` (one docstring line per field = one flag)."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["DQNConfig"]


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
    """Learning rate after the last episode (cosine decay from lr over the episodes; 0: a
    constant learning rate, lr throughout)."""
    average_from: float = 0.8
    """Fraction of the episodes after which the reported network is the running mean of the
    online weights, one sample per finished episode (weight averaging); 1: the final online
    network. Training itself is unchanged: the online network still acts and learns, and the
    run reports the last online network's figures beside the mean (``online_*``)."""
    hidden: int = 128
    """Width of the two hidden layers."""
    fourier: int = 8
    """Sine/cosine frequencies per input in the state features (0: none)."""
    reward_scale: float = 100.0
    """Rewards are divided by this inside the learner."""
    grad_clip: float = 10.0
    """Gradient-norm clip (0: none)."""
    loss: str = "huber"
    """TD loss: 'huber' (smooth L1) or 'mse' (the paper's squared error)."""
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
    conv: int = 16
    """Channels of the first convolution of a weather-reading network (the second has twice
    as many)."""
    move_features: bool = False
    """A weather-reading network also reads, for each move, the destination's geometry after
    it (arrival, progress toward the destination), into its body and straight into the
    advantage head ([`rainuav.rl.networks.WeatherQNet`][rainuav.rl.networks.WeatherQNet])."""
    goal_maps: bool = False
    """A weather-reading network also sees the destination drawn on its grids: on the local window
    how much nearer each point is to it, on the whole area each cell's distance to it and to the UAV
    (extra input channels of the convolutions;
    [`rainuav.rl.networks.WeatherQNet.goal_channels()`][rainuav.rl.networks.WeatherQNet.goal_channels])."""
    goal_starts: float = 0.25
    """Fraction of the training episodes that start near the destination (uniform in the
    square of half side ``GOAL_START_MOVES`` moves around it, outside the arrival disc); the
    rest, and every validation and evaluation flight, start uniform in the area."""
    task_goals: float = 0.0
    """Where the env draws a destination per episode, the fraction of the training episodes
    flown to the task's own destination instead (a training mixture: validation and
    evaluation flights keep the env's draws)."""
    shaping: float = 1.0
    """Weight of the potential-based shaping -(steps to the goal); 0: the plain rewards."""
    sir_weight: float = 1.25
    """Factor on the SIR part of each reward (b + 1) inside the learner; 1: the env's rewards."""
    level_starts: float = 0.0
    """Among flight levels, the share of the training flights that take off at a level drawn
    uniformly among those flyable at the start (the rest, and every validation and evaluation
    flight, at the lowest flyable level)."""
    shield: bool = False
    """Also report greedy flights that keep to moves that stay in the area and can still
    arrive in max_steps, and avoid positions they already visited while they can
    (rainuav.nav.shield), as shielded_*; the headline stays the network alone."""
