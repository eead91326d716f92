"""Building footprints from the files cities publish and OpenStreetMap exports (the physics
reference's buildings page): GeoJSON (RFC 7946: longitude/latitude on WGS 84) Polygon,
MultiPolygon and GeometryCollection features, holes included, read with shapely onto a
scenario's local east/north metres. An OpenStreetMap extract exported with
``osmium export -f geojson`` or ``ogr2ogr`` reads as it is.

**Heights, as OpenStreetMap's wiki defines them** (Key:height, Key:building:levels and Simple 3D
Buildings). A feature's roof is ``height`` (metres), else ``building:levels`` storeys of
[`STOREY_HEIGHT_M`][rainuav.ground.footprints.STOREY_HEIGHT_M] plus its roof (``roof:height``, else
``roof:levels`` storeys; ``building:levels=0`` is a real value: no storey below the roof). With
neither, a feature raised off the ground (``min_height`` > 0: a part standing on another, such as a
dome) has its roof at ``min_height`` plus its ``roof:height`` (else plus one storey); one on the
ground stands at the default height
([`DEFAULT_HEIGHT_M`][rainuav.ground.footprints.DEFAULT_HEIGHT_M], ``[footprints]
default_height_m``, counted: its clearance is a guess). The walls end ``roof:height`` below the roof
(a pitched roof's eaves). The prism starts at ``min_height`` (else ``building:min_level`` storeys;
default 0: on the ground). Heights are above the terrain under the building.

**Values as mappers write them** ([`parse_length()`][rainuav.ground.footprints.parse_length],
[`parse_levels()`][rainuav.ground.footprints.parse_levels]): the first of a
list (``12;15``), the upper end of a range (``3-4``), an approximate value (``~20``), a unit
(``20 m``, ``40 ft``, ``40'``, ``12'6"``) and a decimal comma (``12,5``: one rule for lengths
and storeys).

**Outlines and parts.** Where a building's outline (``building=*``) and its Simple 3D Buildings
parts (``building:part=*``) overlap, the parts give the shape: the outline is kept only where it has
no parts (counted in
[`Footprints.outlines_cut`][rainuav.ground.footprints.Footprints.outlines_cut]).

**What is kept.** Features wholly outside the area are skipped and counted, and so is a feature no
value of which can be read (a height that is not a length, negative or over
[`MAX_HEIGHT_M`][rainuav.ground.footprints.MAX_HEIGHT_M], a bottom at or above its roof, coordinates
off the Earth, a geometry shapely cannot build):
[`Footprints.skipped`][rainuav.ground.footprints.Footprints.skipped] names each, and the summary the
first few. Features across the area's edge are clipped to it. Geometries with no polygon are skipped
and counted. Self-intersecting polygons are repaired with shapely's ``make_valid`` (its polygonal
parts kept) and counted. The material is ``building:material`` where it names one of ITU-R P.2040's
materials ([`MATERIALS`][rainuav.ground.footprints.MATERIALS]; OpenStreetMap's synonyms in
[`OSM_MATERIALS`][rainuav.ground.footprints.OSM_MATERIALS]), else the default (concrete).

**What is refused** (an [`InvalidInputError`][rainuav.errors.InvalidInputError] naming the file): a
file that is not JSON, not a FeatureCollection, in a ``crs`` other than WGS 84, with more than
[`MAX_FEATURES`][rainuav.ground.footprints.MAX_FEATURES] features; a file that yields no building
(naming the first feature skipped and why), and one whose every feature lies outside the area
(naming both extents: latitude and longitude swapped, or another city). One unreadable feature never
refuses a file that has buildings."""

from __future__ import annotations

import json
import math
import os
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rainuav._checks import check_fits
from rainuav.errors import InvalidInputError
from rainuav.geo import Georef
from rainuav.ground.osm import (
    DEFAULT_HEIGHT_M,
    MAX_HEIGHT_M,
    STOREY_HEIGHT_M,
    Unreadable,
    feature_heights,
    is_part,
    parse_length,
    parse_levels,
)

__all__ = [
    "DEFAULT_HEIGHT_M",
    "MATERIALS",
    "MAX_FEATURES",
    "MAX_HEIGHT_M",
    "OSM_MATERIALS",
    "STOREY_HEIGHT_M",
    "Footprint",
    "Footprints",
    "material_permittivity",
    "parse_length",
    "parse_levels",
    "read_footprints",
]

MAX_FEATURES = 500_000
"""The most features a file may hold (a city of a few million people has about this many
buildings; larger files are cut to the area first, e.g. with ``ogr2ogr -clipsrc``)."""

MATERIALS: dict[str, tuple[float, float, float, float]] = {
    "concrete": (5.24, 0.0, 0.0462, 0.7822),
    "brick": (3.91, 0.0, 0.0238, 0.16),
    "plasterboard": (2.73, 0.0, 0.0085, 0.9395),
    "wood": (1.99, 0.0, 0.0047, 1.0718),
    "glass": (6.31, 0.0, 0.0036, 1.3394),
    "chipboard": (2.58, 0.0, 0.0217, 0.78),
    "plywood": (2.71, 0.0, 0.33, 0.0),
    "marble": (7.074, 0.0, 0.0055, 0.9262),
    "metal": (1.0, 0.0, 1e7, 0.0),
}
"""ITU-R P.2040 Table 3: ``eps_r = a f^b``, ``sigma = c f^d`` S/m, f in GHz (fitted over 1-100
GHz; brick and plywood to 40 GHz, marble to 60 GHz, and held as they are beyond)."""

OSM_MATERIALS: dict[str, str] = {
    "reinforced_concrete": "concrete",
    "cement_block": "concrete",
    "steel": "metal",
    "aluminium": "metal",
    "metal_plates": "metal",
    "mirrored_glass": "glass",
    "timber_framing": "wood",
    "plaster": "plasterboard",
}
"""OpenStreetMap ``building:material`` values read as one of
[`MATERIALS`][rainuav.ground.footprints.MATERIALS]."""

_EPS0 = 8.8541878128e-12
MAX_NAMED = 3
"""The skipped features a summary names (the rest are counted)."""


def material_permittivity(material: str, freq_hz: float) -> complex:
    """The complex relative permittivity `eps_r - j sigma / (omega eps_0)` of a P.2040 material.

    Args:
        material: The material's name (P.2040 Table 3).
        freq_hz: The frequency, Hz.

    Returns:
        The permittivity.
    """
    a, b, c, d = MATERIALS[material]
    f_ghz = freq_hz / 1e9
    sigma = c * f_ghz**d
    return complex(a * f_ghz**b, -sigma / (2.0 * math.pi * freq_hz * _EPS0))


@dataclass(frozen=True)
class Footprint:
    """One building: its footprint in local metres and its heights above the terrain."""

    polygon: Any
    """A shapely Polygon (east, north metres)."""
    height_m: float
    """Roof, m."""
    min_height_m: float = 0.0
    """Bottom of the prism, m."""
    wall_top_m: float | None = None
    """Where the walls end (the eaves), m; None: the roof."""
    material: str = "concrete"
    """The walls' P.2040 material."""
    guessed: bool = False
    """Whether the roof is the default height (the file gave no height and no storeys)."""

    @property
    def eaves_m(self) -> float:
        """Top of the walls, m."""
        return self.height_m if self.wall_top_m is None else self.wall_top_m


@dataclass
class Footprints:
    """The buildings of a footprint file within an area, and what was left out."""

    path: str
    """The file."""
    buildings: list[Footprint] = field(default_factory=list)
    """The buildings within the area (clipped to it)."""
    features: int = 0
    """Features in the file."""
    read: int = 0
    """Features read within the area (an outline wholly covered by its parts among them)."""
    outside: int = 0
    """Features wholly outside the area (skipped)."""
    not_polygons: int = 0
    """Features with no polygon (skipped)."""
    clipped: int = 0
    """Features cut at the area's edge."""
    repaired: int = 0
    """Self-intersecting polygons repaired with shapely's make_valid."""
    outlines_cut: int = 0
    """Building outlines replaced by their Simple 3D Buildings parts (wholly or in part)."""
    default_height: int = 0
    """Buildings kept at the default height (no height, no storeys)."""
    default_height_m: float = DEFAULT_HEIGHT_M
    """That default, m."""
    default_material: int = 0
    """Buildings whose material tag named no P.2040 material (the default used)."""
    skipped: list[str] = field(default_factory=list)
    """Each feature skipped because a value could not be read: where it is and why."""

    def summary(self) -> str:
        """What was read and what was left out, in one line (the first few skipped features named).

        Returns:
            The line.
        """
        line = (
            f"footprints {self.path}: {len(self.buildings)} buildings from {self.features} "
            f"features ({self.outside} outside the area, {self.not_polygons} not polygons, "
            f"{len(self.skipped)} unreadable, {self.clipped} clipped, {self.repaired} repaired, "
            f"{self.outlines_cut} outlines replaced by their parts; {self.default_height} of the "
            f"buildings kept at the default height {self.default_height_m:g} m)"
        )
        if self.skipped:
            more = len(self.skipped) - MAX_NAMED
            named = "; ".join(self.skipped[:MAX_NAMED]) + (f"; {more} more" if more > 0 else "")
            line += f"; skipped: {named}"
        return line


def _crs_ok(crs: Any) -> bool:
    if crs is None:
        return True
    try:
        name = str(crs["properties"]["name"]).upper()
    except (TypeError, KeyError):
        return False
    return name.endswith("CRS84") or name.replace("::", ":").endswith("EPSG:4326")


# Long: one pass over a GeoJSON file in stages (parse, project every vertex at once, heights,
# outlines and their parts, repairs), each reading the arrays of the ones before and adding to
# the counts the summary line reports.
def read_footprints(
    path: str | os.PathLike[str],
    georef: Georef,
    bounds: tuple[float, float, float, float],
    default_material: str = "concrete",
    default_height_m: float = DEFAULT_HEIGHT_M,
) -> Footprints:
    """The buildings of a GeoJSON file within an area (the module's docstring has the rules).

    Args:
        path: The file (longitude/latitude, WGS 84).
        georef: The scenario's local frame.
        bounds: The area, `(x_min, x_max, y_min, y_max)` in the local metres.
        default_material: The walls' material where a footprint names none.
        default_height_m: The roof of a building on the ground with neither a height nor storeys, m.

    Returns:
        The [`Footprints`][rainuav.ground.footprints.Footprints].

    Raises:
        InvalidInputError: A file that cannot be read, is not a GeoJSON FeatureCollection in WGS 84,
            is nested too deeply or holds too many features, or a default out of range (the file
            named).
    """
    import shapely

    path = os.fspath(path)
    what = f"footprints file {path}"
    if not (isinstance(default_height_m, int | float) and 0.5 <= default_height_m <= MAX_HEIGHT_M):
        raise InvalidInputError(
            f"footprints.default_height_m {default_height_m!r} must be in 0.5..{MAX_HEIGHT_M:g} m"
        )
    try:
        size = os.path.getsize(path)
    except OSError as err:
        raise InvalidInputError(f"{what}: cannot be read ({err.strerror})") from err
    # json's objects take about 20 times the text, shapely's geometries less.
    check_fits(what, 20.0 * size, "cut the file to the area first (ogr2ogr -clipsrc)")
    try:
        with open(path, encoding="utf-8") as f:
            data = json.load(f)
    except (UnicodeDecodeError, json.JSONDecodeError) as err:
        raise InvalidInputError(f"{what}: not JSON ({err})") from None
    except RecursionError:  # nested deeper than any footprint file
        raise InvalidInputError(f"{what}: nested too deeply to be GeoJSON footprints") from None
    except OSError as err:
        raise InvalidInputError(f"{what}: cannot be read ({err.strerror})") from err
    if not isinstance(data, dict) or data.get("type") not in ("FeatureCollection", "Feature"):
        raise InvalidInputError(f"{what}: must be a GeoJSON FeatureCollection")
    if not _crs_ok(data.get("crs")):
        raise InvalidInputError(
            f"{what}: crs {data.get('crs')!r} is not WGS 84 longitude/latitude "
            "(RFC 7946 has no crs member: reproject to EPSG:4326, e.g. with ogr2ogr -t_srs)"
        )
    feats = [data] if data["type"] == "Feature" else data.get("features")
    if not isinstance(feats, list):
        raise InvalidInputError(f"{what}: 'features' must be a list")
    if len(feats) > MAX_FEATURES:
        raise InvalidInputError(
            f"{what}: {len(feats)} features, more than {MAX_FEATURES}; cut the file to the "
            "area first (ogr2ogr -clipsrc)"
        )
    if default_material not in MATERIALS:
        raise InvalidInputError(
            f"footprints.material {default_material!r} must be one of {sorted(MATERIALS)}"
        )
    out = Footprints(path=path, features=len(feats), default_height_m=float(default_height_m))
    area = shapely.box(bounds[0], bounds[2], bounds[1], bounds[3])
    geoms, where, props_of = [], [], []
    for k, feat in enumerate(feats):
        fid = feat.get("id") if isinstance(feat, dict) else None
        if fid is None and isinstance(feat, dict) and isinstance(feat.get("properties"), dict):
            fid = feat["properties"].get("@id") or feat["properties"].get("osm_id")
        here = f"feature {k}" + (f" (id {fid})" if fid is not None else "")
        geom = feat.get("geometry") if isinstance(feat, dict) else None
        kinds = ("Polygon", "MultiPolygon", "GeometryCollection")
        if not isinstance(geom, dict) or geom.get("type") not in kinds:
            out.not_polygons += 1
            continue
        try:
            with warnings.catch_warnings():  # NaN vertices: refused below, in one line
                warnings.simplefilter("ignore", RuntimeWarning)
                shape = shapely.geometry.shape(geom)
        except (ValueError, TypeError, AttributeError, KeyError, IndexError,
                shapely.errors.ShapelyError) as err:  # fmt: skip
            out.skipped.append(f"{here}: not a valid {geom['type']} ({err})")
            continue
        if isinstance(shape, shapely.GeometryCollection):  # it keeps its polygons
            polys = _polygons(shape)
            if not polys:
                out.not_polygons += 1
                continue
            shape = polys[0] if len(polys) == 1 else shapely.MultiPolygon(polys)
        elif shape.is_empty:
            out.not_polygons += 1
            continue
        coords = shapely.get_coordinates(shape)
        if not (
            np.all(np.isfinite(coords))
            and np.all(np.abs(coords[:, 0]) <= 180)
            and np.all(np.abs(coords[:, 1]) <= 90)
        ):
            out.skipped.append(f"{here}: coordinates must be longitude -180..180, latitude -90..90")
            continue
        props = feat.get("properties") or {}
        if not isinstance(props, dict):
            out.skipped.append(f"{here}: properties must be an object")
            continue
        geoms.append(shape)
        where.append(here)
        props_of.append(props)
    if geoms:
        # Longitude/latitude to the scenario's metres, every vertex at once.
        local = shapely.transform(
            np.asarray(geoms, dtype=object),
            lambda xy: np.column_stack(georef.to_local(xy[:, 1], xy[:, 0], name=what)),
        )
    else:
        local = np.zeros(0, dtype=object)
    kept: list[tuple[Any, str, dict[str, Any]]] = []  # (area-clipped geometry, where, tags)
    valid = shapely.is_valid(local)
    for g, ok, here, props in zip(local, valid, where, props_of, strict=True):
        if not ok:
            g = shapely.make_valid(g)
            out.repaired += 1
        if not shapely.intersects(g, area):
            out.outside += 1
            continue
        if not shapely.within(g, area):
            g = shapely.intersection(g, area)
            out.clipped += 1
        kept.append((g, here, props))
    # Heights first: a part that cannot be read does not cut its outline.
    readable = []
    for g, here, props in kept:
        try:
            readable.append((g, props, feature_heights(props, default_height_m)))
        except Unreadable as err:
            out.skipped.append(f"{here}: {err}")
    # Outlines and parts: the parts give the shape where they overlap an outline.
    parts = [g for g, props, _ in readable if is_part(props)]
    parts_union = shapely.union_all(parts) if parts else None
    for g, props, (height, bottom, eaves, default) in readable:
        if parts_union is not None and not is_part(props) and shapely.intersects(g, parts_union):
            rest = shapely.difference(g, parts_union)
            if shapely.area(rest) < shapely.area(g) - 1e-6:
                out.outlines_cut += 1
                g = rest
        tag = str(props.get("building:material", "")).strip().lower()
        material = OSM_MATERIALS.get(tag, tag)
        if material not in MATERIALS:
            out.default_material += bool(tag)
            material = default_material
        n = len(out.buildings)
        for part in _polygons(g):
            if part.area > 1e-6:
                out.buildings.append(
                    Footprint(part, height, bottom, eaves, material, guessed=default)
                )
        out.read += 1
        out.default_height += default and len(out.buildings) > n
    if not out.buildings:
        _refuse_empty(out, what, local, area, georef, bounds)
    return out


def _polygons(g: Any) -> list[Any]:
    """The polygons of a geometry (a collection's polygonal parts, at any depth)."""
    import shapely

    if isinstance(g, shapely.Polygon):
        return [g]
    if isinstance(g, shapely.MultiPolygon | shapely.GeometryCollection):
        return [p for part in shapely.get_parts(g) for p in _polygons(part)]
    return []


def _refuse_empty(
    out: Footprints, what: str, local: Any, area: Any, georef: Georef, bounds: Any
) -> None:
    """Refuses a file that yields no building, in one line that says why."""
    import shapely

    if out.outside and out.outside == len(local):
        lat, lon = georef.to_latlon(np.array(bounds[:2]), np.array(bounds[2:]))
        x0, y0, x1, y1 = shapely.total_bounds(np.asarray(local, dtype=object))
        flat, flon = georef.to_latlon(np.array([x0, x1]), np.array([y0, y1]))
        raise InvalidInputError(
            f"{what}: all {out.outside} features lie outside the area (latitude "
            f"{lat.min():.4f}..{lat.max():.4f}, longitude {lon.min():.4f}..{lon.max():.4f}); "
            f"the file's features span latitude {flat.min():.4f}..{flat.max():.4f}, longitude "
            f"{flon.min():.4f}..{flon.max():.4f}: another place, or latitude and longitude "
            "swapped?"
        )
    if out.skipped:
        raise InvalidInputError(
            f"{what}: no building could be read ({len(out.skipped)} features skipped; "
            f"{out.skipped[0]})"
        )
    raise InvalidInputError(
        f"{what}: no building footprints in the area ({out.features} features, "
        f"{out.not_polygons} not polygons, {out.outside} outside the area)"
    )
