"""OpenStreetMap's building tags read as the OpenStreetMap wiki defines them (Key:height,
Key:building:levels, Simple 3D Buildings), for
[`rainuav.ground.footprints`][rainuav.ground.footprints]: values as mappers write them (the first of
a list, the upper end of a range, ``~``, units, a decimal comma) and the heights of a feature (its
roof, bottom and eaves) from its tags."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

__all__ = [
    "DEFAULT_HEIGHT_M",
    "MAX_HEIGHT_M",
    "STOREY_HEIGHT_M",
    "Unreadable",
    "export_buildings",
    "feature_heights",
    "is_part",
    "parse_length",
    "parse_levels",
]

STOREY_HEIGHT_M = 3.0
"""Height of one storey (``building:levels``), m: OpenStreetMap's usual 3 m."""
DEFAULT_HEIGHT_M = 10.0
"""Roof height of a building with neither ``height`` nor ``building:levels``, m (about three
storeys)."""
MAX_HEIGHT_M = 1000.0
"""The tallest height accepted, m (the tallest building is 828 m)."""
_NUMBER = r"[0-9]*\.?[0-9]+"
_LENGTH = re.compile(rf"^(?P<v>{_NUMBER})\s*(?P<u>m|meters?|metres?|ft|feet|')?$", re.IGNORECASE)
_FEET_INCHES = re.compile(r"""^(?P<f>[0-9]+)\s*'\s*(?P<i>[0-9]+(\.[0-9]+)?)\s*"$""")
_RANGE = re.compile(rf"^{_NUMBER}\s*(?:-|\.\.|to)\s*(?P<hi>{_NUMBER}.*)$", re.IGNORECASE)


def _clean(text: Any) -> str:
    """An OpenStreetMap value as one number and its unit: the first of a ``;`` list, the
    upper end of a range (``3-4``, ``3..4``), without ``~`` (approximately), with a decimal
    comma (``12,5``) read as a point. Raises ValueError for a value that is not text or a
    number."""
    if isinstance(text, bool) or not isinstance(text, str | int | float):
        raise ValueError(repr(text))
    s = str(text).split(";")[0].strip().lstrip("~\u2248").strip()
    s = re.sub(r"(?<=[0-9]),(?=[0-9])", ".", s)
    if m := _RANGE.match(s):
        s = m["hi"]
    return s


def parse_length(text: Any) -> float:
    """A length in metres from an OpenStreetMap value.

    A number (metres), `"12 m"`, `"40 ft"`, `"40'"` or `12'6"`, read by `_clean`'s rules (`"12;15"`
    is 12, `"~20"` 20, `"12,5"` 12.5, `"10-12"` 12).

    Args:
        text: The tag's value.

    Returns:
        Metres.

    Raises:
        ValueError: Anything else (negative numbers included).
    """
    if isinstance(text, int | float) and not isinstance(text, bool):
        v = float(text)
        if not math.isfinite(v) or v < 0:
            raise ValueError(repr(text))
        return v
    s = _clean(text)
    if m := _FEET_INCHES.match(s):
        return (float(m["f"]) * 12.0 + float(m["i"])) * 0.0254
    m = _LENGTH.match(s)
    if m is None:
        raise ValueError(repr(text))
    unit = (m["u"] or "m").lower()
    return float(m["v"]) * (0.3048 if unit in ("ft", "feet", "'") else 1.0)


def parse_levels(text: Any) -> float:
    """A number of storeys from an OpenStreetMap value.

    `"3"`, `"2.5"`, `"2,5"`, `"3-4"` (the upper end), `"3;4"` (the first); 0 is a real value.

    Args:
        text: The tag's value.

    Returns:
        The storeys.

    Raises:
        ValueError: Anything else (negative numbers included).
    """
    if isinstance(text, int | float) and not isinstance(text, bool):
        v = float(text)
    else:
        s = _clean(text)
        if re.fullmatch(_NUMBER, s) is None:
            raise ValueError(repr(text))
        v = float(s)
    if not math.isfinite(v) or v < 0:
        raise ValueError(repr(text))
    return v


class Unreadable(ValueError):
    """A feature's value that cannot be read (the feature is skipped)."""


def feature_heights(
    props: dict[str, Any], default_height_m: float
) -> tuple[float, float, float | None, bool]:
    """A feature's roof, bottom and eaves by the module docstring's rules.

    Args:
        props: The feature's tags.
        default_height_m: The roof of a building with neither a height nor storeys, m.

    Returns:
        `(roof, bottom, eaves or None, whether the default height was used)`, m.

    Raises:
        Unreadable: A tag that cannot be read, or a roof not above its bottom (the tag named).
    """

    def read(key: str, parse: Any, what: str, top: float) -> float | None:
        v = props.get(key)
        if v is None or (isinstance(v, str) and not v.strip()):
            return None
        try:
            x = parse(v)
        except ValueError:
            raise Unreadable(f"{key} = {v!r} is not {what}") from None
        if x > top:
            raise Unreadable(f"{key} = {v!r} is over {top:g}")
        return x

    def length(key: str) -> float | None:
        return read(key, parse_length, f"a length in 0..{MAX_HEIGHT_M:g} m", MAX_HEIGHT_M)

    def levels(key: str) -> float | None:
        top = MAX_HEIGHT_M / STOREY_HEIGHT_M
        return read(key, parse_levels, f"a number of storeys in 0..{top:g}", top)

    roof_h = length("roof:height")
    if roof_h is None and (roof_lv := levels("roof:levels")) is not None:
        roof_h = roof_lv * STOREY_HEIGHT_M
    bottom = length("min_height")
    if bottom is None:
        ml = levels("building:min_level")
        bottom = 0.0 if ml is None else ml * STOREY_HEIGHT_M
    height = length("height")
    default = False
    if height is None:
        lv = levels("building:levels")
        if lv is not None:
            height = lv * STOREY_HEIGHT_M + (roof_h or 0.0)
        elif bottom > 0.0:  # a raised part: its own roof on its bottom
            height = bottom + (STOREY_HEIGHT_M if roof_h is None else roof_h)
            default = roof_h is None
        else:
            height, default = max(default_height_m, roof_h or 0.0), True
    if height <= bottom:
        raise Unreadable(
            f"its roof ({height:g} m) is not above its bottom (min_height {bottom:g} m)"
        )
    eaves = None if roof_h is None else max(bottom, height - roof_h)
    return height, bottom, eaves, default


def is_part(props: dict[str, Any]) -> bool:
    """Whether a feature is a Simple 3D Buildings part (`building:part` set, not `no`).

    Args:
        props: The feature's tags.

    Returns:
        True for a part.
    """
    v = props.get("building:part")
    return v not in (None, "", "no", False)


def export_buildings(pbf: str, out: str | Path) -> Path:
    """Writes the buildings and building parts of an OpenStreetMap extract as GeoJSON.

    As `osmium export` writes them (areas assembled by libosmium; every tag a property; ids `w<way>`
    / `r<relation>`), whole or not at all (a temporary file, then renamed). Needs pyosmium (the test
    extra).

    Args:
        pbf: The extract (.osm.pbf).
        out: The GeoJSON file to write.

    Returns:
        `out`.

    Raises:
        ImportError: pyosmium is not installed (named).
    """
    import json
    import os

    try:
        import osmium
    except ImportError as err:  # pragma: no cover - depends on the machine
        raise ImportError("exporting an .osm.pbf needs pyosmium: pip install osmium") from err
    factory = osmium.geom.GeoJSONFactory()
    proc = (
        osmium.FileProcessor(pbf)
        .with_areas()
        .with_filter(osmium.filter.EntityFilter(osmium.osm.AREA))
        .with_filter(osmium.filter.KeyFilter("building", "building:part"))
    )
    feats = [
        {"type": "Feature", "id": f"{'w' if a.from_way() else 'r'}{a.orig_id()}",
         "properties": dict(a.tags), "geometry": json.loads(factory.create_multipolygon(a))}
        for a in proc
    ]  # fmt: skip
    out = Path(out)
    tmp = out.with_suffix(f".{os.getpid()}.tmp")
    tmp.write_text(json.dumps({"type": "FeatureCollection", "features": feats}))
    tmp.replace(out)
    return out
