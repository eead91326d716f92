"""A physics map corrected by what was measured:
[`correct_map()`][rainuav.radio.measured.correct.correct_map].

1. The prior at the log's points
   ([`prior_at()`][rainuav.radio.measured.levels.prior_at]).
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
   ([`rainuav.radio.measured.heldout`][rainuav.radio.measured.heldout], scored by
   [`rainuav.radio.measured.scores`][rainuav.radio.measured.scores]), in two designs: one
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
import sys
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from rainuav.errors import InvalidInputError
from rainuav.radio.measured.calibrate import (
    BOUNDS,
    calibrated_maps,
    calibration_std_db,
)
from rainuav.radio.measured.choice import KERNEL_CHOICES
from rainuav.radio.measured.fitting import MIN_FIELD_POINTS, Correction, fit_correction
from rainuav.radio.measured.heldout import cross_validate_log
from rainuav.radio.measured.levels import prior_at
from rainuav.radio.measured.log import MeasurementLog
from rainuav.radio.measured.pattern import elevation_deg
from rainuav.radio.measured.prior import engine_spread
from rainuav.radio.measured.residual import ResidualField
from rainuav.radio.outputs.mapdata import RadioMap
from rainuav.radio.outputs.sinr import RSS_FLOOR_DBM, sir_from_power
from rainuav.radio.scene.terrain import flight_heights

if TYPE_CHECKING:
    from rainuav.radio.scene.scenario import Scenario

__all__ = ["MIN_FIELD_POINTS", "RECEIVE_PATTERNS", "Correction", "correct_map", "fit_correction"]

RECEIVE_PATTERNS = ("off", "elevation", "heading", "both")
"""What ``correct_map``'s ``receive_pattern`` may be."""


# Long: the correction's steps in their order (the log's cells, the calibration, the receive
# pattern, the residual field, the held-out scores, the map's arrays); each reads the one before.
def correct_map(
    rm: RadioMap,
    log: MeasurementLog,
    *,
    params: Sequence[str] = tuple(BOUNDS),
    level_step_m: float = 10.0,
    seed: int = 0,
    cross_validate: bool = True,
    build: Callable[[Scenario], RadioMap] | None = None,
    receive_pattern: str = "off",
    kernel: str = "one-scale",
    progress: bool = False,
) -> RadioMap:
    """Corrects a physics map by a log of measurements, with a spread at every pixel.

    The module docstring gives the method: the sites' parameters calibrated, then a residual
    field per cell, each fitted on the log and scored on blocks of it left out.

    Args:
        rm: The prior, a physics map (not one corrected already).
        log: The measurements ([`read_log()`][rainuav.radio.measured.log.read_log] reads a CSV
            into the map's frame).
        params: The site parameters calibrated, names of
            [`BOUNDS`][rainuav.radio.measured.calibrate.BOUNDS]; empty: none.
        level_step_m: The height bins, m (1-500).
        seed: The draw of the hyperparameters' fitting subset.
        cross_validate: Score the correction on held-out blocks of the log (``fit`` then holds
            the held-out scores beside the baselines: nearest samples, kriging, the prior with
            its power fitted).
        build: How maps at the log's heights are built (default the cached
            [`build_radio_map`][rainuav.radio.outputs.maps.build_radio_map]).
        receive_pattern: ``"off"``, ``"elevation"`` (the UAV's receive gain by elevation fitted
            before the fields, [`rainuav.radio.measured.pattern`][rainuav.radio.measured.pattern];
            the held-out scores fit it in every fold, so ``fit.json`` says whether it helped),
            ``"heading"`` (its gain against the heading, for a log with ``heading_deg``: on the
            map, a spread added to one sample's) or ``"both"``.
        kernel: The residual fields' kernel: ``"one-scale"``, ``"two-scale"``
            ([`rainuav.radio.measured.residual`][rainuav.radio.measured.residual], "Two
            scales"), or ``"auto"``: each cell's kernel chosen by its held-out density over
            blocks of the log (both recorded;
            [`rainuav.radio.measured.choice`][rainuav.radio.measured.choice]).
        progress: A line on standard error per map built at the log's heights, per stage and
            per held-out fold.

    Returns:
        The corrected map: ``rss_dbm``, the serving cell, SIR and SINR corrected;
        ``prior_rss_dbm`` the map given; ``rss_std_db`` each pixel's local-mean deviation and
        ``rss_sample_std_db`` one sample's around it (the page "How far to trust a map");
        ``fit`` the fitted parameters, fields and held-out scores.

    Raises:
        InvalidInputError: An argument out of its range, a map corrected already, or a log
            with too few usable rows for any cell.

    Examples:
        A map in clear air corrected by 2% of its pixels measured in rain:

        ```python
        import numpy as np
        from rainuav.radio import build_radio_map, presets
        from rainuav.radio.measured import correct_map
        from rainuav.radio.measured.synthetic import sample_log

        prior = build_radio_map(presets.uma(freq_hz=28e9, engine="ray"))  # clear air
        truth = build_radio_map(presets.uma(freq_hz=28e9, rain_rate_mm_h=25.0, engine="ray"))
        log = sample_log(truth, share=0.02, seed=0)  # 2% of the pixels, 2 dB of noise
        fixed = correct_map(prior, log, params=("power_db",), cross_validate=False)
        err = lambda m: np.median(np.abs(m.rss_dbm - truth.rss_dbm))
        print(f"median error {err(prior):.2f} -> {err(fixed):.2f} dB")
        ```
    """
    if receive_pattern not in RECEIVE_PATTERNS:
        raise InvalidInputError(
            f"receive_pattern must be one of {', '.join(RECEIVE_PATTERNS)} "
            f"(got {receive_pattern!r})"
        )
    if kernel not in KERNEL_CHOICES:
        raise InvalidInputError(
            f"kernel must be one of {', '.join(KERNEL_CHOICES)} (got {kernel!r})"
        )
    if rm.prior_rss_dbm is not None:
        raise InvalidInputError("the map is already corrected by measurements: correct its prior")
    if not 1.0 <= level_step_m <= 500.0:
        raise InvalidInputError(f"level_step_m must lie within 1..500 m (got {level_step_m:g})")
    scn = rm.scenario
    prior = prior_at(rm, log, level_step_m, build, progress=progress)
    receive = receive_pattern in ("elevation", "both")
    heading = receive_pattern in ("heading", "both")
    if progress:
        print(f"fitting {len(log)} rows: calibration and residual fields", file=sys.stderr,
              flush=True)  # fmt: skip
    corr = fit_correction(rm, log, prior, params=params, level_step_m=level_step_m, seed=seed,
                          receive=receive, heading=heading, kernel=kernel)  # fmt: skip
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
    scale = None  # a scaled field's scale: the engine's own spread, as at the log's rows
    if any(f.scaled for f in corr.fields.values()):
        scale = engine_spread(rm)
    for c, f in corr.fields.items():
        mean, std[c] = f.on_grid(rm.x_m, rm.y_m, h, None if scale is None else scale[c])
        sample[c] = f.sample_db
        cal[c] = np.where(reached[c], cal[c] + mean, cal[c])
    for fc in corr.fits:  # the fitted offsets' own uncertainty, independent of the residual's
        if fc.offsets:
            std[fc.cell] = np.hypot(std[fc.cell], calibration_std_db(scn, fc, gx, gy, gz))
    if corr.heading is not None:  # the heading a pixel is flown at is not known: a spread
        sample = np.hypot(sample, corr.heading.spread_db)
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
        "residual_kernel": kernel,
        "receive_pattern": {"choice": receive_pattern}
        | ({} if corr.receive is None else {"elevation_gain": corr.receive.to_dict()})
        | ({} if corr.heading is None else {"heading_gain": corr.heading.to_dict()}),
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
            heading=heading,
            progress=progress,
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
        "height_length_m": (f.length_m / f.height_ratio
                            if f.height_ratio and not f.components else None),
        "bins": f.bins, "bin_m": f.bin_m, "scaled": f.scaled, "kernel": f.kernel,
        "kernel_scores": None if f.kernel_scores is None else {
            k: v if np.isfinite(v) else None for k, v in f.kernel_scores.items()},
        "components": [
            {"amplitude_db": a, "east_m": e, "north_m": n,
             "height_m": h if np.isfinite(h) else None}
            for a, e, n, h in f.components
        ],
    }  # fmt: skip
