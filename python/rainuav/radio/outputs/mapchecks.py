"""The checks a map file's arrays pass as they are read: shapes from the scenario, finite values
in their physical ranges, the pixel centres of the area
([`RadioMap.load()`][rainuav.radio.outputs.mapdata.RadioMap.load] and the maps in time's loader)."""

from __future__ import annotations

from typing import Any

import numpy as np

from rainuav.errors import InvalidInputError
from rainuav.radio.outputs.sinr import RSS_FLOOR_DBM, SIR_CEIL_DB, SIR_FLOOR_DB
from rainuav.radio.scene.scenario import Scenario

__all__ = ["check_arrays", "check_map_arrays", "map_ranges"]


def check_arrays(
    path: Any,
    data: dict[str, np.ndarray],
    scn: Scenario,
    shapes: dict[str, tuple[int, ...]],
    ranges: dict[str, tuple[float, float]],
) -> None:
    """Checks a file's arrays: shapes, finite values, ranges, and the pixel centres of the area.

    Args:
        path: The file, for the messages.
        data: The arrays by name.
        scn: The file's scenario.
        shapes: The shape each array must have.
        ranges: The bounds each array must lie within.

    Raises:
        InvalidInputError: An array not numeric, of another shape, not finite, out of its bounds, or
            pixel centres that are not the area's (the file and the array named).
    """
    for k, shape in shapes.items():
        a = data[k]
        if a.shape != shape or a.dtype.kind not in "fiu":
            raise InvalidInputError(
                f"{path}: {k} must be a numeric array of shape {shape} for its scenario "
                f"(got {a.dtype} {a.shape})"
            )
        if a.dtype.kind == "f" and not np.all(np.isfinite(a)):
            raise InvalidInputError(f"{path}: {k} holds NaN or infinite values")
    for k, (lo, hi) in ranges.items():
        a = data[k]
        if a.size and (a.min() < lo or a.max() > hi):
            raise InvalidInputError(
                f"{path}: {k} must lie in [{lo:g}, {hi:g}] (holds {a.min():g} to {a.max():g})"
            )
    for k, want in zip(("x_m", "y_m"), scn.area.centres(), strict=True):
        if not np.allclose(data[k], want, rtol=0, atol=1e-6 * max(1.0, float(np.ptp(want)))):
            raise InvalidInputError(f"{path}: {k} is not the pixel centres of its area")


def check_map_arrays(path: Any, data: dict[str, np.ndarray], scn: Scenario) -> None:
    """Checks a map's arrays as `build_radio_map()` writes them.

    Shapes from the scenario, types, and values finite and in their physical ranges (SIR and SINR
    within [SIR_FLOOR_DB, SIR_CEIL_DB], RSS within [RSS_FLOOR_DBM, 100] dBm, serving cells and sites
    that exist, PE shares in [0, 1], pixel centres where the area puts them).

    Args:
        path: The file, for the messages.
        data: The arrays by name.
        scn: The file's scenario.

    Raises:
        InvalidInputError: An array that fails a check (the file and the array named).
    """
    h, w = scn.area.shape
    m = len(data["cell_site"]) if data["cell_site"].ndim == 1 else -1  # the map's own cells
    shapes = {
        "x_m": (w,), "y_m": (h,), "rss_dbm": (m, h, w), "serving_cell": (h, w),
        "sir_db": (h, w), "sinr_db": (h, w), "cell_site": (m,), "pe_share": (m, h, w),
        "pe_cone_deg": (m, 2),
    }  # fmt: skip
    check_arrays(path, data, scn, shapes, map_ranges(m, scn) | {
        "pe_share": (0.0, 1.0), "pe_cone_deg": (0.0, 90.0),
    })  # fmt: skip


def map_ranges(cells: int, scn: Scenario) -> dict[str, tuple[float, float]]:
    """The physical ranges of a map's (or a series') power, SIR, SINR, serving cell and sites.

    Args:
        cells: The map's cells.
        scn: The scenario.

    Returns:
        `(low, high)` by array name.
    """
    return {
        "sir_db": (SIR_FLOOR_DB, SIR_CEIL_DB),
        "sinr_db": (SIR_FLOOR_DB, SIR_CEIL_DB),
        "rss_dbm": (RSS_FLOOR_DBM, 100.0),
        "serving_cell": (-1, cells - 1),
        "cell_site": (0, len(scn.sites) - 1),
    }
