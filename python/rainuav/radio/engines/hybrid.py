"""What the engines compute before their powers are combined
([`engine_parts()`][rainuav.radio.engines.hybrid.engine_parts]): every cell's power by the rays, the
part of it the PE would carry, and the PE's power inside its cone.
[`rainuav.radio.outputs.maps.build_radio_map()`][rainuav.radio.outputs.maps.build_radio_map]
combines them into a map; the maps in time
([`rainuav.radio.outputs.timemap`][rainuav.radio.outputs.timemap]) reuse the PE's part from clear
air at every instant."""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from rainuav import _core
from rainuav.radio.engines import engine_of
from rainuav.radio.engines.grid import MarchGrid, cone_weight, march_grid
from rainuav.radio.engines.pe_engine import march_cell, march_cell_levels, resample
from rainuav.radio.engines.ray_engine import SOILS, Weight, ray_power
from rainuav.radio.scene.cell import Cell
from rainuav.radio.scene.scenario import Scenario, Site

__all__ = ["EngineParts", "engine_parts", "engine_parts_levels", "inside_cone"]


def inside_cone(grid: MarchGrid) -> Weight:
    """The PE's share of a pattern: the cone weight in front of the antenna, 0 behind.

    Args:
        grid: The cell's march grid.

    Returns:
        The weight, a function of the direction cosines.
    """

    def weight(sx: np.ndarray, sy: np.ndarray, sz: np.ndarray) -> np.ndarray:
        return np.asarray(np.where(sz > 0, cone_weight(grid.sine_h, grid.sine_v, sx, sy), 0.0))

    return weight


@dataclass
class EngineParts:
    """Each cell's powers (M, H, W), mW, before they are combined."""

    power: np.ndarray
    """By the rays, the whole pattern (zeros for engine 'pe')."""
    carried: np.ndarray
    """By the rays, the part of the pattern inside the PE's cone (zeros where not marched)."""
    pe_power: np.ndarray
    """By the PE, inside its cone (zeros where not marched)."""
    grids: list[MarchGrid | None]
    """Each cell's march grid (None: not marched)."""
    timings: dict[str, float] = field(default_factory=dict)

    @property
    def weights(self) -> list[Weight | None]:
        """Each cell's cone weight on its pattern (None: not marched)."""
        return [None if g is None else inside_cone(g) for g in self.grids]


def engine_parts(
    scn: Scenario,
    cells: Sequence[tuple[Site, Cell]],
    x_m: np.ndarray,
    y_m: np.ndarray,
    progress: bool = False,
) -> EngineParts:
    """The rays' and the PE's powers of a scenario's engine at the pixel centres.

    The PE marches for engines 'pe' and 'hybrid' over a 'pec' ground or none; the hybrid does not
    march a cell whose cone carries under 1% of its power at every pixel.

    Args:
        scn: The scenario.
        cells: Its `(site, cell)` pairs.
        x_m: The pixel centres' east (W,), m.
        y_m: Their north (H,), m.
        progress: A line on standard error per march.

    Returns:
        The parts the map is summed from.
    """
    h, w = y_m.size, x_m.size
    use_pe = engine_of(scn).marches and scn.ground not in SOILS
    grids = [march_grid(scn, site, cell) if use_pe else None for site, cell in cells]
    timings: dict[str, float] = {}
    power = np.zeros((len(cells), h, w))
    carried = np.zeros_like(power)
    if engine_of(scn).traces:
        t_r = time.perf_counter()
        # What the PE would carry, by the rays: a cell whose cone carries under 1% of its
        # power at every pixel (the UAV above a down-tilted sector's cone) is not marched.
        weights = [None if g is None else inside_cone(g) for g in grids]
        power, in_cone = ray_power(scn, cells, x_m, y_m, weights if use_pe else None)
        if in_cone is not None:
            carried = in_cone
            with np.errstate(divide="ignore", invalid="ignore"):
                frac = np.where(power > 0, carried / power, 0.0)
            for m in range(len(grids)):
                if grids[m] is None or float(frac[m].max()) < 0.01:
                    grids[m] = None
                    carried[m] = 0.0
        timings["rays"] = time.perf_counter() - t_r
    for grid in grids:
        if grid is not None:
            _core.check_memory(grid.bytes)
    pe_power = np.zeros_like(power)
    bar = None
    marches = sum(g is not None for g in grids)
    if progress and marches:
        from tqdm.auto import tqdm

        bar = tqdm(total=marches, desc="radio map (PE)", unit="cell")
    try:
        for m, ((site, cell), grid) in enumerate(zip(cells, grids, strict=True)):
            if grid is not None:
                p = march_cell(scn, site, cell, grid, timings)
                t_r = time.perf_counter()
                pe_power[m] = resample(scn, site, grid, p, x_m, y_m)
                timings["resample"] = timings.get("resample", 0.0) + time.perf_counter() - t_r
                if bar is not None:
                    bar.update(1)
    finally:
        if bar is not None:
            bar.close()
    return EngineParts(power, carried, pe_power, grids, timings)


def engine_parts_levels(
    scns: Sequence[Scenario],
    cells: Sequence[tuple[Site, Cell]],
    x_m: np.ndarray,
    y_m: np.ndarray,
    progress: bool = False,
) -> list[EngineParts]:
    """`engine_parts()` at several flight altitudes, each cell marched once.

    Its grid is the one of the highest level (its top clears every level), every level's two rows
    are recorded after each step, and the rays' part inside the cone at each level uses that grid's
    cone. A cell whose cone carries under 1% of its power at every pixel of every level is not
    marched.

    Args:
        scns: The scenario at each level, lowest first (engine 'pe' or 'hybrid' over flat ground).
        cells: Their `(site, cell)` pairs.
        x_m: The pixel centres' east (W,), m.
        y_m: Their north (H,), m.
        progress: A line on standard error per march.

    Returns:
        Each level's parts, lowest first.
    """
    top = scns[-1]
    heights = [s.area.altitude_m for s in scns]
    h, w = y_m.size, x_m.size
    grids = [march_grid(top, site, cell) for site, cell in cells]
    timings: dict[str, float] = {}
    weights = [None if g is None else inside_cone(g) for g in grids]
    parts = []
    marched = np.zeros(len(cells), dtype=bool)
    for scn in scns:
        power = np.zeros((len(cells), h, w))
        carried = np.zeros_like(power)
        if engine_of(top).traces:
            t_r = time.perf_counter()
            power, in_cone = ray_power(scn, cells, x_m, y_m, weights)
            carried = np.zeros_like(power) if in_cone is None else in_cone
            with np.errstate(divide="ignore", invalid="ignore"):
                frac = np.where(power > 0, carried / power, 0.0)
            marched |= frac.reshape(len(cells), -1).max(axis=1) >= 0.01
            timings["rays"] = timings.get("rays", 0.0) + time.perf_counter() - t_r
        else:
            marched[:] = True
        parts.append(EngineParts(power, carried, np.zeros_like(power), list(grids), timings))
    for m, g in enumerate(grids):
        if g is None or not marched[m]:
            for p in parts:
                p.grids[m] = None
                p.carried[m] = 0.0
        else:
            _core.check_memory(g.bytes + 2 * len(scns) * g.steps * g.nx * 8)
    bar = None
    todo = [m for m in range(len(cells)) if parts[0].grids[m] is not None]
    if progress and todo:
        from tqdm.auto import tqdm

        bar = tqdm(total=len(todo), desc="radio map (PE, every level)", unit="cell")
    try:
        for m in todo:
            site, cell = cells[m]
            grid = grids[m]
            assert grid is not None
            p = march_cell_levels(top, site, cell, grid, heights, timings)
            t_r = time.perf_counter()
            for k, scn in enumerate(scns):
                parts[k].pe_power[m] = resample(scn, site, grid, p[k], x_m, y_m)
            timings["resample"] = timings.get("resample", 0.0) + time.perf_counter() - t_r
            if bar is not None:
                bar.update(1)
    finally:
        if bar is not None:
            bar.close()
    return parts
