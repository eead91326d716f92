"""Building footprints from the files cities publish (``shared/PHYSICS.md`` section 12): GeoJSON
(RFC 7946: longitude/latitude on WGS 84) Polygon and MultiPolygon features, holes included,
read with shapely onto a scenario's local east/north metres.

**Heights, by OpenStreetMap's conventions.** A feature's roof is ``height`` (metres; also
``"12 m"``, ``"40 ft"``, ``"40'"``), else ``building:levels`` times :data:`STOREY_HEIGHT_M`
plus ``roof:height``, else :data:`DEFAULT_HEIGHT_M`. The walls end ``roof:height`` below the
roof (a pitched roof's eaves). The prism starts at ``min_height`` (else ``building:min_level``
times the storey height; default 0: on the ground). Heights are above the terrain under the
building. The wall material is ``building:material`` where it names one of ITU-R P.2040's
materials (:data:`MATERIALS`; OpenStreetMap's synonyms in :data:`OSM_MATERIALS`), else the
default (concrete).

**What is kept.** Features wholly outside the area are skipped and counted; features across
its edge are clipped to it. Geometries that are not polygons are skipped and counted.
Self-intersecting polygons are repaired with shapely's ``make_valid`` (its polygonal parts
kept) and counted. Everything else that is wrong (not JSON, not a FeatureCollection, a ``crs``
other than WGS 84, coordinates off the Earth, a height that is negative, over 1000 m or not a
length, a ``min_height`` at or above the roof, more than :data:`MAX_FEATURES` features) is an
:class:`~rainuav.errors.InvalidInputError` naming the file and the feature.
"""

from __future__ import annotations

import json
import math
import os
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rainuav._checks import check_fits
from rainuav.errors import InvalidInputError
from rainuav.geo import Georef

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
    "read_footprints",
]

STOREY_HEIGHT_M = 3.0
"""Height of one storey (``building:levels``), m: OpenStreetMap's usual 3 m."""
DEFAULT_HEIGHT_M = 10.0
"""Roof height of a building with neither ``height`` nor ``building:levels``, m (about three
storeys)."""
MAX_HEIGHT_M = 1000.0
"""The tallest height accepted, m (the tallest building is 828 m)."""
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
"""OpenStreetMap ``building:material`` values read as one of :data:`MATERIALS`."""

_EPS0 = 8.8541878128e-12
_LENGTH = re.compile(
    r"^\s*(?P<v>[0-9]*\.?[0-9]+)\s*(?P<u>m|meters?|metres?|ft|feet|')?\s*$", re.IGNORECASE
)
_FEET_INCHES = re.compile(r"""^\s*(?P<f>[0-9]+)\s*'\s*(?P<i>[0-9]+(\.[0-9]+)?)\s*"\s*$""")


def material_permittivity(material: str, freq_hz: float) -> complex:
    """The complex relative permittivity ``eps_r - j sigma / (omega eps_0)`` of a P.2040
    material at ``freq_hz``."""
    a, b, c, d = MATERIALS[material]
    f_ghz = freq_hz / 1e9
    sigma = c * f_ghz**d
    return complex(a * f_ghz**b, -sigma / (2.0 * math.pi * freq_hz * _EPS0))


def parse_length(text: Any) -> float:
    """A length in metres from an OpenStreetMap value: a number (metres), ``"12 m"``,
    ``"40 ft"``, ``"40'"`` or ``12'6"``. Raises ValueError for anything else (negative numbers
    included)."""
    if isinstance(text, bool):
        raise ValueError(repr(text))
    if isinstance(text, int | float):
        v = float(text)
        if not math.isfinite(v) or v < 0:
            raise ValueError(repr(text))
        return v
    s = str(text)
    if m := _FEET_INCHES.match(s):
        return (float(m["f"]) * 12.0 + float(m["i"])) * 0.0254
    m = _LENGTH.match(s.replace(",", "."))
    if m is None:
        raise ValueError(repr(text))
    unit = (m["u"] or "m").lower()
    return float(m["v"]) * (0.3048 if unit in ("ft", "feet", "'") else 1.0)


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
    outside: int = 0
    """Features wholly outside the area (skipped)."""
    not_polygons: int = 0
    """Features that are not polygons (skipped)."""
    clipped: int = 0
    """Features cut at the area's edge."""
    repaired: int = 0
    """Self-intersecting polygons repaired with shapely's make_valid."""
    default_height: int = 0
    """Buildings given :data:`DEFAULT_HEIGHT_M` (no height, no levels)."""
    default_material: int = 0
    """Buildings whose material tag named no P.2040 material (the default used)."""

    def summary(self) -> str:
        """One line: what was read and what was left out."""
        return (
            f"footprints {self.path}: {len(self.buildings)} buildings from {self.features} "
            f"features ({self.outside} outside the area, {self.not_polygons} not polygons, "
            f"{self.clipped} clipped, {self.repaired} repaired, {self.default_height} at the "
            f"default height {DEFAULT_HEIGHT_M:g} m)"
        )


def _crs_ok(crs: Any) -> bool:
    if crs is None:
        return True
    try:
        name = str(crs["properties"]["name"]).upper()
    except (TypeError, KeyError):
        return False
    return name.endswith("CRS84") or name.replace("::", ":").endswith("EPSG:4326")


def _heights(props: dict[str, Any], where: str) -> tuple[float, float, float | None, bool]:
    """(roof, bottom, eaves or None, whether the default height was used) of a feature."""

    def length(key: str) -> float | None:
        if props.get(key) in (None, ""):
            return None
        try:
            v = parse_length(props[key])
        except ValueError:
            raise InvalidInputError(
                f"{where}: {key} = {props[key]!r} is not a length in 0..{MAX_HEIGHT_M:g} m "
                "(e.g. 12, '12 m', '40 ft')"
            ) from None
        if v > MAX_HEIGHT_M:
            raise InvalidInputError(f"{where}: {key} = {props[key]!r} is over {MAX_HEIGHT_M:g} m")
        return v

    def levels(key: str) -> float | None:
        if props.get(key) in (None, ""):
            return None
        try:
            v = float(str(props[key]).strip())
        except ValueError:
            v = -1.0
        if not (0 <= v <= MAX_HEIGHT_M / STOREY_HEIGHT_M):
            raise InvalidInputError(
                f"{where}: {key} = {props[key]!r} is not a number of storeys in "
                f"0..{MAX_HEIGHT_M / STOREY_HEIGHT_M:g}"
            )
        return v

    roof_h = length("roof:height")
    height = length("height")
    default = False
    if height is None:
        lv = levels("building:levels")
        if lv is None:
            height, default = DEFAULT_HEIGHT_M, True
        else:
            height = lv * STOREY_HEIGHT_M + (roof_h or 0.0)
    bottom = length("min_height")
    if bottom is None:
        ml = levels("building:min_level")
        bottom = 0.0 if ml is None else ml * STOREY_HEIGHT_M
    if height <= 0.0:
        raise InvalidInputError(f"{where}: height must be above 0 m (got {height:g})")
    if bottom >= height:
        raise InvalidInputError(
            f"{where}: min_height {bottom:g} m must be below the roof ({height:g} m)"
        )
    eaves = None if roof_h is None else max(bottom, height - roof_h)
    return height, bottom, eaves, default


def read_footprints(
    path: str | os.PathLike[str],
    georef: Georef,
    bounds: tuple[float, float, float, float],
    default_material: str = "concrete",
) -> Footprints:
    """The buildings of the GeoJSON file ``path`` within ``bounds`` (x_min, x_max, y_min,
    y_max in the local metres of ``georef``): module docstring."""
    import shapely

    path = os.fspath(path)
    what = f"footprints file {path}"
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
    out = Footprints(path=path, features=len(feats))
    area = shapely.box(bounds[0], bounds[2], bounds[1], bounds[3])
    geoms, attrs = [], []
    for k, feat in enumerate(feats):
        fid = feat.get("id") if isinstance(feat, dict) else None
        where = f"{what}: feature {k}" + (f" (id {fid})" if fid is not None else "")
        geom = feat.get("geometry") if isinstance(feat, dict) else None
        if not isinstance(geom, dict) or geom.get("type") not in ("Polygon", "MultiPolygon"):
            out.not_polygons += 1
            continue
        try:
            shape = shapely.geometry.shape(geom)
        except (ValueError, TypeError, AttributeError, shapely.errors.ShapelyError) as err:
            raise InvalidInputError(f"{where}: not a valid {geom['type']} ({err})") from None
        coords = shapely.get_coordinates(shape)
        if coords.size == 0:
            out.not_polygons += 1
            continue
        if not (
            np.all(np.isfinite(coords))
            and np.all(np.abs(coords[:, 0]) <= 180)
            and np.all(np.abs(coords[:, 1]) <= 90)
        ):
            raise InvalidInputError(
                f"{where}: coordinates must be longitude -180..180, latitude -90..90"
            )
        props = feat.get("properties") or {}
        if not isinstance(props, dict):
            raise InvalidInputError(f"{where}: properties must be an object")
        height, bottom, eaves, default = _heights(props, where)
        tag = str(props.get("building:material", "")).strip().lower()
        material = OSM_MATERIALS.get(tag, tag)
        if material not in MATERIALS:
            out.default_material += bool(tag)
            material = default_material
        out.default_height += default
        geoms.append(shape)
        attrs.append((height, bottom, eaves, material))
    if not geoms:
        return out
    # Longitude/latitude to the scenario's metres, every vertex at once.
    local = shapely.transform(
        np.asarray(geoms, dtype=object),
        lambda xy: np.column_stack(georef.to_local(xy[:, 1], xy[:, 0], name=what)),
    )
    valid = shapely.is_valid(local)
    for g, ok, (height, bottom, eaves, material) in zip(local, valid, attrs, strict=True):
        if not ok:
            g = shapely.make_valid(g)
            out.repaired += 1
        if not shapely.intersects(g, area):
            out.outside += 1
            continue
        if not shapely.within(g, area):
            g = shapely.intersection(g, area)
            out.clipped += 1
        for part in shapely.get_parts(g):
            if isinstance(part, shapely.Polygon) and part.area > 0:
                out.buildings.append(Footprint(part, height, bottom, eaves, material))
            elif isinstance(part, shapely.GeometryCollection | shapely.MultiPolygon):
                for p in shapely.get_parts(part):
                    if isinstance(p, shapely.Polygon) and p.area > 0:
                        out.buildings.append(Footprint(p, height, bottom, eaves, material))
    return out
