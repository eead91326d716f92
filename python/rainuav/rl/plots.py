"""Figures of a training run: the returns, with the validation checks
([`plot_returns()`][rainuav.rl.plots.plot_returns]). The flights over the map are the navigation
layer's ([`rainuav.nav.figures`][rainuav.nav.figures])."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from rainuav._io import write_atomic

__all__ = ["plot_returns"]


def plot_returns(
    returns: list[float],
    path: Path,
    validation: Sequence[tuple[int, float, float]] = (),
    window: int = 50,
) -> None:
    """Writes the training returns and their moving average, and the validation checks.

    Args:
        returns: Every episode's return.
        path: The PNG.
        validation: `(episodes, success, mean excess cost)` of each check.
        window: The moving average's episodes.
    """
    from matplotlib.figure import Figure

    r = np.asarray(returns)
    both = len(validation) > 0
    fig = Figure(figsize=(11 if both else 6.4, 4))
    axes = fig.subplots(1, 2 if both else 1, squeeze=False)
    ax = axes[0, 0]
    ax.plot(r, color="0.8", lw=0.5, label="episode return")
    if len(r) >= window:
        ma = np.convolve(r, np.ones(window) / window, mode="valid")
        ax.plot(np.arange(window - 1, len(r)), ma, "b", label=f"moving average ({window})")
    ax.set_xlabel("episode")
    ax.set_ylabel("return")
    ax.legend()
    if both:
        ep, success, gap = (np.array(v) for v in zip(*validation, strict=True))
        ax = axes[0, 1]
        ax.plot(ep, 100 * success, "g.-", label="success, %")
        ax.plot(ep, 100 * np.minimum(gap, 1.0), "r.-", label="mean excess cost, % (cut at 100)")
        ax.set_xlabel("episode")
        ax.set_ylim(0, 105)
        ax.set_title("network alone (greedy) on the validation starts")
        ax.legend(loc="center right", fontsize="small")
    fig.tight_layout()
    write_atomic(path, lambda t: fig.savefig(t, dpi=110, format="png"))
