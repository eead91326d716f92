"""The site parameters a log says are wrong, fitted per cell (the prior at the log's points
comes from [`prior_at()`][rainuav.radio.measured.levels.prior_at]).

**Calibration.** A site database gets some things wrong: the transmit power, the tilt, the
azimuth, the antenna height. [`calibrate()`][rainuav.radio.measured.calibrate.calibrate] fits,
per cell, an offset to each (within [`BOUNDS`][rainuav.radio.measured.calibrate.BOUNDS]) by robust
least squares (SciPy's ``least_squares``, soft-L1 loss with a 4 dB scale, so a few deep fades or
bad rows do not pull the fit). The model keeps the propagation the engine computed and changes
what the parameters change: the antenna's gain toward the point (the pattern turned by the
azimuth offset, tipped by the tilt offset, seen from the moved height) and the free-space
spreading from the moved antenna:

    P(theta) = P_map + dP + G(az - daz, el' - dtilt) - G(az, el) + 20 log10(d / d')

with ``el'`` and ``d'`` the elevation and distance from the antenna ``dh`` higher. Each value's
uncertainty is the square root of the diagonal of ``s^2 (J^T J)^-1`` at the solution, ``s`` the
residuals' robust spread (1.4826 times their median absolute deviation) and ``J`` the
Gauss-Newton Jacobian of the soft-L1 cost (each row weighted by ``(1 + (r / 4 dB)^2)^-3/4``, as
SciPy reports it). The search runs on the pattern tabulated every ``TABLE_STEP_DEG`` (each
parameter's finite difference in one batched evaluation); the residuals and ``J`` at its
solution are taken on the exact pattern. A cell with fewer than
``MIN_POINTS_PER_PARAMETER`` points per parameter fits its power offset alone, and none with fewer
than that for one."""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy.optimize import least_squares

from rainuav.errors import InvalidInputError
from rainuav.radio.measured._view import (
    _cells,
    _View,
)
from rainuav.radio.measured.log import MeasurementLog
from rainuav.radio.outputs.mapdata import RadioMap
from rainuav.radio.scene.cell import Cell
from rainuav.radio.scene.scenario import Scenario, Site

__all__ = [
    "BOUNDS",
    "CellFit",
    "calibrate",
    "calibrated_at",
    "calibrated_maps",
    "calibration_std_db",
    "gain_change_db",
]

BOUNDS: dict[str, tuple[float, float]] = {
    "power_db": (-15.0, 15.0),
    "tilt_deg": (-15.0, 15.0),
    "azimuth_deg": (-45.0, 45.0),
    "height_m": (-30.0, 30.0),
}
"""Each fitted offset's name and bounds (dB, degrees, degrees, metres)."""
SCALES = {"power_db": 1.0, "tilt_deg": 1.0, "azimuth_deg": 5.0, "height_m": 5.0}
MIN_POINTS_PER_PARAMETER = 15
MAX_EVALUATIONS = 200
START_GRID = {"tilt_deg": tuple(np.arange(-8.0, 8.5, 1.0)),
              "azimuth_deg": tuple(np.arange(-30.0, 31.0, 5.0))}  # fmt: skip
STARTS = 2
SCAN_POINTS = 100
SCAN_EVALUATIONS = 60
SOFT_L1_SCALE_DB = 4.0


def gain_change_db(
    scn: Scenario,
    site: Site,
    cell: Cell,
    x: npt.ArrayLike,
    y: npt.ArrayLike,
    z: npt.ArrayLike,
    offsets: dict[str, float],
) -> np.ndarray:
    """The change of a cell's power at points when its parameters move.

    Args:
        scn: The scenario.
        site: The cell's site.
        cell: The cell.
        x: East, m.
        y: North, m.
        z: Height above sea level, m.
        offsets: The parameters' moves, by the names of
            [`BOUNDS`][rainuav.radio.measured.calibrate.BOUNDS] (missing ones 0).

    Returns:
        The change, dB, at each point.
    """
    return _View(scn, site, cell, x, y, z).change(offsets)


@dataclass
class CellFit:
    """One cell's calibration."""

    cell: int
    """The map's cell index."""
    points: int
    """Logged rows of the cell."""
    offsets: dict[str, float]
    """The fitted offset of each parameter (names of ``BOUNDS``)."""
    std: dict[str, float]
    """Each offset's one-sigma uncertainty."""
    cov: list[list[float]]
    """The offsets' covariance (in the order of ``offsets``)."""
    at_bound: list[str]
    """Parameters whose fit stopped at a bound (their uncertainty understates it)."""
    rmse_before_db: float
    """RMS of measured minus prior."""
    rmse_after_db: float
    """RMS of measured minus calibrated prior."""

    def to_dict(self) -> dict[str, Any]:
        """The fit as plain data, for `fit.json`.

        Returns:
            The cell, the rows used, the fitted offsets, their standard deviations and covariance,
            the parameters at a bound, and the RMSE before and after.
        """
        return dataclasses.asdict(self)


def _starts(names: list[str], resid: Any) -> list[np.ndarray]:
    """Where the fit starts: the database's values (no offset), and the ``STARTS`` best beam
    directions on a grid (tilt every degree, azimuth every 5), each with the power offset that
    centres its residuals. A pattern's nulls and lobes make the cost ripple: a single start
    falls into the nearest ripple. Each start runs ``SCAN_EVALUATIONS`` steps on
    ``SCAN_POINTS`` of the rows (the pattern tabulated); the best goes on, on every row."""
    x0 = np.zeros(len(names))
    pw = names.index("power_db") if "power_db" in names else None

    def centred(x: np.ndarray) -> np.ndarray:
        if pw is not None:
            x[pw] = np.clip(x[pw] - np.median(resid(x)), *BOUNDS["power_db"])
        return x

    axes = [(names.index(p), grid) for p, grid in START_GRID.items() if p in names]
    if not axes:
        return [centred(x0)]
    grid = np.array(list(itertools.product(*(g for _, g in axes))), dtype=float)
    xs = np.zeros((len(grid), len(names)))
    for k, (i, _) in enumerate(axes):
        xs[:, i] = grid[:, k]
    r = resid.many(xs)  # every grid point at once (the power offset is additive: centred after)
    if pw is not None:
        new = np.clip(xs[:, pw] - np.median(r, axis=1), *BOUNDS["power_db"])
        r = r + (new - xs[:, pw])[:, None]
        xs[:, pw] = new
    z = (r / SOFT_L1_SCALE_DB) ** 2
    cost = np.sum(2 * (np.sqrt(1 + z) - 1), axis=1)
    best = np.argsort(cost, kind="stable")[:STARTS]
    return [x0] + [xs[i].copy() for i in best]


class _Fit:
    """The residuals (model minus measured, dB) of one cell's offsets ``names`` at a view's
    points, and their robust least-squares fit from a start."""

    def __init__(self, view: _View, prior: np.ndarray, meas: np.ndarray, names: list[str]):
        self.view, self.prior, self.meas, self.names = view, prior, meas, names

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        off = dict(zip(self.names, theta.tolist(), strict=True))
        return self.prior + self.view.change(off) - self.meas

    def many(self, thetas: np.ndarray) -> np.ndarray:
        """The residuals of S offset vectors (S, k) at once, (S, N) (a tabulated view)."""
        off = {p: thetas[:, i] for i, p in enumerate(self.names)}
        return self.prior + self.view.change_many(off) - self.meas

    def jac(self, theta: np.ndarray, r0: np.ndarray | None = None) -> np.ndarray:
        """Forward differences of the residuals at ``theta`` (whose residuals ``r0`` are, where
        known), steps toward the inside of the bounds, (N, k): a tabulated view's every
        parameter in one batched evaluation, the exact pattern's one by one."""
        hi = np.array([BOUNDS[p][1] for p in self.names])
        h = 1e-4 * np.array([SCALES[p] for p in self.names]) * np.maximum(1.0, np.abs(theta))
        h = np.where(theta + h > hi, -h, h)
        steps = theta + np.diag(h)
        if self.view.table:
            r = self.many(np.vstack([theta, steps]))
            return ((r[1:] - r[0]) / h[:, None]).T
        r0 = self(theta) if r0 is None else r0
        cols = [(self(s) - r0) / d for s, d in zip(steps, h, strict=True)]
        return np.column_stack(cols) if cols else np.zeros((len(r0), 0))

    def solve(self, x0: np.ndarray, evaluations: int = MAX_EVALUATIONS) -> Any:
        lo = [BOUNDS[p][0] for p in self.names]
        hi = [BOUNDS[p][1] for p in self.names]
        return least_squares(
            self, x0, jac=self.jac if self.view.table else "2-point", bounds=(lo, hi),
            loss="soft_l1", f_scale=SOFT_L1_SCALE_DB,
            x_scale=np.array([SCALES[p] for p in self.names]), max_nfev=evaluations,
        )  # fmt: skip


def _near(names: list[str], c: int, near: list[CellFit] | None) -> np.ndarray | None:
    for f in near or []:
        if f.cell == c and list(f.offsets) == names:
            return np.array([f.offsets[p] for p in names])
    return None


def calibrate(
    scn: Scenario,
    log: MeasurementLog,
    prior: np.ndarray,
    params: Sequence[str] = tuple(BOUNDS),
    near: list[CellFit] | None = None,
) -> list[CellFit]:
    """Fits each measured cell's site parameters to the log (the module's docstring).

    Args:
        scn: The scenario.
        log: The log.
        prior: Each row's power in the prior map, dBm
            ([`prior_at()`][rainuav.radio.measured.levels.prior_at]).
        params: The parameters fitted, names of [`BOUNDS`][rainuav.radio.measured.calibrate.BOUNDS].
        near: An earlier fit of the same cells (on more of the log) to start from alone, where it
            fitted the same parameters (a cross-validation fold).

    Returns:
        One [`CellFit`][rainuav.radio.measured.calibrate.CellFit] a measured cell.

    Raises:
        InvalidInputError: A parameter that is not one of `BOUNDS`.
    """
    bad = [p for p in params if p not in BOUNDS]
    if bad:
        raise InvalidInputError(
            f"calibration parameter {bad[0]!r} is not one of {', '.join(BOUNDS)}"
        )
    cells = _cells(scn)
    fits = []
    for c in np.unique(log.cell):
        m = log.cell == c
        n = int(m.sum())
        names = list(params) if n >= MIN_POINTS_PER_PARAMETER * len(params) else ["power_db"]
        if n < MIN_POINTS_PER_PARAMETER:
            names = []
        site, cell = cells[c]
        x, y, z, meas, pri = log.x_m[m], log.y_m[m], log.z_m[m], log.rss_dbm[m], prior[m]
        before = float(np.sqrt(np.mean((meas - pri) ** 2)))
        if not names:
            fits.append(CellFit(int(c), n, {}, {}, [], [], before, before))
            continue

        view = _Fit(_View(scn, site, cell, x, y, z), pri, meas, names)
        x0 = _near(names, c, near)
        if x0 is None:  # each start on a sample of the points, the best then on all
            pick = np.random.default_rng(0).permutation(n)[:SCAN_POINTS]
            sub = _View(scn, site, cell, x[pick], y[pick], z[pick], table=True)
            scan = _Fit(sub, pri[pick], meas[pick], names)
            x0 = min((scan.solve(s, SCAN_EVALUATIONS) for s in _starts(names, scan)),
                     key=lambda r: r.cost).x  # fmt: skip
        # the search on the table, the solution's residuals and Jacobian exact (docstring)
        tab = _Fit(_View(scn, site, cell, x, y, z, table=True), pri, meas, names)
        res = tab.solve(x0)
        r = view(res.x)
        # each row weighted by sqrt(rho'(z) + 2 z rho''(z)) = (1 + z)^-3/4, as SciPy does
        z = (r / SOFT_L1_SCALE_DB) ** 2
        jac = view.jac(res.x, r) * ((1 + z) ** -0.75)[:, None]
        s = 1.4826 * float(np.median(np.abs(r - np.median(r))))
        cov = s**2 * np.linalg.pinv(jac.T @ jac)
        std = np.sqrt(np.maximum(np.diag(cov), 0.0))
        stuck = [p for p, v in zip(names, res.x, strict=True)
                 if min(v - BOUNDS[p][0], BOUNDS[p][1] - v) < 1e-3 * np.ptp(BOUNDS[p])]  # fmt: skip
        fits.append(
            CellFit(
                cell=int(c),
                points=n,
                offsets={p: float(v) for p, v in zip(names, res.x, strict=True)},
                std={p: float(v) for p, v in zip(names, std, strict=True)},
                cov=cov.tolist(),
                at_bound=stuck,
                rmse_before_db=before,
                rmse_after_db=float(np.sqrt(np.mean(r**2))),
            )
        )
    return fits


def calibrated_maps(rm: RadioMap, fits: list[CellFit]) -> np.ndarray:
    """A map's powers with each fitted cell's parameters moved.

    Pixels a cell does not reach stay unreached.

    Args:
        rm: The map.
        fits: The cells' fits.

    Returns:
        `rss_dbm` (M, H, W), dBm.
    """
    scn = rm.scenario
    cells = _cells(scn)
    out = np.array(rm.rss_dbm, dtype=float, copy=True)
    gx, gy = np.meshgrid(rm.x_m, rm.y_m)
    from rainuav.radio.scene.terrain import flight_heights

    gz = flight_heights(scn)
    for f in fits:
        if not f.offsets:
            continue
        site, cell = cells[f.cell]
        d = gain_change_db(scn, site, cell, gx, gy, gz, f.offsets)
        reached = out[f.cell] > -249.0
        out[f.cell] = np.where(reached, out[f.cell] + d, out[f.cell])
    return out


def calibration_std_db(
    scn: Scenario, fit: CellFit, x: npt.ArrayLike, y: npt.ArrayLike, z: npt.ArrayLike
) -> np.ndarray:
    """How far the fitted offsets' uncertainty moves a cell's power at points, dB.

    Half the change between the offsets one standard deviation either way along each principal axis
    of their covariance, added in quadrature (sigma points, on the tabulated pattern, the offsets
    kept within their bounds): where the power is linear in the offsets this is `sqrt(J C J^T)`, and
    it stays finite beside a pattern's nulls, whose place a small tilt moves, and for an offset the
    log hardly constrains.

    Args:
        scn: The scenario.
        fit: The cell's fit.
        x: East, m.
        y: North, m.
        z: Height above sea level, m.

    Returns:
        The deviation, dB, at each point.
    """
    x = np.asarray(x, dtype=float)
    if not fit.offsets:
        return np.zeros(x.shape)
    site, cell = _cells(scn)[fit.cell]
    view = _View(scn, site, cell, x, y, z, table=True)
    names = list(fit.offsets)
    theta = np.array([fit.offsets[p] for p in names])
    lam, vec = np.linalg.eigh(np.asarray(fit.cov))
    lo = np.array([BOUNDS[p][0] for p in names])
    hi = np.array([BOUNDS[p][1] for p in names])
    var = np.zeros(x.shape)
    for k in range(len(names)):
        d = np.sqrt(max(float(lam[k]), 0.0)) * vec[:, k]
        up, dn = (
            view.change(dict(zip(names, np.clip(t, lo, hi).tolist(), strict=True)))
            for t in (theta + d, theta - d)
        )
        var += ((up - dn) / 2) ** 2
    return np.sqrt(var)


def calibrated_at(
    scn: Scenario, log: MeasurementLog, prior: np.ndarray, fits: list[CellFit]
) -> np.ndarray:
    """Each row's power in the calibrated prior, dBm.

    Args:
        scn: The scenario.
        log: The log.
        prior: Each row's power in the prior map, dBm.
        fits: The cells' fits.

    Returns:
        (N,) powers, dBm.
    """
    cells = _cells(scn)
    out = np.array(prior, dtype=float, copy=True)
    for f in fits:
        if not f.offsets:
            continue
        m = log.cell == f.cell
        site, cell = cells[f.cell]
        out[m] += gain_change_db(scn, site, cell, log.x_m[m], log.y_m[m], log.z_m[m], f.offsets)
    return out
