"""A study's map figures: the SINR (``maps.png``) or the best cell's received power
(``rss.png``) of every distinct scenario among its cases on one colour scale, and beside each
its difference from the base case's map."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from rainuav._io import write_atomic
from rainuav.studies.spec import Case, case_scenario, train_config

__all__ = ["plot_maps"]


QUANTITIES = {
    "sinr": ("SINR [dB]", "RdYlGn", lambda rm: rm.sinr_db),
    "rss": ("best RSS [dBm]", "viridis", lambda rm: np.max(rm.rss_dbm, axis=0)),
}


def plot_maps(cases: list[Case], path: Path, quantity: str = "sinr") -> bool:
    """Writes a PNG of a study's maps and their differences from the base case's.

    The first seed of each case; one colour scale for the maps.

    Args:
        cases: The study's cases.
        path: The PNG.
        quantity: "sinr", or "rss" (the best cell's received power).

    Returns:
        False where there is only one map (nothing to compare).
    """
    from matplotlib.figure import Figure

    from rainuav.radio.outputs.maps import build_radio_map

    maps: list[tuple[str, Any]] = []
    seen: set[str] = set()
    for case in cases:
        fields = dict(case.fields)
        scn = case_scenario(fields, train_config(fields, case.seed, "unused"))
        if scn.digest() in seen:
            continue
        seen.add(scn.digest())
        maps.append((case.id.rsplit("_s", 1)[0], build_radio_map(scn)))  # from the cache
    if len(maps) < 2:
        return False
    label, cmap, of = QUANTITIES[quantity]
    values = [of(m) for _, m in maps]
    lo, hi = (float(np.percentile(np.stack(values), q)) for q in (2, 98))
    diffs = [v - values[0] for v in values]
    span = max(float(np.max(np.abs(d))) for d in diffs) or 1.0
    fig = Figure(figsize=(8.0, 3.4 * len(maps)), layout="constrained")
    axes = fig.subplots(len(maps), 2, squeeze=False)
    for (name, rm), v, d, (a, b) in zip(maps, values, diffs, axes, strict=True):
        extent = rm.extent_m
        im = a.imshow(v, origin="lower", extent=extent, cmap=cmap, vmin=lo, vmax=hi)
        a.set_title(f"{name}: {label}", fontsize="small")
        fig.colorbar(im, ax=a)
        im = b.imshow(d, origin="lower", extent=extent, cmap="RdBu", vmin=-span, vmax=span)
        b.set_title(f"{name} minus {maps[0][0]} [dB]", fontsize="small")
        fig.colorbar(im, ax=b)
        for ax in (a, b):
            ax.set_xticks([])
            ax.set_yticks([])
    write_atomic(path, lambda t: fig.savefig(t, dpi=90, format="png"))
    return True
