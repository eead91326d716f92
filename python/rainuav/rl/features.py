"""What the networks compute from the observation alone: goal-relative features, and the geometry
a network needs to read the destination move by move."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
import torch

from rainuav.nav.task import MOVES

__all__ = ["MoveGeometry", "goal_features"]


def goal_features(rel: Any, scale: Any) -> Any:
    """Goal-relative features `tanh(rel / scale)` per axis and scale (numpy or torch).

    Args:
        rel: Offsets to the destination (N, 2).
        scale: The scales (2, K).

    Returns:
        (N, 2K).
    """
    if isinstance(rel, torch.Tensor):
        return torch.tanh(rel[:, :, None] / scale).flatten(1)
    return np.tanh(rel[:, :, None] / scale).reshape(len(rel), -1)


@dataclass(frozen=True)
class MoveGeometry:
    """What a network needs to read the destination move by move: the area's sides
    ``span_m`` (the observation's positions are fractions of them), the move ``step_m`` and
    the arrival radius ``tol_m``, m."""

    span_m: tuple[float, float]
    step_m: float
    tol_m: float
    per_move: ClassVar[int] = 2
    """Features per move: arrival, progress."""

    @property
    def shifts_m(self) -> np.ndarray:
        """(4, 2): each move's displacement, m, in the env's action order."""
        return (self.step_m * MOVES).astype(np.float32)
