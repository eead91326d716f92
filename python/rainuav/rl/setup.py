"""Building a run's pieces from its configuration: the agent for an environment, the device,
and torch's settings for the run (restored afterwards). The environment comes from the world
([`rainuav.world`][rainuav.world])."""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Iterator

import torch

from rainuav._checks import check_fits as check_fits_memory
from rainuav.errors import InvalidInputError
from rainuav.nav.env import UAVNavEnv
from rainuav.nav.training import NetworkInputs, network_inputs
from rainuav.nav.views import WeatherView
from rainuav.rl.config import DQNConfig, TrainConfig
from rainuav.rl.dqn import Agent, Encoder, memory_needed
from rainuav.rl.networks import MoveGeometry, PositionEncoder, WeatherEncoder
from rainuav.world import levels_of

__all__ = ["check_fits", "make_agent", "make_encoder", "pick_device", "torch_settings"]


def check_fits(cfg: TrainConfig) -> None:
    """Refuses a run whose agent cannot fit in memory; called before any map is built.

    Args:
        cfg: The run's configuration ([`memory_needed()`][rainuav.rl.dqn.memory_needed]).

    Raises:
        InvalidInputError: The field and the GB that do not fit.
    """
    layers = len(levels_of(cfg)) if cfg.altitudes_m else 1
    view = WeatherView(layers=layers) if cfg.observation == "weather" else None
    need = memory_needed(cfg.dqn, view, levels=bool(cfg.altitudes_m))
    biggest = max(need, key=lambda k: need[k])
    check_fits_memory(
        f"{biggest} = {getattr(cfg.dqn, biggest.split('.')[1])}",
        sum(need.values()),
        f"lower {biggest}",
    )


def make_agent(cfg: TrainConfig, env: UAVNavEnv, device: torch.device) -> Agent:
    """An agent for an environment: its time limit, destination and one move in observation units.

    Args:
        cfg: The run's configuration.
        env: The environment (its spaces and task).
        device: Where the networks run.

    Returns:
        The [`Agent`][rainuav.rl.dqn.Agent].

    Raises:
        InvalidInputError: An agent that cannot fit in memory
            ([`check_fits()`][rainuav.rl.setup.check_fits]).
    """
    check_fits(cfg)
    return Agent(cfg.dqn, cfg.seed, device, make_encoder(cfg.dqn, network_inputs(env)))


def make_encoder(d: DQNConfig, inputs: NetworkInputs) -> Encoder:
    """The encoder (and network) for an environment's observation.

    The weather-reading one where the env shows the weather, else the position one (with the env's
    fixed destination; among levels with the level); the actions are the env's action space's
    ([`rainuav.rl.networks`][rainuav.rl.networks]).

    Args:
        d: The learner's settings.
        inputs: What the network reads of the environment
            ([`network_inputs()`][rainuav.nav.training.network_inputs]).

    Returns:
        The encoder.
    """
    i = inputs
    if i.view is not None:
        geometry = MoveGeometry(i.area_m, i.step_m, i.tol_m)
        return WeatherEncoder(d, i.view, i.step, geometry, i.actions)
    assert i.goal is not None  # an env that observes the position has its destination
    if i.among_levels:  # the level in the input, six actions (a climb and a descent)
        return PositionEncoder(d, i.max_steps, i.goal, i.step, i.observation_dims,
                               gives_time=i.gives_time, n_actions=i.actions)  # fmt: skip
    return PositionEncoder(d, i.max_steps, i.goal, i.step, i.observation_dims)


def pick_device(name: str) -> torch.device:
    """The device a name asks for.

    Args:
        name: "cpu", "cuda" or "auto" (CUDA when available, else the CPU).

    Returns:
        The `torch.device`.

    Raises:
        InvalidInputError: "cuda" where CUDA is not available.
    """
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    if name == "cuda" and not torch.cuda.is_available():
        raise InvalidInputError("device 'cuda' requested but CUDA is not available")
    return torch.device(name)


def _deterministic(mode: bool, warn_only: bool) -> None:
    """``torch.use_deterministic_algorithms`` without importing the compiler: the public call
    also sets ``torch._inductor``'s flag, and importing it costs about 1.5 s a process on 2
    cores. Nothing here compiles, so its flag is set only where it is already loaded."""
    eager = getattr(torch._C, "_set_deterministic_algorithms", None)
    if eager is None:  # another torch: the public call
        torch.use_deterministic_algorithms(mode, warn_only=warn_only)
        return
    eager(mode, warn_only=warn_only)
    inductor = sys.modules.get("torch._inductor.config")
    if inductor is not None:
        inductor.deterministic = mode


@contextlib.contextmanager
def torch_settings(device: torch.device) -> Iterator[None]:
    """A context of deterministic algorithms and, on the CPU, one thread; restored afterwards.

    The networks are tiny: one thread is faster than two and keeps CPU runs bit-reproducible.

    Args:
        device: Where the networks run.

    Yields:
        Nothing.
    """
    threads = torch.get_num_threads()
    deterministic = torch.are_deterministic_algorithms_enabled()
    warn_only = torch.is_deterministic_algorithms_warn_only_enabled()
    _deterministic(True, warn_only=True)
    if device.type == "cpu":
        torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(threads)
        _deterministic(deterministic, warn_only=warn_only)
