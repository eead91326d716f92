"""Random storms: moving, growing and decaying convective cells over a uniform background, drawn
from one documented distribution ([`draw_storm()`][rainuav.radio.scene.storms.draw_storm]), the
weather of the ``storm`` preset.

The distribution (every draw from ``numpy.random.default_rng(seed)``, in this order):

- background: uniform rain of ``U(0, 10)`` mm/h over the whole area;
- 1 to 4 Gaussian cells (uniform count);
- one storm velocity: speed ``U(5, 20)`` m/s in a direction uniform in [0, 360) degrees; each
  cell's velocity is the storm's plus a vector uniform in the disc of radius 2 m/s (cells of
  one storm move together, not in lockstep);
- per cell: peak rate at mid-storm log-uniform in [30, 150] mm/h, 1/e radius ``U(200, 800)``
  m, and an e-folding time of its peak of ``U(10, 30)`` minutes, growing or decaying with equal
  odds;
- per cell, its centre at mid-storm (``STORM_DURATION_S / 2`` = 150 s) uniform in the area, so
  that each cell crosses the area during the storm's 300 s; its position at time 0 follows from
  its velocity.

Storm seeds at or above [`EVAL_SEEDS_FROM`][rainuav.radio.scene.storms.EVAL_SEEDS_FROM] are reserved
for evaluation: nothing is trained or tuned on them (``check_storm_seed`` refuses them where
training asks)."""

from __future__ import annotations

import math

import numpy as np

from rainuav._checks import check_integer, check_number
from rainuav.errors import InvalidInputError
from rainuav.radio.scene.weather import Medium, RainCell

__all__ = [
    "EVAL_SEEDS_FROM",
    "STORM_DURATION_S",
    "check_storm_seed",
    "draw_storm",
]

STORM_DURATION_S = 300.0
"""How long a storm of the distribution lasts, s: a UAV at 10 m/s crossing the 2 km area."""
EVAL_SEEDS_FROM = 1_000_000
"""Storm seeds from here on are the evaluation storms: never trained or tuned on."""
MAX_STORM_SEED = 2**63 - 1
BACKGROUND_MM_H = (0.0, 10.0)
CELLS = (1, 4)
STORM_SPEED_M_S = (5.0, 20.0)
CELL_SPREAD_M_S = 2.0
PEAK_MM_H = (30.0, 150.0)
RADIUS_M = (200.0, 800.0)
EFOLD_MIN = (10.0, 30.0)


def check_storm_seed(seed: object, training: bool = False) -> int:
    """A storm seed, checked.

    Args:
        seed: The seed given.
        training: Refuse the evaluation storms (from
            [`EVAL_SEEDS_FROM`][rainuav.radio.scene.storms.EVAL_SEEDS_FROM]).

    Returns:
        The seed as an int in 0..2^63-1.

    Raises:
        InvalidInputError: Not such an int, or an evaluation storm where training.
    """
    hi = EVAL_SEEDS_FROM - 1 if training else MAX_STORM_SEED
    try:
        return check_integer("storm_seed", seed, 0, hi)
    except InvalidInputError as err:
        if training and isinstance(seed, int) and seed >= EVAL_SEEDS_FROM:
            raise InvalidInputError(
                f"storm_seed {seed} is an evaluation storm (seeds from {EVAL_SEEDS_FROM}); "
                f"train on seeds 0..{EVAL_SEEDS_FROM - 1}"
            ) from err
        raise


def draw_storm(
    seed: int,
    extent_m: tuple[float, float, float, float] = (0.0, 2000.0, 0.0, 2000.0),
    speed_m_s: float | None = None,
) -> Medium:
    """The storm of a seed over an area, as a weather whose cells move.

    [`Medium.at()`][rainuav.radio.scene.weather.Medium.at] gives it at any instant; time 0 is the
    storm's start. The distribution is the module docstring's.

    Args:
        seed: The storm.
        extent_m: The area `(x0, x1, y0, y1)`, m.
        speed_m_s: The storm's speed, m/s, where given: every cell's velocity scaled by one factor
            (the same draws; 0 keeps each cell at its mid-storm place).

    Returns:
        The [`Medium`][rainuav.radio.scene.weather.Medium].
    """
    rng = np.random.default_rng(check_storm_seed(seed))
    if speed_m_s is not None:
        speed_m_s = check_number("speed_m_s", speed_m_s, 0.0, 100.0, " m/s")
    x0, x1, y0, y1 = extent_m
    background = float(rng.uniform(*BACKGROUND_MM_H))
    n = int(rng.integers(CELLS[0], CELLS[1] + 1))
    speed = float(rng.uniform(*STORM_SPEED_M_S))
    heading = float(rng.uniform(0.0, 2.0 * math.pi))
    vx, vy = speed * math.cos(heading), speed * math.sin(heading)
    scale = 1.0 if speed_m_s is None else speed_m_s / speed
    mid = STORM_DURATION_S / 2.0
    cells = []
    for _ in range(n):
        r, a = CELL_SPREAD_M_S * math.sqrt(float(rng.uniform())), float(rng.uniform(0, 2 * math.pi))
        cvx, cvy = scale * (vx + r * math.cos(a)), scale * (vy + r * math.sin(a))
        peak = float(math.exp(rng.uniform(math.log(PEAK_MM_H[0]), math.log(PEAK_MM_H[1]))))
        radius = float(rng.uniform(*RADIUS_M))
        efold = 60.0 * float(rng.uniform(*EFOLD_MIN)) * (1.0 if rng.uniform() < 0.5 else -1.0)
        xm, ym = float(rng.uniform(x0, x1)), float(rng.uniform(y0, y1))
        # The peak given is the one at mid-storm; at time 0 it is that times exp(-mid/efold).
        cells.append(
            RainCell(
                x_m=xm - cvx * mid,
                y_m=ym - cvy * mid,
                radius_m=radius,
                peak_rate_mm_h=peak * math.exp(-mid / efold),
                vx_m_s=cvx,
                vy_m_s=cvy,
                growth_s=efold,
            )
        )
    weather = Medium(kind="cells", rain_rate_mm_h=background, cells=cells)
    weather.check("storm")
    return weather
