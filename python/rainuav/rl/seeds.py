"""Every random choice of a run from its one seed: independent streams for the agent and the
environment."""

from __future__ import annotations

import numpy as np

__all__ = ["random_streams"]


def random_streams(seed: int) -> dict[str, np.random.SeedSequence]:
    """Independent seed sequences for every random choice of a run, all from one seed.

    Seeding both generators with `seed` itself would make them draw the same stream
    (`SeedSequence.spawn` keeps them apart).

    Args:
        seed: The run's seed.

    Returns:
        `"agent"` (exploration and replay sampling) and `"env"` (training starts).
    """
    agent, env = np.random.SeedSequence(seed).spawn(2)
    return {"agent": agent, "env": env}
