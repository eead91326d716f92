"""A scenario's buildings as the radio layer uses them (PHYSICS.md section 12): the boxes of
``Scenario.buildings`` and the footprints of ``Scenario.footprints``
(:mod:`rainuav.ground.footprints`) as one set of prisms standing on the terrain, their walls,
and the pixels they touch.

- **One kind of obstacle.** A box is the four-cornered footprint; both are
  :class:`rainuav._core.Prisms` for the ray engine (profiles, diffraction, visibility) and for
  the parabolic equation's obstacle heights.
- **Merged where they touch.** Footprints with the same heights and material that touch are
  merged into one polygon (a building mapped in parts, or a terrace of equal houses): a wall
  between two parts is inside a building, so it neither reflects nor adds a face to a path's
  profile. The result is the same whatever the order of the features.
- **Walls** are the merged footprints' edges (outer rings counter-clockwise, holes
  clockwise: the outward normal on each edge's right), from the prism's bottom to the eaves;
  where a neighbour stands against a wall, the wall starts at the neighbour's roof (and is
  gone where the neighbour is as tall: inside the block). Their material's
  permittivity is ITU-R P.2040's at the scenario's frequency.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

from rainuav import _core
from rainuav._checks import check_fits
from rainuav.errors import InvalidInputError
from rainuav.ground.footprints import Footprint, material_permittivity, read_footprints
from rainuav.radio.cell import Cell, Weight, gain_linear, weight_at
from rainuav.radio.scenario import Scenario, Site
from rainuav.radio.terrain import core_args

__all__ = [
    "Buildings",
    "WallRays",
    "obstacle_args",
    "pixels_touched_max",
    "scenario_buildings",
    "trace_walls",
    "wall_args",
    "wall_terms",
]


@dataclass(frozen=True)
class Buildings:
    """A scenario's buildings, merged: footprints, prisms for the core, walls."""

    footprints: tuple[Footprint, ...]
    """The merged buildings (local metres)."""
    prisms: _core.Prisms
    """The same as the core takes them."""
    walls: np.ndarray
    """(K, 6): ``[ax, ay, bx, by, base, top]`` of every wall, m (outward normal on the right
    of a -> b; heights above the terrain)."""
    wall_material: tuple[str, ...]
    """Each wall's P.2040 material."""
    summary: str
    """What was read (one line; empty without a footprint file)."""


def _merge(items: list[Footprint]) -> list[Footprint]:
    """Footprints with the same heights and material that touch, merged (snapped to 1 mm
    and simplified within 1 micrometre, so collinear vertices go)."""
    import shapely

    groups: dict[tuple[Any, ...], list[Any]] = {}
    for f in items:
        groups.setdefault((f.height_m, f.min_height_m, f.wall_top_m, f.material), []).append(
            f.polygon
        )
    out = []
    for h, lo, eaves, material in sorted(groups, key=str):
        polys = shapely.set_precision(np.asarray(groups[(h, lo, eaves, material)]), 1e-3)
        merged = shapely.union_all(polys)
        parts = [p for p in shapely.get_parts(merged) if isinstance(p, shapely.Polygon)]
        parts = sorted(parts, key=lambda p: (p.bounds, p.area))
        for p in parts:
            p = shapely.simplify(shapely.geometry.polygon.orient(p, 1.0), 1e-6)
            if isinstance(p, shapely.Polygon) and p.area > 0:
                out.append(
                    Footprint(shapely.geometry.polygon.orient(p, 1.0), h, lo, eaves, material)
                )
    return out


def _prisms(items: list[Footprint]) -> _core.Prisms:
    """The footprints as the core's prisms (rings not closed)."""
    xy: list[np.ndarray] = []
    ring_starts, prism_rings, tops = [0], [0], []
    for f in items:
        for ring in [f.polygon.exterior, *f.polygon.interiors]:
            c = np.asarray(ring.coords)[:-1, :2]
            xy.append(c)
            ring_starts.append(ring_starts[-1] + len(c))
        prism_rings.append(len(ring_starts) - 1)
        tops.append(f.height_m)
    pts = np.concatenate(xy) if xy else np.zeros((0, 2))
    return _core.Prisms(
        np.ascontiguousarray(pts, dtype=float),
        np.asarray(ring_starts, dtype=np.int64),
        np.asarray(prism_rings, dtype=np.int64),
        np.asarray(tops, dtype=float),
    )


def _walls(items: list[Footprint]) -> tuple[np.ndarray, tuple[str, ...]]:
    """Every exposed wall (module docstring)."""
    import shapely

    polys = np.asarray([f.polygon for f in items], dtype=object)
    tree = shapely.STRtree(polys)
    rows: list[list[float]] = []
    materials: list[str] = []
    for k, f in enumerate(items):
        ends = []
        for ring in [f.polygon.exterior, *f.polygon.interiors]:
            c = np.asarray(ring.coords)[:, :2]
            ends.extend(itertools.pairwise(c))
        near = [j for j in tree.query(f.polygon, predicate="intersects") if j != k]
        # Each piece of each edge with its bottom: raised to a neighbour's roof where the
        # neighbour stands against it, gone where the neighbour reaches the eaves.
        pieces = [(a, b, f.min_height_m) for a, b in ends]
        for j in near:
            nbr = items[j]
            block = nbr.polygon.buffer(1e-3)
            split = []
            for a, b, base in pieces:
                seg = shapely.LineString([a, b])
                for part, bottom in (
                    (shapely.intersection(seg, block), max(base, nbr.height_m)),
                    (shapely.difference(seg, block), base),
                ):
                    if bottom >= f.eaves_m:
                        continue
                    for line in shapely.get_parts(part):
                        if not isinstance(line, shapely.LineString):
                            continue
                        c = np.asarray(line.coords)
                        if len(c) >= 2 and np.hypot(*(c[-1] - c[0])) > 1e-3:
                            # In the edge's own direction (its outward normal).
                            same = np.dot(c[-1] - c[0], np.asarray(b) - np.asarray(a)) > 0
                            p, q = (c[0], c[-1]) if same else (c[-1], c[0])
                            split.append((p, q, bottom))
            pieces = split
        for a, b, base in pieces:
            rows.append([a[0], a[1], b[0], b[1], base, f.eaves_m])
            materials.append(f.material)
    return np.asarray(rows, dtype=float).reshape(-1, 6), tuple(materials)


@lru_cache(maxsize=8)
def _build(key: str, scn_json: str) -> Buildings:
    del key
    scn = Scenario.from_dict(__import__("json").loads(scn_json))
    items: list[Footprint] = []
    import shapely

    for b in scn.buildings:
        items.append(Footprint(shapely.box(b.x0_m, b.y0_m, b.x1_m, b.y1_m), b.height_m))
    summary = ""
    if scn.footprints is not None and scn.georef is not None:
        fp = read_footprints(
            scn.footprints.file, scn.georef, scn.area.bounds, scn.footprints.material
        )
        items.extend(fp.buildings)
        summary = fp.summary()
    merged = _merge(items)
    for j, s in enumerate(scn.sites):
        pt = shapely.Point(s.x_m, s.y_m)
        for f in merged:
            if f.height_m >= s.height_m and shapely.contains(f.polygon, pt):
                raise InvalidInputError(
                    f"sites[{j}] stands inside a building {f.height_m:g} m tall, as tall as its "
                    f"antenna ({s.height_m:g} m above the ground): give the roof in height_m"
                )
    walls, materials = _walls(merged)
    return Buildings(tuple(merged), _prisms(merged), walls, materials, summary)


def scenario_buildings(scn: Scenario) -> Buildings | None:
    """The buildings of ``scn`` (boxes and footprints; read once per file contents, area and
    sites), or None where it has neither."""
    if not scn.buildings and scn.footprints is None:
        return None
    import json

    d = scn.to_dict()
    keep = {k: d[k] for k in ("area", "sites", "buildings", "origin", "footprints") if k in d}
    text = json.dumps({**keep, "sites": d["sites"]}, sort_keys=True)
    return _build(scn.digest() if scn.footprints is not None else text, text)


def wall_args(scn: Scenario) -> tuple[np.ndarray, np.ndarray]:
    """The walls (K, 6) and their permittivities (K, 2: real, imaginary) at ``scn``'s
    frequency, as :func:`rainuav._core.ray_walls` takes them."""
    b = scenario_buildings(scn)
    if b is None or b.walls.shape[0] == 0:
        return np.zeros((0, 6)), np.zeros((0, 2))
    eps = {m: material_permittivity(m, scn.freq_hz) for m in set(b.wall_material)}
    e = np.array([[eps[m].real, eps[m].imag] for m in b.wall_material], dtype=float)
    return np.ascontiguousarray(b.walls), e


def pixels_touched_max(scn: Scenario, shape: tuple[int, int] | None = None) -> np.ndarray:
    """The tallest building (m above the terrain) whose footprint overlaps each pixel of the
    area (an overlap of positive area: footprints intersected with pixels as polygons),
    (H, W)."""
    import shapely

    a = scn.area
    h, w = a.shape if shape is None else shape
    out = np.zeros((h, w))
    b = scenario_buildings(scn)
    if b is None:
        return out
    check_fits("the buildings' pixel heights", 16.0 * h * w, "use a coarser map")
    px = (a.x_max_m - a.x_min_m) / w
    py = (a.y_max_m - a.y_min_m) / h
    for f in b.footprints:
        x0, y0, x1, y1 = f.polygon.bounds
        j0, j1 = max(0, int((x0 - a.x_min_m) // px)), min(w - 1, int((x1 - a.x_min_m) // px))
        i0, i1 = max(0, int((y0 - a.y_min_m) // py)), min(h - 1, int((y1 - a.y_min_m) // py))
        if j0 > j1 or i0 > i1:
            continue
        jj, ii = np.meshgrid(np.arange(j0, j1 + 1), np.arange(i0, i1 + 1))
        cells = shapely.box(
            a.x_min_m + jj * px, a.y_min_m + ii * py, a.x_min_m + (jj + 1) * px,
            a.y_min_m + (ii + 1) * py,
        )  # fmt: skip
        hit = shapely.intersects(cells, f.polygon) & ~shapely.touches(cells, f.polygon)
        block = out[i0 : i1 + 1, j0 : j1 + 1]
        np.maximum(block, np.where(hit, f.height_m, 0.0), out=block)
    return out


def _heights(scn: Scenario) -> tuple[np.ndarray | None, tuple[float, float, float, float]]:
    if scn.height_map_m is None:
        return None, (0.0, 1.0, 0.0, 1.0)
    hm = np.ascontiguousarray(np.asarray(scn.height_map_m, dtype=float))
    a = scn.area
    rows, cols = hm.shape
    return hm, (
        a.x_min_m,
        (a.x_max_m - a.x_min_m) / cols,
        a.y_min_m,
        (a.y_max_m - a.y_min_m) / rows,
    )


def obstacle_args(scn: Scenario) -> dict[str, Any]:
    """The buildings (boxes and footprints, :mod:`rainuav.radio.buildings`) and the height
    map of ``scn`` as the core's ray functions take them."""
    b = scenario_buildings(scn)
    heights, h_os = _heights(scn)
    return {
        "buildings": np.zeros((0, 5)),
        "prisms": None if b is None else b.prisms,
        "heights": heights,
        "heights_origin_step": h_os,
    }


WallRays = tuple[np.ndarray, ...]
"""Per wall ray (:func:`rainuav._core.ray_walls`): its site (index into the distinct sites),
pixel, departure azimuth and elevation (degrees), power per mW for isotropic antennas, and
length (m)."""


def trace_walls(
    scn: Scenario, jobs: Sequence[tuple[Site, Cell]], x_m: np.ndarray, y_m: np.ndarray
) -> tuple[WallRays, dict[int, int]] | None:
    """Every ray the walls of ``scn`` reflect from each distinct site of ``jobs`` to each
    pixel, and each site's index; None without walls."""
    walls, eps = wall_args(scn)
    if walls.shape[0] == 0:
        return None
    unique = list({id(s): s for s, _ in jobs}.values())
    index = {id(s): k for k, s in enumerate(unique)}
    rays = _core.ray_walls(
        np.array([[s.x_m, s.y_m, s.height_m] for s in unique], dtype=float).reshape(-1, 3),
        np.ascontiguousarray(x_m, dtype=float),
        np.ascontiguousarray(y_m, dtype=float),
        walls,
        eps,
        altitude_m=scn.area.altitude_m,
        freq_hz=scn.freq_hz,
        polarization=scn.polarization,
        **obstacle_args(scn),
        **core_args(scn),
    )
    return rays, index


def wall_terms(
    scn: Scenario,
    jobs: Sequence[tuple[Site, Cell]],
    x_m: np.ndarray,
    y_m: np.ndarray,
    weights: Sequence[Weight | None] | None = None,
    rays: tuple[WallRays, dict[int, int]] | None = None,
) -> np.ndarray | None:
    """Each cell's rays reflected by walls at every pixel (PHYSICS.md section 12), (M, H, W,
    2): their clear-air power (mW, each with the cell's gain toward its specular point; added
    incoherently) and their power-weighted mean length (m); with ``weights``, the part of
    each pattern they select. None where ``scn`` has no walls (``rays``: from
    :func:`_wall_rays`, traced here if not given)."""
    traced = trace_walls(scn, jobs, x_m, y_m) if rays is None else rays
    if traced is None:
        return None
    (site_k, pixel, az, el, factor, length), index = traced
    plane = y_m.size * x_m.size
    out = np.zeros((len(jobs), plane, 2))
    for m, (site, cell) in enumerate(jobs):
        sel = site_k == index[id(site)]
        g = gain_linear(cell, az[sel], el[sel])
        if weights is not None:
            w = weights[m]
            g = g * (0.0 if w is None else weight_at(w, cell, az[sel], el[sel]))
        p = 10 ** (cell.tx_power_dbm / 10) * g * factor[sel]
        total = np.bincount(pixel[sel], p, minlength=plane)
        dl = np.bincount(pixel[sel], p * length[sel], minlength=plane)
        out[m, :, 0] = total
        out[m, :, 1] = np.divide(dl, total, out=np.zeros(plane), where=total > 0)
    return out.reshape(len(jobs), y_m.size, x_m.size, 2)
