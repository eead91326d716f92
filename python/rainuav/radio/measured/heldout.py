"""A corrected map's held-out scores: the designs that leave measurements out, the baselines a
user would otherwise use, and one line of what they say (step 5 of
[`rainuav.radio.measured.correct`][rainuav.radio.measured.correct];
[`cross_validate_log()`][rainuav.radio.measured.heldout.cross_validate_log])."""

from __future__ import annotations

import sys
from collections.abc import Sequence
from typing import Any

import numpy as np

from rainuav.radio.measured.calibrate import BOUNDS, calibrate, calibrated_at
from rainuav.radio.measured.fitting import Correction, _fields, _heights, _take, fit_correction
from rainuav.radio.measured.log import MeasurementLog
from rainuav.radio.measured.prior import SITE_DB, excess_at, site_distance_at, spreads_of
from rainuav.radio.measured.residual import ResidualField
from rainuav.radio.measured.scores import local_means, score
from rainuav.radio.outputs.mapdata import RadioMap

__all__ = [
    "CV_MAX_POINTS",
    "KNN",
    "MAX_FOLDS",
    "STRETCHES",
    "cross_validate_log",
    "designs",
    "held_out_line",
]

STRETCHES = 5
"""The stretches each flight is cut into for the held-out stretches' design."""
KNN = 25
"""The nearest logged samples the nearest-neighbour baseline averages."""
CV_MAX_POINTS = 1000
"""The most bins a cross-validation fold's fields are conditioned on (the map's own: 2 500)."""
MAX_FOLDS = 10
"""The most folds of a design: a log of more flights or heights leaves out neighbouring
flights (by number) or heights together, in at most this many groups."""


def designs(rm: RadioMap, log: MeasurementLog, step: float) -> dict[str, np.ndarray]:
    """The held-out designs of a log (the module's docstring, step 5): each row's fold in each.

    One flight left out at a time (or, in a log of one flight, one height), and one stretch of every
    flight.

    Args:
        rm: The prior map.
        log: The log.
        step: The height of a level, m (the heights of a log of one flight).

    Returns:
        Each design's name (`flight` or `height`, and `stretch`) and every row's fold (N,).
    """
    out = {}
    if len(np.unique(log.flight)) >= 2:
        out["flight"] = _at_most(log.flight, MAX_FOLDS)
    else:
        hb = np.round(_heights(rm, log) / step).astype(np.int64)
        if len(np.unique(hb)) >= 2:
            out["height"] = _at_most(hb, MAX_FOLDS)
    stretch = np.zeros(len(log), dtype=np.int64)
    for f in np.unique(log.flight):
        idx = np.flatnonzero(log.flight == f)
        if log.time_s is not None:
            idx = idx[np.argsort(log.time_s[idx], kind="stable")]
        stretch[idx] = (np.arange(len(idx)) * STRETCHES) // max(len(idx), 1)
    out["stretch"] = stretch
    return out


def _at_most(group: np.ndarray, folds: int) -> np.ndarray:
    """``group`` as it is if it has at most ``folds`` values, else its values in order cut into
    ``folds`` runs of neighbouring values (each row's run, (N,))."""
    values, rank = np.unique(group, return_inverse=True)
    if len(values) <= folds:
        return group
    return (rank * folds) // len(values)


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
    heading: bool = False, progress: bool = False, kernel: str = "one-scale",
) -> dict[str, Any]:  # fmt: skip
    """Every held-out design of a log, scored per method: single samples and local means.

    Args:
        rm: The prior map.
        log: The log.
        prior: Each row's power in the prior map, dBm.
        params: The site parameters calibrated.
        level_step_m: The height between the maps built at the log's heights, m.
        seed: The fits' seed.
        whole: The correction of the whole log (its hyperparameters are reused); None: fitted here.
        baselines: Score the baselines too (the nearest samples, ordinary kriging, the prior with
            its power fitted).
        receive: The corrected and calibrated maps fit the UAV's receive gain by elevation in every
            fold.
        heading: They fit its gain against the heading (each held-out row predicted with its own
            heading).
        progress: One line on standard error per fold.
        kernel: The residual fields' kernel where `whole` is None (else `whole`'s); "auto": each
            fold chooses again on its own rows.

    Returns:
        Per design its folds and, per method, the scores
        ([`score()`][rainuav.radio.measured.scores.score]); `kernels`: what each fold chose.
    """
    scn = rm.scenario
    step = level_step_m
    if whole is None:
        whole = fit_correction(rm, log, prior, params=params, level_step_m=step, seed=seed,
                               receive=receive, heading=heading, kernel=kernel)  # fmt: skip
    heights = _heights(rm, log)
    pts = np.column_stack([log.x_m, log.y_m, heights])
    z = log.z_m
    excess = np.full(len(log), np.nan)
    dist = np.full(len(log), np.nan)
    for c in np.unique(log.cell):
        m = log.cell == c
        excess[m] = excess_at(scn, c, log.x_m[m], log.y_m[m], z[m], prior[m])
        dist[m] = site_distance_at(scn, c, log.x_m[m], log.y_m[m], z[m])
    prior_local, prior_sample = spreads_of(excess, dist, SITE_DB)
    kriged: dict[int, ResidualField] | None = None
    out: dict[str, Any] = {}
    for name, group in designs(rm, log, step).items():
        methods = ["prior", "power", "calibrated", "corrected"]
        if baselines:
            methods += ["knn", "kriging"]
        pred = {k: [np.full(len(log), np.nan) for _ in range(3)] for k in methods}
        kernels: dict[str, dict[str, str]] = {}
        for k, g in enumerate(np.unique(group)):
            if progress:
                print(f"held out: one {name} of {len(np.unique(group))} ({k + 1})",
                      file=sys.stderr, flush=True)  # fmt: skip
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
                                receive=receive, heading=heading)  # fmt: skip
            got["corrected"] = fc.predict(te, prior[test])
            kernels[str(g)] = {str(c): f.kernel for c, f in fc.fields.items()}
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
        res["kernels"] = kernels  # per fold, each cell's residual kernel (chosen there: "auto")
        out[name] = res
    first = next(iter(out))
    out["left_out"] = first
    return out


def held_out_line(cv: dict[str, Any]) -> str:
    """The held-out scores in one line (`fit.json`'s `cross_validation`).

    Args:
        cv: What [`cross_validate_log()`][rainuav.radio.measured.heldout.cross_validate_log] gave.

    Returns:
        Per design: the rows scored, the single samples' RMSE of the prior, the calibrated and the
        corrected map and the nearest samples, and the corrected map's coverage at one and two
        sigma.
    """

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
