"""A scenario's buildings as the radio layer uses them ([physics reference, section
12][12-terrain-buildings-diffraction-and-reflections]): the boxes of ``Scenario.buildings`` and the
footprints of ``Scenario.footprints`` ([`rainuav.ground.footprints`][rainuav.ground.footprints]) as
one set of prisms standing on the terrain, their walls, and the pixels they touch.

- **One kind of obstacle.** A box is the four-cornered footprint; both are
  `rainuav._core.Prisms` for the ray engine (profiles, diffraction, visibility) and for
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
from typing import Any

import numpy as np

from rainuav import _core
from rainuav._checks import check_fits
from rainuav.errors import InvalidInputError
from rainuav.ground.footprints import Footprint, material_permittivity, read_footprints
from rainuav.radio.scene.scenario import Scenario

__all__ = [
    "NEAR_ROUTE_M",
    "Buildings",
    "buildings_near_route",
    "default_height_warning",
    "pixels_touched_max",
    "prism_eps",
    "scenario_buildings",
    "wall_args",
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
    and simplified within 1 micrometre, so collinear vertices go): each connected group of
    touching footprints is one union; the result is in an order of its own (by position),
    whatever the order of ``items``."""
    import shapely
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    if not items:
        return []
    polys = shapely.set_precision(np.asarray([f.polygon for f in items], dtype=object), 1e-3)
    keys = [(f.height_m, f.min_height_m, f.wall_top_m, f.material, f.guessed) for f in items]
    a, b = shapely.STRtree(polys).query(polys, predicate="intersects")
    same = np.fromiter((keys[i] == keys[j] for i, j in zip(a, b, strict=True)), bool, a.size)
    graph = coo_matrix((np.ones(same.sum()), (a[same], b[same])), shape=(len(items),) * 2)
    _, label = connected_components(graph, directed=False)
    order = np.argsort(label, kind="stable")
    starts = np.flatnonzero(np.r_[True, np.diff(label[order]) != 0])
    out = []
    for group in np.split(order, starts[1:]):
        merged = polys[group[0]] if group.size == 1 else shapely.union_all(polys[group])
        for p in shapely.get_parts(merged):
            # Simplified, and free of the snapping grid (later operations in full precision).
            p = shapely.set_precision(shapely.simplify(p, 1e-6), 0.0)
            if isinstance(p, shapely.Polygon) and p.area > 0:
                f = items[group[0]]
                p = shapely.geometry.polygon.orient(p, 1.0)
                out.append(Footprint(p, f.height_m, f.min_height_m, f.wall_top_m, f.material,
                                     f.guessed))  # fmt: skip
    out.sort(key=lambda f: (f.polygon.bounds, f.polygon.area, f.height_m))
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
    """Every exposed wall (module docstring), as ``[ax, ay, bx, by, base, top]`` rows: each
    footprint edge, split where neighbours stand against it (there its bottom rises to the
    tallest neighbour's roof; a piece is gone where that reaches the eaves)."""
    import shapely

    if not items:
        return np.zeros((0, 6)), ()
    polys = np.asarray([f.polygon for f in items], dtype=object)
    # Every edge: (E, 2, 2) ends, its building.
    ends, owner = [], []
    for k, f in enumerate(items):
        for r in (f.polygon.exterior, *f.polygon.interiors):
            c = np.asarray(r.coords)[:, :2]
            ends.append(np.stack([c[:-1], c[1:]], axis=1))
            owner.append(np.full(len(c) - 1, k))
    e_all, own = np.concatenate(ends), np.concatenate(owner)
    base = np.array([f.min_height_m for f in items])[own]
    eaves = np.array([f.eaves_m for f in items])[own]
    # Each edge against each neighbouring footprint: the stretch of the edge it covers.
    a, b = shapely.STRtree(polys).query(polys, predicate="intersects")
    a, b = a[a != b], b[a != b]
    first = np.searchsorted(own, np.arange(len(items)))
    count = np.bincount(own, minlength=len(items))
    edge_of = np.concatenate([np.arange(first[k], first[k] + count[k]) for k in a] or [[]])
    edge_of = edge_of.astype(int)
    nbr = np.repeat(b, count[a])
    blocks = shapely.buffer(polys, 1e-3)
    parts, idx = shapely.get_parts(
        shapely.intersection(shapely.linestrings(e_all[edge_of]), blocks[nbr]), return_index=True
    )
    keep = (shapely.get_type_id(parts) == 1) & (shapely.length(parts) > 1e-3)
    parts, idx = parts[keep], idx[keep]
    d = e_all[:, 1] - e_all[:, 0]
    length2 = np.einsum("ij,ij->i", d, d)
    covers: dict[int, list[tuple[float, float, float]]] = {}
    for p0, p1, e, top in zip(
        shapely.get_coordinates(shapely.get_point(parts, 0)),
        shapely.get_coordinates(shapely.get_point(parts, -1)),
        edge_of[idx],
        np.array([f.height_m for f in items])[nbr[idx]],
        strict=True,
    ):
        s0, s1 = (np.array([p0, p1]) - e_all[e, 0]) @ d[e] / length2[e]
        covers.setdefault(int(e), []).append((min(s0, s1), max(s0, s1), float(top)))
    rows = [np.column_stack([e_all.reshape(-1, 4), base, eaves])]
    extra: list[str] = []
    drop = np.zeros(len(e_all), bool)
    for e, spans in covers.items():
        drop[e] = True
        cuts = np.unique(np.clip([0.0, 1.0, *(v for s in spans for v in s[:2])], 0.0, 1.0))
        pieces: list[list[float]] = []
        for lo, hi in itertools.pairwise(cuts):
            mid = 0.5 * (lo + hi)
            bottom = max([base[e], *(t for s0, s1, t in spans if s0 <= mid <= s1)])
            if bottom >= eaves[e] or hi - lo < 1e-9:
                continue
            if pieces and pieces[-1][1] == lo and pieces[-1][2] == bottom:
                pieces[-1][1] = hi
            else:
                pieces.append([lo, hi, bottom])
        for lo, hi, bottom in pieces:
            pa, pb = e_all[e, 0] + lo * d[e], e_all[e, 0] + hi * d[e]
            rows.append(np.array([[*pa, *pb, bottom, eaves[e]]]))
            extra.append(items[own[e]].material)
    out = np.concatenate([rows[0][~drop], *rows[1:]])
    return out, (*(items[k].material for k in own[~drop]), *extra)


def _build(scn: Scenario) -> Buildings:
    """The buildings of ``scn``, read and merged, their walls found."""
    import shapely

    items = [
        Footprint(shapely.box(b.x0_m, b.y0_m, b.x1_m, b.y1_m), b.height_m) for b in scn.buildings
    ]
    summary = ""
    if scn.footprints is not None and scn.georef is not None:
        fp = read_footprints(
            scn.footprints.file, scn.georef, scn.area.bounds, scn.footprints.material,
            scn.footprints.default_height_m,
        )  # fmt: skip
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


_BUILT: dict[str, Buildings] = {}
"""The last few scenarios' buildings, by what they depend on
([`scenario_buildings()`][rainuav.radio.scene.buildings.scenario_buildings])."""


def scenario_buildings(scn: Scenario) -> Buildings | None:
    """The buildings of a scenario: boxes and footprints, read once per file contents, area and
    sites.

    Args:
        scn: The scenario.

    Returns:
        The buildings, or None where it has neither.

    Raises:
        InvalidInputError: A footprints file that cannot be read (named).
    """
    if not scn.buildings and scn.footprints is None:
        return None
    import json

    from rainuav.ground import file_digest

    d = scn.to_dict()
    keep = {k: d[k] for k in ("area", "sites", "buildings", "origin", "footprints") if k in d}
    # The key: what the buildings depend on, and the footprint file's contents.
    key = json.dumps(keep, sort_keys=True)
    if scn.footprints is not None:
        try:
            key = f"{key}|{file_digest(scn.footprints.file)}"
        except OSError as err:
            raise InvalidInputError(
                f"footprints file {scn.footprints.file}: cannot be read ({err.strerror})"
            ) from err
    if key not in _BUILT:
        while len(_BUILT) >= 8:
            del _BUILT[next(iter(_BUILT))]
        _BUILT[key] = _build(scn)
    return _BUILT[key]


def wall_args(scn: Scenario) -> tuple[np.ndarray, np.ndarray]:
    """The walls and their permittivities at a scenario's frequency, as the core takes them.

    Args:
        scn: The scenario.

    Returns:
        `(walls (K, 6), permittivities (K, 2): real, imaginary)`.
    """
    b = scenario_buildings(scn)
    if b is None or b.walls.shape[0] == 0:
        return np.zeros((0, 6)), np.zeros((0, 2))
    return np.ascontiguousarray(b.walls), _permittivities(b.wall_material, scn.freq_hz)


def prism_eps(scn: Scenario) -> np.ndarray | None:
    """Each merged building's wall permittivity at a scenario's frequency, in its prisms' order.

    What the corners diffract with.

    Args:
        scn: The scenario.

    Returns:
        (P, 2): real, imaginary; None without buildings.
    """
    b = scenario_buildings(scn)
    if b is None or len(b.footprints) == 0:
        return None
    return _permittivities([f.material for f in b.footprints], scn.freq_hz)


def _permittivities(materials: Sequence[str], freq_hz: float) -> np.ndarray:
    """Each material's permittivity at ``freq_hz`` (N, 2: real, imaginary), found once a
    distinct material."""
    names, which = np.unique(np.asarray(materials, dtype=str), return_inverse=True)
    eps = np.array([material_permittivity(m, freq_hz) for m in names], dtype=complex)
    return np.ascontiguousarray(np.column_stack([eps.real, eps.imag])[which.ravel()], dtype=float)


def pixels_touched_max(
    scn: Scenario, shape: tuple[int, int] | None = None, at_least_m: float = 0.0
) -> np.ndarray:
    """The tallest building whose footprint overlaps each pixel of the area, m above the terrain.

    An overlap of positive area (footprints intersected with pixels as polygons; a pixel a footprint
    only touches along an edge or at a corner does not count). Every (footprint, pixel of its
    bounding box) pair is tested in one vectorised shapely call.

    Args:
        scn: The scenario.
        shape: The map's (H, W); None: the area's.
        at_least_m: Buildings lower than this are left out, m.

    Returns:
        (H, W), m (0 where none is).
    """
    import shapely

    a = scn.area
    h, w = a.shape if shape is None else shape
    out = np.zeros((h, w))
    b = scenario_buildings(scn)
    if b is None or not b.footprints:
        return out
    px = (a.x_max_m - a.x_min_m) / w
    py = (a.y_max_m - a.y_min_m) / h
    tall = [f for f in b.footprints if f.height_m >= at_least_m]
    if not tall:
        return out
    polys = np.asarray([f.polygon for f in tall], dtype=object)
    bounds = shapely.bounds(polys)  # (P, 4): x0, y0, x1, y1
    j0 = np.clip(np.floor((bounds[:, 0] - a.x_min_m) / px), 0, w - 1).astype(np.int64)
    j1 = np.clip(np.floor((bounds[:, 2] - a.x_min_m) / px), 0, w - 1).astype(np.int64)
    i0 = np.clip(np.floor((bounds[:, 1] - a.y_min_m) / py), 0, h - 1).astype(np.int64)
    i1 = np.clip(np.floor((bounds[:, 3] - a.y_min_m) / py), 0, h - 1).astype(np.int64)
    counts = (j1 - j0 + 1) * (i1 - i0 + 1)
    check_fits("the buildings' pixel tests", 200.0 * counts.sum() + 16.0 * h * w,
               "use a coarser map")  # fmt: skip
    owner = np.repeat(np.arange(len(counts)), counts)
    k = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
    width = (j1 - j0 + 1)[owner]
    ii, jj = i0[owner] + k // width, j0[owner] + k % width
    cells = shapely.box(a.x_min_m + jj * px, a.y_min_m + ii * py,
                        a.x_min_m + (jj + 1) * px, a.y_min_m + (ii + 1) * py)  # fmt: skip
    shapely.prepare(polys)
    # Interiors that meet: an overlap of positive area, not a shared edge or corner.
    hit = shapely.relate_pattern(polys[owner], cells, "T********")
    tops = np.array([f.height_m for f in tall])[owner]
    np.maximum.at(out, (ii[hit], jj[hit]), tops[hit])
    return out


NEAR_ROUTE_M = 100.0
"""Buildings within this distance of a flight's path count as near it (the summary's
``buildings_near_route``), m."""


def buildings_near_route(scn: Scenario, path: np.ndarray) -> dict[str, int] | None:
    """How many buildings stand near a route, and how many of those at the default height.

    Near is within [`NEAR_ROUTE_M`][rainuav.radio.scene.buildings.NEAR_ROUTE_M]; a building at the
    default height has a clearance that is a guess.

    Args:
        scn: The scenario.
        path: The route (N, 2), m.

    Returns:
        `buildings_near_route` and `buildings_near_route_at_default_height`; None without buildings.
    """
    b = scenario_buildings(scn)
    if b is None:
        return None
    import shapely

    line = shapely.LineString(path[:, :2]) if len(path) > 1 else shapely.Point(path[0, :2])
    polys = np.asarray([f.polygon for f in b.footprints], dtype=object)
    near = shapely.distance(polys, line) <= NEAR_ROUTE_M  # every building at once
    guessed = np.fromiter((f.guessed for f in b.footprints), bool, len(b.footprints))
    return {
        "buildings_near_route": int(near.sum()),
        "buildings_near_route_at_default_height": int((near & guessed).sum()),
    }


def default_height_warning(summary: dict[str, Any], default_height_m: float) -> str | None:
    """A warning line where most buildings near the route stand at the default height.

    Args:
        summary: A flight's summary (its counts of buildings near the route).
        default_height_m: The default height, m.

    Returns:
        The line, or None.
    """
    n = summary.get("buildings_near_route") or 0
    k = summary.get("buildings_near_route_at_default_height") or 0
    if n == 0 or 2 * k <= n:
        return None
    return (
        f"warning: {k} of the {n} buildings within {NEAR_ROUTE_M:g} m of the route stand at the "
        f"default height {default_height_m:g} m (their file gives no height or storeys): the "
        "clearance over them is a guess; set --default-height or add heights to the file"
    )
