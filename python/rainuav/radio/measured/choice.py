"""Which residual kernel a log supports, chosen by the log itself: each candidate field scored by
its held-out log predictive density over blocks of the log's own bins
([`kernel_scores()`][rainuav.radio.measured.choice.kernel_scores]; ``kernel="auto"`` in
[`fit_correction()`][rainuav.radio.measured.fitting.fit_correction] and
[`correct_map()`][rainuav.radio.measured.correct.correct_map]).

A kernel's marginal likelihood says how well it explains the bins it was fitted on; it does not
say how well it predicts where the log has not been, which is what a map is for. Both kernels of
[`KERNELS`][rainuav.radio.measured.residual.KERNELS] are fitted (each its own hyperparameters),
then each is conditioned, its hyperparameters fixed, on all the bins but one block and scored
on that block, block by block:

- **heights**: where the log spans two height bins or more, its heights in at most ``BLOCKS``
  groups of neighbouring heights, each left out in turn (a flight at a height not flown);
- **places**: the bins' positions across the ground in ``BLOCKS`` clusters (k-means, seeded),
  each left out at every height at once (a stretch of the path not flown at all).

The score is the mean over the held-out bins of ``log N(y; mu, sigma^2 + a)``: ``mu`` and
``sigma`` the field's prediction of the bin's local mean, ``a`` the bin mean's own variance
(the sample spread squared over its rows), in dB, with a scaled field's Jacobian (its residual
is ``s(x)`` times its field's). Both candidates are scored on the same bins (the coarser of
their two bin widths), and the higher score is kept; ``fit.json`` records both. The choice is
made again on each cross-validation fold's own rows (the candidates' hyperparameters, the
fold's rows; only the one kept is conditioned on them), so a held-out score never rests on a
choice that saw it."""

from __future__ import annotations

import numpy as np

from rainuav.radio.measured.residual import (
    KERNELS,
    ResidualField,
    _features,
    bin_points,
    bin_scale,
)

__all__ = [
    "AUTO",
    "BLOCKS",
    "KERNEL_CHOICES",
    "block_folds",
    "chosen",
    "held_out_density",
    "kernel_scores",
]

AUTO = "auto"
"""The kernel name that asks the log to choose."""
KERNEL_CHOICES = (*KERNELS, AUTO)
"""What a correction's ``kernel`` may be."""
BLOCKS = 5
"""The blocks of each kind (heights, places) a candidate is scored on."""


def block_folds(bp: np.ndarray, step_m: float, seed: int) -> list[np.ndarray]:
    """The held-out blocks of a log's bins, each a mask (the module's docstring).

    Groups of neighbouring heights where the bins span two or more, then `BLOCKS` places across the
    ground.

    Args:
        bp: The bins' points (B, 3): east, north, height, m.
        step_m: The bins' height, m.
        seed: The places' seed (k-means).

    Returns:
        The blocks, (B,) bool each.
    """
    from sklearn.cluster import KMeans

    folds = []
    hb = np.round(bp[:, 2] / step_m).astype(np.int64)
    values, rank = np.unique(hb, return_inverse=True)
    if len(values) >= 2:
        group = (rank * min(BLOCKS, len(values))) // len(values)
        folds += [group == g for g in np.unique(group)]
    k = min(BLOCKS, len(np.unique(bp[:, :2], axis=0)))
    if k >= 2:
        lab = KMeans(k, n_init=3, random_state=seed).fit_predict(bp[:, :2])
        folds += [lab == g for g in range(k)]
    return folds


def held_out_density(
    field: ResidualField, pts: np.ndarray, resid: np.ndarray, *, bin_m: float, step_m: float,
    seed: int = 0, scale: np.ndarray | None = None, folds: list[np.ndarray] | None = None,
) -> float:  # fmt: skip
    """The mean held-out log predictive density of a field's kernel, its hyperparameters fixed.

    Over the blocks of the rows, binned (the module's docstring).

    Args:
        field: The fitted field.
        pts: The rows' points (N, 3), m.
        resid: Their residuals (N,), dB.
        bin_m: The bins' width, m.
        step_m: Their height, m.
        seed: The blocks' seed, where `folds` is None.
        scale: Each row's scale (N,), for a scaled field.
        folds: The bins' blocks where already drawn; None:
            [`block_folds()`][rainuav.radio.measured.choice.block_folds].

    Returns:
        Nats a bin; NaN where the log has fewer than two blocks.

    Raises:
        ValueError: A scaled field without the scale at its rows.
    """
    from sklearn.gaussian_process import GaussianProcessRegressor

    bp, bv, count = bin_points(pts[:, 0], pts[:, 1], pts[:, 2], resid, bin_m, step_m)
    if field.scaled and scale is None:
        raise ValueError("a scaled field needs the scale at its rows")
    sample = 0.0 if field.nugget_is_sample else field.sample_db
    alpha = np.maximum(sample**2 / count, 1e-6)
    u = bin_scale(pts, scale if field.scaled else None, bin_m, step_m, count)
    y, a = bv / u, alpha / u**2
    x = _features(bp, field.height_ratio)
    total, n = 0.0, 0
    for test in block_folds(bp, step_m, seed) if folds is None else folds:
        train = ~test
        if train.sum() < 2 or not test.any():
            continue
        g = GaussianProcessRegressor(field.gp.kernel_, alpha=a[train], optimizer=None)
        g.fit(x[train], y[train])
        mu, sd = g.predict(x[test], return_std=True)
        var = sd**2 + a[test]  # the field's predictive variance includes its nugget
        lpd = -0.5 * np.log(2 * np.pi * var) - 0.5 * (y[test] - mu) ** 2 / var - np.log(u[test])
        total += float(lpd.sum())
        n += int(test.sum())
    return total / n if n else float("nan")


def kernel_scores(
    fields: dict[str, ResidualField], pts: np.ndarray, resid: np.ndarray, *, step_m: float,
    seed: int = 0, scale: np.ndarray | None = None,
) -> dict[str, float]:  # fmt: skip
    """Each candidate kernel's held-out log predictive density a bin, on the same bins and blocks.

    The bins are the coarsest of the candidates' widths
    ([`held_out_density()`][rainuav.radio.measured.choice.held_out_density]).

    Args:
        fields: The candidates by kernel name.
        pts: The rows' points (N, 3), m.
        resid: Their residuals (N,), dB.
        step_m: The bins' height, m.
        seed: The blocks' seed.
        scale: Each row's scale (N,), for a scaled field.

    Returns:
        Nats a bin, by kernel name.
    """
    bin_m = max(f.bin_m for f in fields.values())
    bp, _, _ = bin_points(pts[:, 0], pts[:, 1], pts[:, 2], resid, bin_m, step_m)
    folds = block_folds(bp, step_m, seed)
    return {
        k: held_out_density(f, pts, resid, bin_m=bin_m, step_m=step_m, scale=scale, folds=folds)
        for k, f in fields.items()
    }


def chosen(scores: dict[str, float]) -> str:
    """The candidate of the highest finite score (the first where none is finite).

    Args:
        scores: Scores by candidate
            ([`kernel_scores()`][rainuav.radio.measured.choice.kernel_scores]).

    Returns:
        The candidate's name.
    """
    finite = {k: v for k, v in scores.items() if np.isfinite(v)}
    return max(finite, key=lambda k: finite[k]) if finite else next(iter(scores))
