"""What a log teaches about a map, in a form that predicts anywhere: the fitted site offsets, the
receive gain by elevation, each cell's residual field and the spreads of the cells without one
([`fit_correction()`][rainuav.radio.measured.fitting.fit_correction] returns a
[`Correction`][rainuav.radio.measured.fitting.Correction]; steps 2-3 of
[`rainuav.radio.measured.correct`][rainuav.radio.measured.correct])."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np

from rainuav.errors import InvalidInputError
from rainuav.radio.measured.calibrate import BOUNDS, calibrate, calibrated_at, calibration_std_db
from rainuav.radio.measured.choice import AUTO, chosen, kernel_scores
from rainuav.radio.measured.log import MeasurementLog
from rainuav.radio.measured.pattern import (
    ElevationGain,
    HeadingGain,
    elevation_deg,
    fit_gain,
    fit_heading_gain,
    relative_azimuth_deg,
)
from rainuav.radio.measured.prior import engine_spread_at
from rainuav.radio.measured.residual import KERNELS, ResidualField, fit_residual, sample_spread
from rainuav.radio.outputs.mapdata import RadioMap

__all__ = ["MIN_FIELD_POINTS", "Correction", "fit_correction"]

MIN_FIELD_POINTS = 10
"""The fewest rows of a cell that give it a residual field."""


def _take(log: MeasurementLog, m: np.ndarray) -> MeasurementLog:
    return dataclasses.replace(
        log, x_m=log.x_m[m], y_m=log.y_m[m], z_m=log.z_m[m], alt_m=log.alt_m[m],
        cell=log.cell[m], rss_dbm=log.rss_dbm[m], flight=log.flight[m],
        time_s=None if log.time_s is None else log.time_s[m],
        sinr_db=None if log.sinr_db is None else log.sinr_db[m],
        heading_deg=None if log.heading_deg is None else log.heading_deg[m],
    )  # fmt: skip


def _heights(rm: RadioMap, log: MeasurementLog) -> np.ndarray:
    return log.z_m if rm.scenario.area.msl else log.alt_m


def _scale_at(scn: Any, log: MeasurementLog, prior: np.ndarray) -> np.ndarray:
    """The engine's own spread at each row (its cell's prior power there), dB: the scale a
    residual field may follow ([`rainuav.radio.measured.residual`][rainuav.radio.measured.residual],
    "Scaled")."""
    out = np.ones(len(log))
    for c in np.unique(log.cell):
        m = log.cell == c
        out[m] = engine_spread_at(scn, c, log.x_m[m], log.y_m[m], log.z_m[m], prior[m])
    return out


def _fields(
    rm: RadioMap, log: MeasurementLog, resid: np.ndarray, step: float, seed: int,
    like: dict[int, ResidualField] | None = None, max_points: int | None = None,
    scale: np.ndarray | None = None, kernel: str = "one-scale",
) -> dict[int, ResidualField]:  # fmt: skip
    a = rm.scenario.area
    pts = np.column_stack([log.x_m, log.y_m, _heights(rm, log)])
    extent = max(a.x_max_m - a.x_min_m, a.y_max_m - a.y_min_m)
    out = {}
    for c in np.unique(log.cell):
        m = log.cell == c
        if m.sum() < MIN_FIELD_POINTS or (like is not None and int(c) not in like):
            continue
        was = None if like is None else like[int(c)]
        sc = None if scale is None else scale[m]

        def one(k: str, was: ResidualField | None, m: np.ndarray = m, sc: Any = sc) -> Any:
            return fit_residual(
                pts[m], resid[m], size_m=a.resolution_m, step_m=step, extent_m=extent,
                seed=seed, like=was, scale=sc, kernel=k,
                **({} if max_points is None else {"max_points": max_points}),
            )  # fmt: skip

        if was is not None and was.candidates:  # a fold of a log that chose: choose again, on
            # this log's rows with the candidates' hyperparameters; condition the one kept
            cands = was.candidates
            got = kernel_scores(cands, pts[m], resid[m], step_m=step, seed=seed, scale=sc)
            field = one(chosen(got), cands[chosen(got)])
        elif was is None and kernel == AUTO:
            cands = {k: one(k, None) for k in KERNELS}
            got = kernel_scores(cands, pts[m], resid[m], step_m=step, seed=seed, scale=sc)
            field = cands[chosen(got)]
        else:
            out[int(c)] = one(kernel, was)
            continue
        out[int(c)] = dataclasses.replace(field, kernel_scores=got, candidates=cands)
    return out


@dataclasses.dataclass
class Correction:
    """What a log says about a map: the fitted site offsets, each cell's residual field, and the
    spreads of the cells it has no field for; a predictive distribution at any point
    ([`predict()`][rainuav.radio.measured.fitting.Correction.predict])."""

    scenario: Any
    """The map's scenario."""
    fits: list[Any]
    """Per measured cell, the fitted offsets
    ([`CellFit`][rainuav.radio.measured.calibrate.CellFit])."""
    fields: dict[int, ResidualField]
    """Per cell with enough rows, its residual field."""
    other_local_db: float
    """The local mean's deviation of a cell without a field, dB."""
    other_sample_db: float
    """One sample's deviation of a cell without a field, dB."""
    msl: bool = False
    """Whether the fields' height is above sea level (the map's altitude reference)."""
    receive: ElevationGain | None = None
    """The UAV's receive gain by elevation, where one was fitted
    ([`rainuav.radio.measured.pattern`][rainuav.radio.measured.pattern])."""
    heading: HeadingGain | None = None
    """The UAV's receive gain against its heading, where one was fitted (the same module)."""

    def receive_at(self, log: MeasurementLog) -> np.ndarray:
        """The receive gain at a log's rows, dB (0 without one; the heading's where the log gives
        it).

        Args:
            log: The log.

        Returns:
            (N,) dB.
        """
        scn = self.scenario
        out = np.zeros(len(log))
        if self.receive is not None:
            out += self.receive.at(elevation_deg(scn, log.cell, log.x_m, log.y_m, log.z_m))
        if self.heading is not None and log.heading_deg is not None:
            rel = relative_azimuth_deg(scn, log.cell, log.x_m, log.y_m, log.heading_deg)
            out += self.heading.at(rel)
        return out

    def predict(
        self, log: MeasurementLog, prior: np.ndarray, *, fields: bool = True,
        far: dict[int, ResidualField] | None = None,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
        """The corrected power at a log's rows, with the local mean's and one sample's deviation.

        Args:
            log: The rows (their cells and positions).
            prior: Their prior powers (N,), dBm.
            fields: False: the calibrated map alone, each measured cell's local deviation its
                field's far from every measurement.
            far: The fields whose far deviation to use (default the correction's own).

        Returns:
            `(power dBm, local deviation dB, sample deviation dB)`, (N,) each.
        """
        scn = self.scenario
        mean = calibrated_at(scn, log, prior, self.fits) + self.receive_at(log)
        local = np.full(len(log), self.other_local_db)
        sample = np.full(len(log), self.other_sample_db)
        pts = np.column_stack([log.x_m, log.y_m, log.z_m if self.msl else log.alt_m])
        used = self.fields if fields else (far or self.fields)
        scale = _scale_at(scn, log, prior) if any(f.scaled for f in used.values()) else None
        for c, f in used.items():
            m = log.cell == c
            if not m.any():
                continue
            sample[m] = f.sample_db
            at = None if scale is None else scale[m]
            if fields:
                mean[m] += f.mean(pts[m], at)
                local[m] = f.std(pts[m], at)
            else:
                local[m] = f.far_at(int(m.sum()), at)
        for fc in self.fits:
            m = log.cell == fc.cell
            if fc.offsets and m.any():
                local[m] = np.hypot(
                    local[m], calibration_std_db(scn, fc, log.x_m[m], log.y_m[m], log.z_m[m])
                )
        return mean, local, sample


def fit_correction(
    rm: RadioMap, log: MeasurementLog, prior: np.ndarray, *,
    params: Sequence[str] = tuple(BOUNDS), level_step_m: float = 10.0, seed: int = 0,
    like: Correction | None = None, max_points: int | None = None, receive: bool = False,
    heading: bool = False, kernel: str = "one-scale",
) -> Correction:  # fmt: skip
    """Steps 2-3 of the module's docstring on a log: the offsets, the fields and the spreads.

    The spreads of the cells without a field too.

    Args:
        rm: The prior map.
        log: The log.
        prior: Its rows' prior powers (N,), dBm.
        params: The site parameters calibrated.
        level_step_m: The height between the maps built at the log's heights, m.
        seed: The fits' seed.
        like: A correction of more of the log whose hyperparameters to reuse (a cross-validation
            fold).
        max_points: The most bins a field is conditioned on.
        receive: Fit the UAV's receive gain by elevation before the fields
            ([`rainuav.radio.measured.pattern`][rainuav.radio.measured.pattern]).
        heading: Fit its gain against its heading (the log needs `heading_deg`).
        kernel: The residual fields' kernel: one of
            [`KERNELS`][rainuav.radio.measured.residual.KERNELS], or "auto" (each cell's chosen by
            its held-out density, [`rainuav.radio.measured.choice`][rainuav.radio.measured.choice]);
            a `like`'s own where given, chosen again on this log where `like` chose.

    Returns:
        The [`Correction`][rainuav.radio.measured.fitting.Correction].

    Raises:
        InvalidInputError: A heading gain asked of a log without headings.
    """
    scn = rm.scenario
    fits = calibrate(scn, log, prior, params, near=None if like is None else like.fits)
    resid = log.rss_dbm - calibrated_at(scn, log, prior, fits)
    gain = None
    if receive:
        el = elevation_deg(scn, log.cell, log.x_m, log.y_m, log.z_m)
        gain = fit_gain(el, resid)
        resid = resid - gain.at(el)
    by_heading = None
    if heading:
        if log.heading_deg is None or not np.isfinite(log.heading_deg).any():
            raise InvalidInputError(
                f"{log.source or 'the log'}: a receive gain against the heading needs a "
                "heading_deg column"
            )
        rel = relative_azimuth_deg(scn, log.cell, log.x_m, log.y_m, log.heading_deg)
        by_heading = fit_heading_gain(rel, resid)
        resid = resid - by_heading.at(rel)
    fields = _fields(rm, log, resid, level_step_m, seed,
                     None if like is None else like.fields, max_points,
                     _scale_at(scn, log, prior), kernel)  # fmt: skip
    pooled = float(np.sqrt(np.mean((log.rss_dbm - prior) ** 2)))
    if like is not None:
        sample = like.other_sample_db
    elif fields:
        sample = float(np.sqrt(np.mean([f.sample_db**2 for f in fields.values()])))
    else:
        h = _heights(rm, log)
        sample = sample_spread(log.x_m, log.y_m, h, resid, scn.area.resolution_m, level_step_m)
        sample = 0.0 if not np.isfinite(sample) else sample
    return Correction(scn, fits, fields, pooled, sample, bool(scn.area.msl), gain, by_heading)
