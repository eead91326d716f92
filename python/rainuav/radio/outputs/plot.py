"""Figures of radio maps (matplotlib; no global state: figures are built without pyplot
unless the caller hands in an Axes or wants an interactive figure)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rainuav._io import write_atomic
from rainuav.errors import InvalidInputError
from rainuav.radio.outputs.sinr import RSS_FLOOR_DBM

if TYPE_CHECKING:  # for the annotations alone
    from rainuav.radio.outputs.mapdata import RadioMap
    from rainuav.radio.outputs.timemap import RadioMapSeries

__all__ = ["KINDS", "plot_map", "save_map_png", "save_series_gif"]

KINDS = ("sir", "sinr", "rss", "serving", "rss_std", "rss_sample_std", "correction")
"""What a map figure shows; the last two only for a map corrected by measurements."""


def plot_map(rm: RadioMap, kind: str = "sir", cell: int | None = None, ax: Any = None) -> Any:
    """Draws a map with the sites and beam azimuths marked.

    Args:
        rm: The map (a [`RadioMap`][rainuav.radio.outputs.mapdata.RadioMap]).
        kind: "sir", "sinr", "rss" (dB) or "serving" (the serving cell); for a map that carries its
            spreads "rss_std" (the serving cell's standard deviation), for a corrected one
            "correction" (the serving cell's corrected minus prior power).
        cell: With "rss", the one cell to draw; None: the strongest.
        ax: A matplotlib Axes to draw on; None: a new pyplot figure.

    Returns:
        The Axes.

    Raises:
        InvalidInputError: An unknown kind, a cell out of range, or a kind the map cannot show.
    """
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
        reach = data > RSS_FLOOR_DBM
        finite = data[reach]
        vmin = float(np.percentile(finite, 2)) if finite.size else None
        # Out of reach (no path: the files hold the -250 dBm floor): grey, and said so.
        import matplotlib as mpl

        cmap = mpl.colormaps["viridis"].with_extremes(bad="0.75")
        shown = np.ma.masked_where(~reach, data)
        im = ax.imshow(shown, origin="lower", extent=rm.extent_m, cmap=cmap, vmin=vmin)
        if not reach.all():
            from matplotlib.patches import Patch

            floor = Patch(
                facecolor="0.75", label=f"out of reach ({RSS_FLOOR_DBM:g} dBm in the files)"
            )
            ax.legend(handles=[floor], loc="upper right", fontsize="small", framealpha=0.8)
    elif kind in ("rss_std", "rss_sample_std", "correction"):
        if rm.rss_std_db is None or (kind == "rss_sample_std" and rm.rss_sample_std_db is None):
            raise InvalidInputError(f"kind {kind!r} needs a map that carries its spreads")
        if kind == "correction" and rm.prior_rss_dbm is None:
            raise InvalidInputError("kind 'correction' needs a map corrected by measurements")
        data, label, cmap, lo, hi = _measured(rm, kind)
        im = ax.imshow(data, origin="lower", extent=rm.extent_m, cmap=cmap, vmin=lo, vmax=hi)
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
    _sites(rm, ax)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(f"{rm.scenario.name}: {label}, {rm.altitude_m:g} m")
    return ax


def _measured(rm: RadioMap, kind: str) -> tuple[Any, str, str, float, float | None]:
    """A corrected map's 'rss_std' or 'correction' figure: data, label, colours and range."""
    ii, jj = np.indices(rm.serving_cell.shape)
    s = np.maximum(rm.serving_cell, 0)
    if kind == "rss_std":
        data = rm.rss_std_db[s, ii, jj]
        if rm.prior_rss_dbm is None:  # a physics map's prior: the site error sets the floor
            lo, hi = (float(np.percentile(data, q)) for q in (1, 99))
            return (data, "prior local-mean RSS std, serving cell [dB]", "magma", lo,
                    max(hi, lo + 1.0))  # fmt: skip
        return data, "local-mean RSS std, serving cell [dB]", "magma", 0.0, None
    if kind == "rss_sample_std":
        return (rm.rss_sample_std_db[s, ii, jj], "one sample's RSS std, serving cell [dB]",
                "magma", 0.0, None)  # fmt: skip
    d = rm.rss_dbm[s, ii, jj] - rm.prior_rss_dbm[s, ii, jj]
    m = max(1.0, float(np.percentile(np.abs(d), 99)))
    return d, "corrected - prior RSS, serving cell [dB]", "RdBu_r", -m, m


def _sites(rm: RadioMap, ax: Any) -> None:
    """Marks the sites and each cell's azimuth."""
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


RAIN_CONTOURS_MM_H = (10.0, 30.0, 100.0)
"""Rain rates outlined on maps whose rain varies over the area (cells, storms, rate maps)."""


def _rain_contours(rm: RadioMap, ax: Any) -> None:
    """Outlines the rain at [`RAIN_CONTOURS_MM_H`][rainuav.radio.outputs.plot.RAIN_CONTOURS_MM_H]
    where the weather varies over the area (rain cells, a storm at its instant, a rate map),
    labelled in mm/h."""
    from rainuav.radio.engines.pe_engine import rain_rate_at

    if not rm.scenario.medium.varies:
        return
    xx, yy = np.meshgrid(rm.x_m, rm.y_m)
    rate = rain_rate_at(rm.scenario, xx, yy)
    levels = [v for v in RAIN_CONTOURS_MM_H if rate.min() < v < rate.max()]
    if levels:
        cs = ax.contour(xx, yy, rate, levels=levels, colors="navy", linewidths=1.0)
        ax.clabel(cs, fmt="%g mm/h", fontsize=7)


def save_map_png(rm: RadioMap, kind: str, path: str | Path) -> Path:
    """Writes one map figure as PNG, atomically, without touching pyplot's state.

    Args:
        rm: The map.
        kind: As [`plot_map()`][rainuav.radio.outputs.plot.plot_map]'s.
        path: The file.

    Returns:
        The path written.
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.5, 5.2))
    plot_map(rm, kind, ax=fig.subplots())
    fig.tight_layout()
    return write_atomic(path, lambda t: fig.savefig(t, dpi=110, format="png"))


def save_series_gif(
    series: RadioMapSeries,
    path: str | Path,
    min_db: float | None = None,
    fps: float = 8.0,
    progress: bool = False,
) -> Path:
    """Writes the SINR of a map series as an animated GIF, one frame a slice on one colour scale.

    The rain outlined at each instant (10/30/100 mm/h), the outage edge dashed and the sites.

    Args:
        series: The [`RadioMapSeries`][rainuav.radio.outputs.timemap.RadioMapSeries].
        path: The file.
        min_db: The outage edge drawn, SINR dB; None: none drawn.
        fps: Frames a second.
        progress: A bar over the frames.

    Returns:
        The path written.
    """
    import io

    from matplotlib.figure import Figure
    from PIL import Image

    lo = min(-10.0, float(np.percentile(series.sinr_db, 1)))
    hi = max(float(np.percentile(series.sinr_db, 99)), lo + 10.0)
    from tqdm.auto import tqdm

    frames = []
    for t in tqdm(series.t_s, desc="storm.gif frames", unit="frame", disable=not progress):
        rm = series.at(float(t))
        fig = Figure(figsize=(6.0, 5.0))
        ax = fig.subplots()
        im = ax.imshow(
            rm.sinr_db, origin="lower", extent=rm.extent_m, cmap="RdYlGn", vmin=lo, vmax=hi
        )
        fig.colorbar(im, ax=ax, label="SINR [dB]")
        if min_db is not None and rm.sinr_db.min() < min_db < rm.sinr_db.max():
            ax.contour(rm.x_m, rm.y_m, rm.sinr_db, levels=[min_db], colors="k",
                       linestyles="--", linewidths=0.8)  # fmt: skip
        _rain_contours(rm, ax)
        _sites(rm, ax)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        edge = "" if min_db is None else f", outage edge {min_db:g} dB dashed"
        ax.set_title(f"{rm.scenario.name}: SINR at t = {t:.0f} s{edge}", fontsize=9)
        fig.tight_layout()
        buf = io.BytesIO()
        fig.savefig(buf, dpi=80, format="png")
        frames.append(Image.open(buf).convert("P", palette=Image.Palette.ADAPTIVE))
    ms = round(1000.0 / fps)

    def write(tmp: Path) -> None:
        frames[0].save(tmp, format="GIF", save_all=True, append_images=frames[1:],
                       duration=ms, loop=0)  # fmt: skip

    return write_atomic(path, write)
