"""Figures of radio maps (matplotlib; no global state: figures are built without pyplot
unless the caller hands in an Axes or wants an interactive figure)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from rainuav._io import write_atomic
from rainuav.errors import InvalidInputError
from rainuav.radio.sinr import RSS_FLOOR_DBM

__all__ = ["KINDS", "plot_map", "save_map_png"]

KINDS = ("sir", "sinr", "rss", "serving")


def plot_map(rm: Any, kind: str = "sir", cell: int | None = None, ax: Any = None) -> Any:
    """Draws the map ``rm`` (a RadioMap): ``kind`` 'sir', 'sinr', 'rss' (dB; ``cell``
    selects one cell's RSS, default the strongest) or 'serving' (the serving cell), with
    the sites and beam azimuths marked. Returns the matplotlib Axes (a new pyplot figure
    when ``ax`` is None)."""
    if kind not in KINDS:
        raise InvalidInputError(f"kind must be one of {KINDS} (got {kind!r})")
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(6, 5))
    if kind == "rss":
        if cell is None:
            data, label = rm.rss_dbm.max(axis=0), "RSS of the strongest cell [dBm]"
        else:
            if not 0 <= cell < len(rm.rss_dbm):
                raise InvalidInputError(f"cell must be within 0..{len(rm.rss_dbm) - 1}")
            data, label = rm.rss_dbm[cell], f"RSS of cell {cell} [dBm]"
        finite = data[data > RSS_FLOOR_DBM]
        vmin = float(np.percentile(finite, 2)) if finite.size else None
        im = ax.imshow(data, origin="lower", extent=rm.extent_m, cmap="viridis", vmin=vmin)
    elif kind == "serving":
        data, label = rm.serving_cell, "serving cell"
        cells = max(len(rm.rss_dbm), 1)
        im = ax.imshow(
            data, origin="lower", extent=rm.extent_m, cmap="tab20", vmin=-0.5, vmax=cells - 0.5
        )
    else:
        data = rm.sir_db if kind == "sir" else rm.sinr_db
        label = f"{kind.upper()} [dB]"
        # Colour scale from the map itself (a physical uma map spans -6..+3 dB).
        lo = min(-10.0, float(np.percentile(data, 1)))
        hi = max(float(np.percentile(data, 99)), lo + 10.0)
        im = ax.imshow(data, origin="lower", extent=rm.extent_m, cmap="RdYlGn", vmin=lo, vmax=hi)
    ax.figure.colorbar(im, ax=ax, label=label)
    _rain_contours(rm, ax)
    xs = [s.x_m for s in rm.scenario.sites]
    ys = [s.y_m for s in rm.scenario.sites]
    ax.plot(xs, ys, "k^", markersize=7, markerfacecolor="white", label="sites")
    for s in rm.scenario.sites:
        for c in s.cells:
            phi = math.radians(c.azimuth_deg)
            ax.annotate(
                "",
                xy=(s.x_m + 120 * math.cos(phi), s.y_m + 120 * math.sin(phi)),
                xytext=(s.x_m, s.y_m),
                arrowprops={"arrowstyle": "->", "lw": 1},
            )
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(f"{rm.scenario.name}: {label}, {rm.altitude_m:g} m")
    return ax


RAIN_CONTOURS_MM_H = (10.0, 30.0, 100.0)
"""Rain rates outlined on maps whose rain varies over the area (cells, storms, rate maps)."""


def _rain_contours(rm: Any, ax: Any) -> None:
    """Outlines the rain at :data:`RAIN_CONTOURS_MM_H` where the weather varies over the area
    (rain cells, a storm at its instant, a rate map), labelled in mm/h."""
    from rainuav.radio.pe_engine import rain_rate_at

    if rm.scenario.medium.kind not in ("cells", "map"):
        return
    xx, yy = np.meshgrid(rm.x_m, rm.y_m)
    rate = rain_rate_at(rm.scenario, xx, yy)
    levels = [v for v in RAIN_CONTOURS_MM_H if rate.min() < v < rate.max()]
    if levels:
        cs = ax.contour(xx, yy, rate, levels=levels, colors="navy", linewidths=1.0)
        ax.clabel(cs, fmt="%g mm/h", fontsize=7)


def save_map_png(rm: Any, kind: str, path: str | Path) -> Path:
    """Writes one map figure as PNG (atomically), without touching pyplot's state."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.5, 5.2))
    plot_map(rm, kind, ax=fig.subplots())
    fig.tight_layout()
    return write_atomic(path, lambda t: fig.savefig(t, dpi=110, format="png"))
