"""A physics map corrected by what was measured:
[`correct_map()`][rainuav.radio.measured.correct.correct_map].

1. The prior at the log's points
   ([`prior_at()`][rainuav.radio.measured.calibrate.prior_at]).
2. Per cell, the site parameters fitted to the log
   ([`calibrate()`][rainuav.radio.measured.calibrate.calibrate]) and the map moved by them.
3. Per cell, the residual (measured minus calibrated) as a Gaussian-process field
   ([`rainuav.radio.measured.residual`][rainuav.radio.measured.residual]): the corrected power is
   the calibrated map plus the field's mean, its standard deviation the field's and the fitted
   offsets' own (their covariance carried to the power,
   [`calibration_std_db()`][rainuav.radio.measured.calibrate.calibration_std_db]), added in
   quadrature. A cell the log does not measure keeps its prior power, with the prior's RMS
   error over every logged row as its deviation (how far this map is off, typically).
4. The serving cell, SIR and SINR again from the corrected powers.
5. The error at points the fit did not see: the whole of 2-3 again with one flight left out
   (the log's ``flight`` column), else one height bin, else one ninth of the area (a 3 x 3 grid),
   each in turn; the kernels' hyperparameters are those fitted on the whole log."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np

from rainuav.errors import InvalidInputError
from rainuav.radio.measured.calibrate import (
    BOUNDS,
    calibrate,
    calibrated_at,
    calibrated_maps,
    calibration_std_db,
    prior_at,
)
from rainuav.radio.measured.log import MeasurementLog
from rainuav.radio.measured.residual import ResidualField, fit_residual
from rainuav.radio.outputs.mapdata import RadioMap
from rainuav.radio.outputs.sinr import RSS_FLOOR_DBM, sir_from_power
from rainuav.radio.scene.terrain import flight_heights

__all__ = ["MIN_FIELD_POINTS", "correct_map"]

MIN_FIELD_POINTS = 10
"""The fewest rows of a cell that give it a residual field."""


def _take(log: MeasurementLog, m: np.ndarray) -> MeasurementLog:
    return dataclasses.replace(
        log, x_m=log.x_m[m], y_m=log.y_m[m], z_m=log.z_m[m], alt_m=log.alt_m[m],
        cell=log.cell[m], rss_dbm=log.rss_dbm[m], flight=log.flight[m],
        time_s=None if log.time_s is None else log.time_s[m],
        sinr_db=None if log.sinr_db is None else log.sinr_db[m],
    )  # fmt: skip


def _heights(rm: RadioMap, log: MeasurementLog) -> np.ndarray:
    return log.z_m if rm.scenario.area.msl else log.alt_m


def _fields(
    rm: RadioMap, log: MeasurementLog, resid: np.ndarray, step: float, seed: int,
    like: dict[int, ResidualField] | None = None,
) -> dict[int, ResidualField]:  # fmt: skip
    a = rm.scenario.area
    pts = np.column_stack([log.x_m, log.y_m, _heights(rm, log)])
    extent = max(a.x_max_m - a.x_min_m, a.y_max_m - a.y_min_m)
    out = {}
    for c in np.unique(log.cell):
        m = log.cell == c
        if m.sum() < MIN_FIELD_POINTS or (like is not None and int(c) not in like):
            continue
        out[int(c)] = fit_residual(
            pts[m], resid[m], size_m=a.resolution_m, step_m=step, extent_m=extent, seed=seed,
            like=None if like is None else like[int(c)],
        )  # fmt: skip
    return out


def correct_map(
    rm: RadioMap,
    log: MeasurementLog,
    *,
    params: Sequence[str] = tuple(BOUNDS),
    level_step_m: float = 10.0,
    seed: int = 0,
    cross_validate: bool = True,
    build: Any = None,
) -> RadioMap:
    """``rm`` corrected by ``log`` (module docstring): ``rss_dbm``, the serving cell, SIR and
    SINR corrected; ``prior_rss_dbm`` the map given; ``rss_std_db`` each pixel's deviation;
    ``fit`` the fitted parameters, fields and cross-validated error. ``params``: the site
    parameters calibrated (names of
    [`BOUNDS`][rainuav.radio.measured.calibrate.BOUNDS]; empty: none); ``level_step_m``: the
    height bins; ``seed``: the draw of the hyperparameters' fitting subset; ``build``: how maps at
    the log's heights are built (default the cached
    [`build_radio_map`][rainuav.radio.outputs.maps.build_radio_map])."""
    if rm.rss_std_db is not None:
        raise InvalidInputError("the map is already corrected by measurements: correct its prior")
    if not 1.0 <= level_step_m <= 500.0:
        raise InvalidInputError(f"level_step_m must lie within 1..500 m (got {level_step_m:g})")
    scn = rm.scenario
    prior = prior_at(rm, log, level_step_m, build)
    fits = calibrate(scn, log, prior, params)
    resid = log.rss_dbm - calibrated_at(scn, log, prior, fits)
    fields = _fields(rm, log, resid, level_step_m, seed)
    if not fields:
        raise InvalidInputError(
            f"{log.source or 'the log'}: no cell has {MIN_FIELD_POINTS} usable rows; too few "
            "measurements to correct a map"
        )
    cal = calibrated_maps(rm, fits)
    reached = rm.rss_dbm > RSS_FLOOR_DBM + 1.0
    pooled = float(np.sqrt(np.mean((log.rss_dbm - prior) ** 2)))
    std = np.full(cal.shape, pooled)
    h = np.full(scn.area.shape, rm.altitude_m)
    for c, f in fields.items():
        mean, std[c] = f.on_grid(rm.x_m, rm.y_m, h)
        cal[c] = np.where(reached[c], cal[c] + mean, cal[c])
    gx, gy = np.meshgrid(rm.x_m, rm.y_m)
    gz = flight_heights(scn)
    for fc in fits:  # the fitted offsets' own uncertainty, independent of the residual's
        if fc.offsets:
            std[fc.cell] = np.hypot(std[fc.cell], calibration_std_db(scn, fc, gx, gy, gz))
    cal = np.where(reached, np.clip(cal, RSS_FLOOR_DBM, 100.0), RSS_FLOOR_DBM)
    power = np.where(reached, 10.0 ** (cal / 10.0), 0.0)
    serving, sir, sinr = sir_from_power(power, scn.noise_power_dbm)
    fit: dict[str, Any] = {
        "log": log.summary(),
        "rows": log.rows,
        "rows_used": len(log),
        "skipped": log.skipped,
        "level_step_m": level_step_m,
        "calibration": [f.to_dict() for f in fits],
        "residual": [_field_dict(c, f) for c, f in fields.items()],
        "unmeasured_cells_std_db": pooled,
    }
    if cross_validate:
        fit["cross_validation"] = _cross_validate(
            rm, log, prior, params, level_step_m, seed, fields, fits
        )
    return dataclasses.replace(
        rm, rss_dbm=cal, serving_cell=serving, sir_db=sir, sinr_db=sinr,
        prior_rss_dbm=np.asarray(rm.rss_dbm, dtype=float), rss_std_db=std, fit=fit,
        build_seconds=0.0, timings={},
    )  # fmt: skip


def _field_dict(c: int, f: ResidualField) -> dict[str, Any]:
    return {
        "cell": c, "amplitude_db": f.amplitude_db, "noise_db": f.noise_db,
        "length_m": f.length_m,
        "height_length_m": f.length_m / f.height_ratio if f.height_ratio else None,
        "bins": f.bins, "bin_m": f.bin_m,
    }  # fmt: skip


def _groups(rm: RadioMap, log: MeasurementLog, step: float) -> tuple[str, np.ndarray]:
    if len(np.unique(log.flight)) >= 2:
        return "flight", log.flight
    hb = np.round(_heights(rm, log) / step).astype(np.int64)
    if len(np.unique(hb)) >= 2:
        return "height", hb
    a = rm.scenario.area
    gx = np.clip((3 * (log.x_m - a.x_min_m) / (a.x_max_m - a.x_min_m)).astype(int), 0, 2)
    gy = np.clip((3 * (log.y_m - a.y_min_m) / (a.y_max_m - a.y_min_m)).astype(int), 0, 2)
    return "block", gx + 3 * gy


def _cross_validate(
    rm: RadioMap, log: MeasurementLog, prior: np.ndarray, params: Sequence[str], step: float,
    seed: int, fields: dict[int, ResidualField], whole: list[Any],
) -> dict[str, Any]:  # fmt: skip
    scn = rm.scenario
    kind, group = _groups(rm, log, step)
    err = {k: np.full(len(log), np.nan) for k in ("prior", "calibrated", "corrected")}
    sigma = np.full(len(log), np.nan)
    for g in np.unique(group):
        test, train = group == g, group != g
        tr, te = _take(log, train), _take(log, test)
        fits = calibrate(scn, tr, prior[train], params, near=whole)
        resid = tr.rss_dbm - calibrated_at(scn, tr, prior[train], fits)
        fl = _fields(rm, tr, resid, step, seed, fields)
        cal_te = calibrated_at(scn, te, prior[test], fits)
        corr, sd = cal_te.copy(), np.full(len(te), np.nan)
        pts = np.column_stack([te.x_m, te.y_m, _heights(rm, te)])
        for c, f in fl.items():
            m = te.cell == c
            if m.any():
                corr[m] += f.mean(pts[m])
                sd[m] = np.hypot(f.std(pts[m]), f.noise_db)
        for fc in fits:
            m = te.cell == fc.cell
            if fc.offsets and m.any():
                sd[m] = np.hypot(
                    sd[m], calibration_std_db(scn, fc, te.x_m[m], te.y_m[m], te.z_m[m])
                )
        idx = np.flatnonzero(test)
        err["prior"][idx] = te.rss_dbm - prior[test]
        err["calibrated"][idx] = te.rss_dbm - cal_te
        err["corrected"][idx] = te.rss_dbm - corr
        sigma[idx] = sd
    ok = np.isfinite(sigma)
    out: dict[str, Any] = {"left_out": kind, "folds": len(np.unique(group)),
                           "points": int(ok.sum())}  # fmt: skip
    for k, e in err.items():
        out[k] = {"rmse_db": float(np.sqrt(np.mean(e[ok] ** 2))) if ok.any() else None,
                  "median_abs_db": float(np.median(np.abs(e[ok]))) if ok.any() else None,
                  "bias_db": float(np.mean(e[ok])) if ok.any() else None}  # fmt: skip
    out["within_one_sigma"] = (
        float(np.mean(np.abs(err["corrected"][ok]) <= sigma[ok])) if ok.any() else None
    )
    return out
