"""The building effect of the ray engine against the tracer's, site by site: the statistic the
comparisons report ([`compare()`][rainuav.radio.reference.comparison.compare])."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from rainuav.radio.reference.tracer import FLOOR_DB, MAX_NOISE_DB, SHADOW_DB, TracerMap

__all__ = ["Agreement", "agreement"]


@dataclass(frozen=True)
class Agreement:
    """The building effect of the ray engine against the tracer's over the pixels both cover
    (one value a site, dB unless said)."""

    pixels: np.ndarray
    """Pixels compared."""
    noisy: np.ndarray
    """Pixels the tracer covers but left out: its noise above the tolerance."""
    shadow_pixels: np.ndarray
    """Of these, where the tracer sees a shadow (effect below
    [`SHADOW_DB`][rainuav.radio.reference.tracer.SHADOW_DB])."""
    shadow_median: np.ndarray
    """Median of |engine - tracer| in the tracer's shadow."""
    shadow_p90: np.ndarray
    """90th percentile of |engine - tracer| there."""
    shadow_bias: np.ndarray
    """Median of engine - tracer there (negative: the engine's shadows are deeper)."""
    light_median: np.ndarray
    """Median of |engine - tracer| where the tracer sees light."""
    classes_agree: np.ndarray
    """Share of pixels on which shadow and light agree."""
    noise_median: np.ndarray
    """Median over the shadow of the tracer's own noise, |half a - half b| / 2 in dB."""

    def rows(self) -> list[dict[str, float]]:
        """The comparison as one dict a site.

        Returns:
            The fields' values by name, one dict a site.
        """
        names = [f.name for f in dataclasses.fields(self)]
        return [{n: float(getattr(self, n)[k]) for n in names} for k in range(len(self.pixels))]


def _q(v: np.ndarray, p: float) -> float:
    return float(np.percentile(v, p)) if v.size else float("nan")


def _db(x: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore"):
        return 10.0 * np.log10(x)


def agreement(
    engine_with: np.ndarray,
    engine_without: np.ndarray,
    tracer_with: TracerMap,
    tracer_without: TracerMap,
    inside: np.ndarray,
    max_noise_db: float = MAX_NOISE_DB,
) -> Agreement:
    """Compares the building effects site by site (the module's docstring).

    Args:
        engine_with: The engine's gain with the buildings (S, H, W).
        engine_without: Without them.
        tracer_with: The tracer's with them.
        tracer_without: Without them.
        inside: Pixels where the UAV would be inside a building (H, W), left out.
        max_noise_db: Pixels where the tracer's halves differ by more than twice this are left out
            (its own estimate is uncertain there by more than the tolerance; counted in `noisy`).

    Returns:
        The [`Agreement`][rainuav.radio.reference.agreement.Agreement].
    """
    with np.errstate(invalid="ignore"):
        return _agreement(engine_with, engine_without, tracer_with, tracer_without, inside,
                          max_noise_db)  # fmt: skip


def _agreement(
    engine_with: np.ndarray,
    engine_without: np.ndarray,
    tracer_with: TracerMap,
    tracer_without: TracerMap,
    inside: np.ndarray,
    max_noise_db: float,
) -> Agreement:
    ours = np.maximum(_db(engine_with) - _db(engine_without), FLOOR_DB)
    ref = np.maximum(_db(tracer_with.gain) - _db(tracer_without.gain), FLOOR_DB)
    noise = 0.5 * np.abs(_db(tracer_with.half_a) - _db(tracer_with.half_b))
    covered = tracer_with.covered & tracer_without.covered & ~inside[None] & np.isfinite(ours)
    ok = covered & (noise <= max_noise_db)
    stats: dict[str, list[float]] = {f.name: [] for f in dataclasses.fields(Agreement)}
    for k in range(ours.shape[0]):
        o, r, n = ours[k][ok[k]], ref[k][ok[k]], noise[k][ok[k]]
        dark = r < SHADOW_DB
        err = o - r

        stats["pixels"].append(float(o.size))
        stats["noisy"].append(float((covered[k] & ~ok[k]).sum()))
        stats["shadow_pixels"].append(float(dark.sum()))
        stats["shadow_median"].append(_q(np.abs(err[dark]), 50))
        stats["shadow_p90"].append(_q(np.abs(err[dark]), 90))
        stats["shadow_bias"].append(_q(err[dark], 50))
        stats["light_median"].append(_q(np.abs(err[~dark]), 50))
        stats["classes_agree"].append(
            float(np.mean((o < SHADOW_DB) == dark)) if o.size else float("nan")
        )
        stats["noise_median"].append(_q(n[dark], 50))
    return Agreement(**{k: np.asarray(v) for k, v in stats.items()})
