"""A predictive distribution scored as forecasts are: against what was measured where the fit
did not look.

A map predicts, at a point, a Gaussian in dB: a mean and a standard deviation. Two questions
are asked of it, each on single samples and on local means:

- **single samples**: each held-out row against the mean with the deviation of one sample
  (the local mean's and the sample spread in quadrature);
- **local means**: the held-out rows averaged over bins of the map's pixel and ``step_m`` of
  height ([`local_means()`][rainuav.radio.measured.scores.local_means]), against the mean
  averaged the same way, with the local mean's deviation and the bin average's own standard
  error (the sample spread over the square root of the bin's rows) in quadrature.

Scores ([`score()`][rainuav.radio.measured.scores.score]): RMSE and bias (measured minus
predicted), the share of errors within one and two standard deviations (a calibrated Gaussian:
68.3% and 95.4%), and the continuous ranked probability score (CRPS, dB; a proper score: lower
is better, and for a point forecast it is the mean absolute error), in its closed form for a
Gaussian (Gneiting and Raftery 2007, eq. 21):

    CRPS(N(mu, s^2), y) = s [z (2 Phi(z) - 1) + 2 phi(z) - 1 / sqrt(pi)],  z = (y - mu) / s

(the tests check it against ``properscoring.crps_gaussian``)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from scipy.special import ndtr

from rainuav.radio.measured.residual import bin_index

__all__ = ["COVERAGE_GAUSSIAN", "crps_gaussian", "local_means", "score"]

COVERAGE_GAUSSIAN = (0.6827, 0.9545)
"""The share of a Gaussian's draws within one and two standard deviations of its mean."""


def crps_gaussian(y: npt.ArrayLike, mu: npt.ArrayLike, sigma: npt.ArrayLike) -> np.ndarray:
    """The CRPS of Gaussian forecasts N(mu, sigma^2) for outcomes, in the outcomes' units.

    The module's docstring has the closed form; `sigma` 0 gives the absolute error.

    Args:
        y: The outcomes.
        mu: The forecasts' means.
        sigma: Their standard deviations.

    Returns:
        The CRPS of each, of the broadcast shape.
    """
    y, mu, sigma = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (y, mu, sigma)))
    out = np.abs(y - mu)
    pos = sigma > 0
    z = (y[pos] - mu[pos]) / sigma[pos]
    pdf = np.exp(-0.5 * z**2) / np.sqrt(2 * np.pi)
    out[pos] = sigma[pos] * (z * (2 * ndtr(z) - 1) + 2 * pdf - 1 / np.sqrt(np.pi))
    return out


def score(err: npt.ArrayLike, sigma: npt.ArrayLike) -> dict[str, float | int | None]:
    """The scores of errors under their deviations: RMSE, bias, coverage and mean CRPS.

    Args:
        err: The errors (measured minus predicted).
        sigma: Their predicted deviations.

    Returns:
        `points` (the finite pairs scored), `rmse_db`, `bias_db`, `within_one_sigma`,
        `within_two_sigma` and `crps_db` (None each where no pair is finite).
    """
    e, s = np.broadcast_arrays(np.asarray(err, dtype=float), np.asarray(sigma, dtype=float))
    ok = np.isfinite(e) & np.isfinite(s)
    if not ok.any():
        keys = ("rmse_db", "bias_db", "within_one_sigma", "within_two_sigma", "crps_db")
        return {"points": 0} | dict.fromkeys(keys)
    e, s = e[ok], s[ok]
    return {
        "points": int(ok.sum()),
        "rmse_db": float(np.sqrt(np.mean(e**2))),
        "bias_db": float(np.mean(e)),
        "within_one_sigma": float(np.mean(np.abs(e) <= s)),
        "within_two_sigma": float(np.mean(np.abs(e) <= 2 * s)),
        "crps_db": float(np.mean(crps_gaussian(e, 0.0, s))),
    }


def local_means(
    pts: np.ndarray, measured: np.ndarray, mean: np.ndarray, local_std: np.ndarray,
    sample_std: np.ndarray, size_m: float, step_m: float, cell: np.ndarray | None = None,
    min_rows: int = 5,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Held-out rows averaged over bins, with their errors and deviations.

    Each bin's error is measured minus predicted, both averaged over its rows; its deviation is the
    rows' mean local deviation and the bin average's standard error (`sample_std / sqrt(n)`) in
    quadrature.

    Args:
        pts: The rows' points (N, 3): east, north, height, m.
        measured: Their measured powers, dBm.
        mean: Their predicted powers, dBm.
        local_std: The local mean's predicted deviation at each, dB.
        sample_std: One sample's deviation at each, dB.
        size_m: The bins' width, m.
        step_m: Their height, m.
        cell: Each row's cell (N,): a cell's bins are not another's; None: one cell.
        min_rows: The fewest rows a bin is kept with.

    Returns:
        `(error, deviation)`, (B,) each.
    """
    inv, count = bin_index(pts[:, 0], pts[:, 1], pts[:, 2], size_m, step_m, cell)

    def avg(a: np.ndarray) -> np.ndarray:
        return np.bincount(inv, weights=a, minlength=len(count)) / count

    keep = count >= min_rows
    err = avg(measured - mean)
    sd = np.hypot(avg(local_std), avg(sample_std) / np.sqrt(count))
    return err[keep], sd[keep]
