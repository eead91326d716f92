"""A physics map corrected by what was measured:
[`correct_map()`][rainuav.radio.measured.correct.correct_map].

1. The prior at the log's points
   ([`prior_at()`][rainuav.radio.measured.calibrate.prior_at]).
2. Per cell, the site parameters fitted to the log
   ([`calibrate()`][rainuav.radio.measured.calibrate.calibrate]) and the map moved by them.
3. Per cell, the residual (measured minus calibrated) as a Gaussian-process field
   ([`rainuav.radio.measured.residual`][rainuav.radio.measured.residual]): the corrected power is
   the calibrated map plus the field's mean. Its two spreads: the **local mean's**
   (``rss_std_db``: the field's deviation with its nugget, and the fitted offsets' own,
   their covariance carried to the power by
   [`calibration_std_db()`][rainuav.radio.measured.calibrate.calibration_std_db], in
   quadrature) and **one sample's** around it (``rss_sample_std_db``: the rows' scatter within
   the field's bins). A cell the log does not measure keeps its prior power, with the prior's
   RMS error over every logged row as its local deviation and the measured cells' sample
   spread.
4. The serving cell, SIR and SINR again from the corrected powers.
5. The error at points the fit did not see
   ([`rainuav.radio.measured.scores`][rainuav.radio.measured.scores]), in two designs: one
   flight left out at a time (the log's ``flight`` column; a flight at one height is a height
   left out), else one height bin, where the log has two; and a stretch of every flight left
   out (``STRETCHES`` contiguous stretches of each flight's rows in time, one at a time: blocks,
   not random rows, because neighbouring samples are correlated). Every held-out row is scored,
   single samples and 10 m local means, for the corrected map and for the baselines a user
   would otherwise use: the prior with its spreads by mechanism
   ([`rainuav.radio.measured.prior`][rainuav.radio.measured.prior]), the prior with only its
   power fitted, the calibrated map without a field, the ``KNN`` nearest logged samples in
   3-D, and ordinary kriging (the same Gaussian process on the measurements alone, about their
   mean). The kernels' hyperparameters are those fitted on the whole log."""

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
from rainuav.radio.measured.pattern import ElevationGain, elevation_deg, fit_gain
from rainuav.radio.measured.prior import excess_at, spreads_of
from rainuav.radio.measured.residual import ResidualField, fit_residual, sample_spread
from rainuav.radio.measured.scores import local_means, score
from rainuav.radio.outputs.mapdata import RadioMap
from rainuav.radio.outputs.sinr import RSS_FLOOR_DBM, sir_from_power
from rainuav.radio.scene.terrain import flight_heights

__all__ = [
    "CV_MAX_POINTS",
    "KNN",
    "MIN_FIELD_POINTS",
    "STRETCHES",
    "Correction",
    "correct_map",
    "cross_validate_log",
    "designs",
    "fit_correction",
    "held_out_line",
]

MIN_FIELD_POINTS = 10
"""The fewest rows of a cell that give it a residual field."""
STRETCHES = 5
"""The stretches each flight is cut into for the held-out stretches' design."""
KNN = 25
"""The nearest logged samples the nearest-neighbour baseline averages."""
RECEIVE_PATTERNS = ("off", "elevation")
"""What ``correct_map``'s ``receive_pattern`` may be."""
CV_MAX_POINTS = 1000
"""The most bins a cross-validation fold's fields are conditioned on (the map's own: 2 500)."""


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
    like: dict[int, ResidualField] | None = None, max_points: int | None = None,
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
            **({} if max_points is None else {"max_points": max_points}),
        )  # fmt: skip
    return out


@dataclasses.dataclass
class Correction:
    """What a log says about a map: the fitted site offsets, each cell's residual field, and the
    spreads of the cells it has no field for; a predictive distribution at any point
    ([`predict()`][rainuav.radio.measured.correct.Correction.predict])."""

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

    def receive_at(self, log: MeasurementLog) -> np.ndarray:
        """The receive gain at the rows of ``log``, dB (0 without one)."""
        if self.receive is None:
            return np.zeros(len(log))
        return self.receive.at(elevation_deg(self.scenario, log.cell, log.x_m, log.y_m, log.z_m))

    def predict(
        self, log: MeasurementLog, prior: np.ndarray, *, fields: bool = True,
        far: dict[int, ResidualField] | None = None,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
        """At the rows of ``log`` (their cells and positions) whose prior powers are ``prior``,
        (N,): the corrected power, the local mean's and one sample's deviation, dB, (N,)
        each. ``fields`` False: the calibrated map alone, each measured cell's local deviation
        its field's far from every measurement (of ``far``'s fields, default its own)."""
        scn = self.scenario
        mean = calibrated_at(scn, log, prior, self.fits) + self.receive_at(log)
        local = np.full(len(log), self.other_local_db)
        sample = np.full(len(log), self.other_sample_db)
        pts = np.column_stack([log.x_m, log.y_m, log.z_m if self.msl else log.alt_m])
        for c, f in (self.fields if fields else (far or self.fields)).items():
            m = log.cell == c
            if not m.any():
                continue
            sample[m] = f.sample_db
            if fields:
                mean[m] += f.mean(pts[m])
                local[m] = f.std(pts[m])
            else:
                local[m] = f.far_db
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
) -> Correction:  # fmt: skip
    """Steps 2-3 of the module docstring on ``log``, whose rows' prior powers are ``prior``:
    the offsets, the fields and the spreads of the cells without one. ``like``: a correction
    of more of the log whose hyperparameters to reuse (a cross-validation fold);
    ``receive``: fit the UAV's receive gain by elevation before the fields
    ([`rainuav.radio.measured.pattern`][rainuav.radio.measured.pattern])."""
    scn = rm.scenario
    fits = calibrate(scn, log, prior, params, near=None if like is None else like.fits)
    resid = log.rss_dbm - calibrated_at(scn, log, prior, fits)
    gain = None
    if receive:
        el = elevation_deg(scn, log.cell, log.x_m, log.y_m, log.z_m)
        gain = fit_gain(el, resid)
        resid = resid - gain.at(el)
    fields = _fields(rm, log, resid, level_step_m, seed,
                     None if like is None else like.fields, max_points)  # fmt: skip
    pooled = float(np.sqrt(np.mean((log.rss_dbm - prior) ** 2)))
    if like is not None:
        sample = like.other_sample_db
    elif fields:
        sample = float(np.sqrt(np.mean([f.sample_db**2 for f in fields.values()])))
    else:
        h = _heights(rm, log)
        sample = sample_spread(log.x_m, log.y_m, h, resid, scn.area.resolution_m, level_step_m)
        sample = 0.0 if not np.isfinite(sample) else sample
    return Correction(scn, fits, fields, pooled, sample, bool(scn.area.msl), gain)


def correct_map(
    rm: RadioMap,
    log: MeasurementLog,
    *,
    params: Sequence[str] = tuple(BOUNDS),
    level_step_m: float = 10.0,
    seed: int = 0,
    cross_validate: bool = True,
    build: Any = None,
    receive_pattern: str = "off",
) -> RadioMap:
    """``rm`` corrected by ``log`` (module docstring): ``rss_dbm``, the serving cell, SIR and
    SINR corrected; ``prior_rss_dbm`` the map given; ``rss_std_db`` each pixel's local-mean
    deviation and ``rss_sample_std_db`` one sample's around it; ``fit`` the fitted parameters,
    fields and held-out scores. ``params``: the site parameters calibrated (names of
    [`BOUNDS`][rainuav.radio.measured.calibrate.BOUNDS]; empty: none); ``level_step_m``: the
    height bins; ``seed``: the draw of the hyperparameters' fitting subset; ``build``: how maps at
    the log's heights are built (default the cached
    [`build_radio_map`][rainuav.radio.outputs.maps.build_radio_map]); ``receive_pattern``:
    ``"off"`` or ``"elevation"`` (the UAV's receive gain by elevation fitted before the fields,
    [`rainuav.radio.measured.pattern`][rainuav.radio.measured.pattern]; the held-out scores then
    fit it in every fold, so ``fit.json`` says whether it helped)."""
    if receive_pattern not in RECEIVE_PATTERNS:
        raise InvalidInputError(
            f"receive_pattern must be one of {', '.join(RECEIVE_PATTERNS)} "
            f"(got {receive_pattern!r})"
        )
    if rm.prior_rss_dbm is not None:
        raise InvalidInputError("the map is already corrected by measurements: correct its prior")
    if not 1.0 <= level_step_m <= 500.0:
        raise InvalidInputError(f"level_step_m must lie within 1..500 m (got {level_step_m:g})")
    scn = rm.scenario
    prior = prior_at(rm, log, level_step_m, build)
    receive = receive_pattern == "elevation"
    corr = fit_correction(rm, log, prior, params=params, level_step_m=level_step_m, seed=seed,
                          receive=receive)  # fmt: skip
    if not corr.fields:
        raise InvalidInputError(
            f"{log.source or 'the log'}: no cell has {MIN_FIELD_POINTS} usable rows; too few "
            "measurements to correct a map"
        )
    cal = calibrated_maps(rm, corr.fits)
    reached = rm.rss_dbm > RSS_FLOOR_DBM + 1.0
    std = np.full(cal.shape, corr.other_local_db)
    sample = np.full(cal.shape, corr.other_sample_db)
    h = np.full(scn.area.shape, rm.altitude_m)
    gx, gy = np.meshgrid(rm.x_m, rm.y_m)
    gz = flight_heights(scn)
    if corr.receive is not None:
        gzb = np.broadcast_to(gz, gx.shape)
        for c in range(len(cal)):
            g = corr.receive.at(elevation_deg(scn, c, gx.ravel(), gy.ravel(), gzb.ravel()))
            cal[c] = np.where(reached[c], cal[c] + g.reshape(gx.shape), cal[c])
    for c, f in corr.fields.items():
        mean, std[c] = f.on_grid(rm.x_m, rm.y_m, h)
        sample[c] = f.sample_db
        cal[c] = np.where(reached[c], cal[c] + mean, cal[c])
    for fc in corr.fits:  # the fitted offsets' own uncertainty, independent of the residual's
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
        "calibration": [f.to_dict() for f in corr.fits],
        "residual": [_field_dict(c, f) for c, f in corr.fields.items()],
        "unmeasured_cells_std_db": corr.other_local_db,
        "unmeasured_cells_sample_std_db": corr.other_sample_db,
        "receive_pattern": {"choice": receive_pattern}
        | ({} if corr.receive is None else {"elevation_gain": corr.receive.to_dict()}),
    }
    if cross_validate:
        fit["cross_validation"] = cross_validate_log(
            rm,
            log,
            prior,
            params=params,
            level_step_m=level_step_m,
            seed=seed,
            whole=corr,
            receive=receive,
        )
    return dataclasses.replace(
        rm, rss_dbm=cal, serving_cell=serving, sir_db=sir, sinr_db=sinr,
        prior_rss_dbm=np.asarray(rm.rss_dbm, dtype=float), rss_std_db=std,
        rss_sample_std_db=sample, fit=fit, build_seconds=0.0, timings={},
    )  # fmt: skip


def _field_dict(c: int, f: ResidualField) -> dict[str, Any]:
    return {
        "cell": c, "amplitude_db": f.amplitude_db, "noise_db": f.noise_db,
        "sample_db": f.sample_db, "length_m": f.length_m,
        "height_length_m": f.length_m / f.height_ratio if f.height_ratio else None,
        "bins": f.bins, "bin_m": f.bin_m,
    }  # fmt: skip


def designs(rm: RadioMap, log: MeasurementLog, step: float) -> dict[str, np.ndarray]:
    """The held-out designs of the log (module docstring, step 5): each design's name and
    every row's fold, (N,)."""
    out = {}
    if len(np.unique(log.flight)) >= 2:
        out["flight"] = log.flight
    else:
        hb = np.round(_heights(rm, log) / step).astype(np.int64)
        if len(np.unique(hb)) >= 2:
            out["height"] = hb
    stretch = np.zeros(len(log), dtype=np.int64)
    for f in np.unique(log.flight):
        idx = np.flatnonzero(log.flight == f)
        if log.time_s is not None:
            idx = idx[np.argsort(log.time_s[idx], kind="stable")]
        stretch[idx] = (np.arange(len(idx)) * STRETCHES) // max(len(idx), 1)
    out["stretch"] = stretch
    return out


def _knn(tr: MeasurementLog, te: MeasurementLog, heights: tuple[np.ndarray, np.ndarray],
         sample_db: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """The nearest-neighbour baseline: per cell, the mean of the ``KNN`` nearest training rows
    in 3-D (metres), with the neighbours' spread as one sample's and that less the sample
    spread (and the mean's standard error) as the local mean's."""
    from scipy.spatial import cKDTree

    mean = np.full(len(te), np.nan)
    local = np.full(len(te), np.nan)
    for c in np.unique(te.cell):
        mt, me = tr.cell == c, te.cell == c
        if mt.sum() < 2:
            continue
        k = min(KNN, int(mt.sum()))
        tree = cKDTree(np.column_stack([tr.x_m[mt], tr.y_m[mt], heights[0][mt]]))
        _, j = tree.query(np.column_stack([te.x_m[me], te.y_m[me], heights[1][me]]), k=k)
        v = tr.rss_dbm[mt][j]
        mean[me] = v.mean(axis=1)
        var = v.var(axis=1, ddof=1)
        local[me] = np.sqrt(np.maximum(var - sample_db**2, 0.0) + var / k)
    return mean, local, np.full(len(te), sample_db)


def _kriging(
    rm: RadioMap, tr: MeasurementLog, te: MeasurementLog, step: float, seed: int,
    like: dict[int, ResidualField] | None,
) -> tuple[Any, dict[int, ResidualField]]:  # fmt: skip
    """Ordinary kriging on the measurements alone: per cell the residual's Gaussian process on
    the measured powers about their mean (no physics)."""
    offset = np.zeros(len(tr))
    means = {}
    for c in np.unique(tr.cell):
        m = tr.cell == c
        means[int(c)] = float(tr.rss_dbm[m].mean())
        offset[m] = means[int(c)]
    fields = _fields(rm, tr, tr.rss_dbm - offset, step, seed, like,
                     None if like is None else CV_MAX_POINTS)  # fmt: skip
    pts = np.column_stack([te.x_m, te.y_m, _heights(rm, te)])
    mean = np.full(len(te), np.nan)
    local = np.full(len(te), np.nan)
    sample = np.full(len(te), np.nan)
    for c, f in fields.items():
        m = te.cell == c
        if m.any():
            mean[m] = means[c] + f.mean(pts[m])
            local[m], sample[m] = f.std(pts[m]), f.sample_db
    return (mean, local, sample), fields


def cross_validate_log(
    rm: RadioMap, log: MeasurementLog, prior: np.ndarray, *,
    params: Sequence[str] = tuple(BOUNDS), level_step_m: float = 10.0, seed: int = 0,
    whole: Correction | None = None, baselines: bool = True, receive: bool = False,
) -> dict[str, Any]:  # fmt: skip
    """Every held-out design of the log (module docstring, step 5), scored: per design, its
    folds and, per method, the scores of single samples and of local means
    ([`score()`][rainuav.radio.measured.scores.score]). ``whole``: the correction of the
    whole log (its hyperparameters are reused; fitted here if None); ``receive``: the corrected
    and calibrated maps fit the UAV's receive gain by elevation in every fold."""
    scn = rm.scenario
    step = level_step_m
    if whole is None:
        whole = fit_correction(rm, log, prior, params=params, level_step_m=step, seed=seed,
                               receive=receive)  # fmt: skip
    heights = _heights(rm, log)
    pts = np.column_stack([log.x_m, log.y_m, heights])
    z = log.z_m
    excess = np.full(len(log), np.nan)
    for c in np.unique(log.cell):
        m = log.cell == c
        excess[m] = excess_at(scn, c, log.x_m[m], log.y_m[m], z[m], prior[m])
    prior_local, prior_sample = spreads_of(excess)
    kriged: dict[int, ResidualField] | None = None
    out: dict[str, Any] = {}
    for name, group in designs(rm, log, step).items():
        methods = ["prior", "power", "calibrated", "corrected"]
        if baselines:
            methods += ["knn", "kriging"]
        pred = {k: [np.full(len(log), np.nan) for _ in range(3)] for k in methods}
        for g in np.unique(group):
            test, train = group == g, group != g
            tr, te = _take(log, train), _take(log, test)
            idx = np.flatnonzero(test)
            got: dict[str, Any] = {"prior": (prior[test], prior_local[test], prior_sample[test])}
            pw = calibrate(scn, tr, prior[train], ("power_db",))
            r = tr.rss_dbm - calibrated_at(scn, tr, prior[train], pw)
            tot = float(np.sqrt(np.mean(r**2)))
            smp = min(whole.other_sample_db, tot)
            loc = float(np.sqrt(max(tot**2 - smp**2, 0.0)))
            got["power"] = (calibrated_at(scn, te, prior[test], pw), np.full(len(te), loc),
                            np.full(len(te), smp))  # fmt: skip
            fc = fit_correction(rm, tr, prior[train], params=params, level_step_m=step,
                                seed=seed, like=whole, max_points=CV_MAX_POINTS,
                                receive=receive)  # fmt: skip
            got["corrected"] = fc.predict(te, prior[test])
            got["calibrated"] = fc.predict(te, prior[test], fields=False, far=whole.fields)
            if baselines:
                got["knn"] = _knn(tr, te, (heights[train], heights[test]), whole.other_sample_db)
                got["kriging"], kf = _kriging(rm, tr, te, step, seed, kriged)
                if kriged is None:  # the first fold's hyperparameters, reused by the others
                    kriged = kf
            for k in methods:
                for a, v in zip(pred[k], got[k], strict=True):
                    a[idx] = v

        def scores(m: np.ndarray, methods: list[str] = methods, pred: Any = pred) -> dict[str, Any]:
            got = {}
            for k in methods:
                mean, local, sample = (a[m] for a in pred[k])
                got[k] = {
                    "samples": score(log.rss_dbm[m] - mean, np.hypot(local, sample)),
                    "local_means": score(*local_means(pts[m], log.rss_dbm[m], mean, local,
                                                      sample, scn.area.resolution_m, step,
                                                      log.cell[m])),
                }  # fmt: skip
            return got

        res: dict[str, Any] = {"folds": len(np.unique(group)), "rows": len(log)}
        res |= scores(np.ones(len(log), bool))
        res["per_fold"] = {str(g): scores(group == g) for g in np.unique(group)}
        out[name] = res
    first = next(iter(out))
    out["left_out"] = first
    return out


def held_out_line(cv: dict[str, Any]) -> str:
    """One line of the held-out scores (``fit.json``'s ``cross_validation``): per design, the
    rows scored, the single samples' RMSE of the prior, the calibrated and the corrected map and
    the nearest samples, and the corrected map's coverage at one and two sigma."""

    def f(v: Any, form: str) -> str:
        return "n/a" if v is None else format(v, form)

    parts = []
    for name in (k for k in cv if k != "left_out"):
        d = cv[name]
        c = d["corrected"]["samples"]
        rm = [f(d[k]["samples"]["rmse_db"], ".1f") for k in ("prior", "calibrated", "corrected")]
        knn = d.get("knn", {}).get("samples", {}).get("rmse_db")
        one, two = c["within_one_sigma"], c["within_two_sigma"]
        parts.append(
            f"one {name} of {d['folds']} left out ({c['points']} of {d['rows']} rows scored): "
            f"RMSE {rm[0]} (prior) / {rm[1]} (calibrated) / {rm[2]} (corrected) / "
            f"{f(knn, '.1f')} (nearest {KNN}) dB, "
            f"{f(None if one is None else 100 * one, '.0f')}% within one sigma, "
            f"{f(None if two is None else 100 * two, '.0f')}% within two"
        )
    return "measurements, held out: " + "; ".join(parts)
