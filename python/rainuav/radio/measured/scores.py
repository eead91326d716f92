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

from typing import Any

import numpy as np
from scipy.special import ndtr

from rainuav.radio.measured.residual import bin_index

__all__ = ["COVERAGE_GAUSSIAN", "crps_gaussian", "local_means", "score"]

COVERAGE_GAUSSIAN = (0.6827, 0.9545)
"""The share of a Gaussian's draws within one and two standard deviations of its mean."""


def crps_gaussian(y: Any, mu: Any, sigma: Any) -> np.ndarray:
    """The CRPS of the Gaussian forecasts N(``mu``, ``sigma``^2) for the outcomes ``y``, in the
    units of ``y`` (module docstring); ``sigma`` 0 gives the absolute error."""
    y, mu, sigma = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (y, mu, sigma)))
    out = np.abs(y - mu)
    pos = sigma > 0
    z = (y[pos] - mu[pos]) / sigma[pos]
    pdf = np.exp(-0.5 * z**2) / np.sqrt(2 * np.pi)
    out[pos] = sigma[pos] * (z * (2 * ndtr(z) - 1) + 2 * pdf - 1 / np.sqrt(np.pi))
    return out


def score(err: Any, sigma: Any) -> dict[str, float | int | None]:
    """RMSE, bias, coverage at one and two sigma and mean CRPS of the errors ``err`` (measured
    minus predicted) under the deviations ``sigma``, over the finite pairs (``points``)."""
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
    """The held-out rows at ``pts`` (N, 3) of each ``cell`` (N,) averaged over bins ``size_m``
    wide and ``step_m`` tall, of ``min_rows`` rows or more: each bin's error (measured minus
    predicted, both averaged over its rows) and its deviation (the rows' mean local deviation
    and the bin average's standard error, ``sample_std / sqrt(n)``, in quadrature), (B,)
    each."""
    inv, count = bin_index(pts[:, 0], pts[:, 1], pts[:, 2], size_m, step_m, cell)

    def avg(a: np.ndarray) -> np.ndarray:
        return np.bincount(inv, weights=a, minlength=len(count)) / count

    keep = count >= min_rows
    err = avg(measured - mean)
    sd = np.hypot(avg(local_std), avg(sample_std) / np.sqrt(count))
    return err[keep], sd[keep]
