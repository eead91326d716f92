"""The flight's figure (``flight.png``) that ``fly`` writes, at one altitude or among
levels."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np

from rainuav._io import write_atomic
from rainuav.geo import latlon_text
from rainuav.missions import corners
from rainuav.radio.scene import presets

__all__ = ["flight_figure", "plot_flight"]


def plot_flight(rm: Any, path: np.ndarray, place: Any, where: Path, heights: Any = None) -> None:
    """Writes `flight.png` ([`flight_figure()`][rainuav.fly.figure.flight_figure]), atomically.

    Args:
        rm: The map flown (or maps in time).
        path: The flight's path (N, 2), m.
        place: The place.
        where: The file.
        heights: Among levels, `(t_s, altitude_m, outage)` a vertex.
    """
    fig = flight_figure(rm, path, place, heights)
    write_atomic(where, lambda tmp: fig.savefig(tmp, dpi=90, format="png"))


def flight_figure(rm: Any, path: np.ndarray, place: Any, heights: Any = None) -> Any:
    """The figure of `flight.png`: the path over the SINR at take-off, with what the UAV must avoid.

    The rain at take-off outlined, the buildings' footprints, the pixels the UAV may not fly
    (hatched), the waypoints, the sites, the start and the destination; the legend below the map,
    where it hides nothing.

    Args:
        rm: The map flown (a series: its first instant).
        path: The flight's path (N, 2), m.
        place: The place.
        heights: Among levels, `(t_s, altitude_m, outage)` a vertex, drawn below as the height
            against time with the moves in outage marked.

    Returns:
        The matplotlib Figure.
    """
    from matplotlib.figure import Figure

    if heights is None:
        fig = Figure(figsize=(6.4, 5.6), layout="constrained")
        ax = fig.subplots()
    else:
        fig = Figure(figsize=(6.4, 7.6), layout="constrained")
        ax, prof = fig.subplots(2, 1, height_ratios=[3.2, 1.0])
        t, z, out = (np.asarray(v) for v in heights)
        prof.plot(t, z, "k-", lw=1.2, label="height")
        prof.plot(t[out], z[out], "r|", ms=8, label="in outage")
        prof.set_xlabel("flight time [s]")
        prof.set_ylabel("height [m]")
        prof.set_ylim(0.0, max(float(np.max(z)) * 1.15, 1.0))
        prof.legend(loc="lower right", fontsize="small")
    a = place.scenario.area
    x0, x1, y0, y1 = a.x_min_m, a.x_max_m, a.y_min_m, a.y_max_m
    lo = float(presets.SINR_THRESHOLDS_DB["uma"])
    sinr = rm.sinr_db if rm.sinr_db.ndim == 2 else rm.sinr_db[0]  # a series: at take-off
    im = ax.imshow(sinr, origin="lower", extent=(x0, x1, y0, y1), cmap="RdYlGn",
                   vmin=lo - 15, vmax=lo + 15)  # fmt: skip
    from rainuav.radio.engines.pe_engine import rain_rate_at

    scn = place.scenario
    if scn.medium.varies:  # the rain at take-off, outlined
        xx, yy = np.meshgrid(np.linspace(x0, x1, 200), np.linspace(y0, y1, 200))
        rate = rain_rate_at(dataclasses.replace(scn, medium=scn.medium.at(0.0)), xx, yy)
        levels = [v for v in (5.0, 20.0, 50.0) if rate.min() < v < rate.max()]
        if levels:
            cs = ax.contour(xx, yy, rate, levels=levels, colors="navy", linewidths=1.0)
            ax.clabel(cs, fmt="%g mm/h", fontsize=7)
    proxies = _obstacles(ax, rm, scn, (x0, x1, y0, y1), None)
    ax.plot(path[:, 0], path[:, 1], "k-", lw=1.5, label="planned flight")
    wp = path[corners(path)]
    ax.plot(wp[:, 0], wp[:, 1], "ko", ms=3, label="waypoints")
    for k, s in enumerate(place.scenario.sites):
        ax.plot(s.x_m, s.y_m, "k^", ms=7, label="sites" if k == 0 else None)
    ax.plot(*place.start_m, "bs", label="start")
    ax.plot(*place.goal_m, "b*", ms=12, label="destination")
    ax.set_xlabel("east of origin [m]")
    ax.set_ylabel("north of origin [m]")
    origin = latlon_text(place.georef.lat_deg, place.georef.lon_deg)
    level = "" if heights is None else f" at {float(np.asarray(heights[1])[0]):g} m"
    what = f"SINR{level} and rain" if scn.medium.varies else f"SINR{level}"
    ax.set_title(f"{what} at take-off; origin {origin}", fontsize=10)
    fig.colorbar(im, ax=ax, label="SINR [dB]")
    # Below the map: a legend inside it could hide the destination.
    handles, labels = ax.get_legend_handles_labels()
    handles += proxies
    labels += [h.get_label() for h in proxies]
    fig.legend(handles, labels, loc="outside lower center", ncols=4, fontsize="small",
               frameon=False)  # fmt: skip
    return fig


def _obstacles(
    ax: Any, rm: Any, scn: Any, extent: tuple[float, ...], level: int | None
) -> list[Any]:
    """The buildings' footprints (grey) and the pixels the UAV may not fly (hatched: terrain
    or a building within the clearance of the flight height) on ``ax``; returns the legend's
    entry for the hatching (contours carry no label)."""
    from matplotlib.patches import Patch, Polygon

    proxies: list[Any] = []
    nf = getattr(rm, "not_flyable", None)
    if nf is not None:
        nf = np.asarray(nf)
        if nf.ndim == 3:
            nf = nf[0 if level is None else level]
        if nf.any():
            h, w = nf.shape
            xs = np.linspace(extent[0], extent[1], w + 1)
            ys = np.linspace(extent[2], extent[3], h + 1)
            ax.contourf(0.5 * (xs[1:] + xs[:-1]), 0.5 * (ys[1:] + ys[:-1]), nf.astype(float),
                        levels=[0.5, 1.5], colors="none", hatches=["xxxx"])  # fmt: skip
            proxies.append(Patch(facecolor="none", edgecolor="0.2", hatch="xxxx", lw=0.5,
                                 label="not flyable"))  # fmt: skip
    if scn.buildings or scn.footprints is not None:
        from rainuav.radio.scene.buildings import scenario_buildings

        b = scenario_buildings(scn)
        for k, f in enumerate(() if b is None else b.footprints):
            ring = np.asarray(f.polygon.exterior.coords)[:, :2]
            label = "buildings" if k == 0 else None
            ax.add_patch(Polygon(ring, closed=True, facecolor="0.55", edgecolor="0.25",
                                 lw=0.4, alpha=0.6, label=label))  # fmt: skip
    return proxies
