"""Base stations from a file, in latitude and longitude: one row per sector, as an
operator's site list has them, into the scenario's [`Site`][rainuav.radio.scene.scenario.Site]\\ s.

CSV (a header row, then one sector per row) or GeoJSON (a ``FeatureCollection`` of ``Point``
features whose properties are the same fields; the point gives ``lat`` and ``lon``):

- ``site_id``: sectors with the same id are one mast (their position and height must agree);
- ``lat``, ``lon``: degrees, WGS 84; ``height_m``: the antenna above the ground, m (1-300);
- ``azimuth_deg``: the boresight, **degrees clockwise from north**, as operators and compasses
  give it (rainuav's own ``Cell.azimuth_deg`` is counter-clockwise from east: converted);
- ``electrical_tilt_deg``: **downtilt, degrees, positive down**, as operators give it
  (``Cell.electrical_tilt_deg`` is positive up: negated); ``tx_power_dbm``;
- optional: ``antenna`` (``array``, the TR 38.901 sector column, by default; or ``tr38901``,
  ``gaussian``), ``rows`` (8), ``mechanical_tilt_deg`` (downtilt, positive down, 0) and
  ``freq_ghz`` (every row that gives it must give the same: one carrier per scenario).

A bad row is refused in one line naming the file, the row (CSV: its line number; GeoJSON: the
feature's index) and the column, with the allowed range.
"""

from __future__ import annotations

import csv
import json
import math
import os
from pathlib import Path
from typing import Any

from rainuav.errors import InvalidInputError
from rainuav.geo import Georef
from rainuav.radio.scene.cell import Cell
from rainuav.radio.scene.scenario import Site

__all__ = ["REQUIRED", "SiteRow", "cell_names", "read_site_rows", "sites_from_rows"]

REQUIRED = ("site_id", "lat", "lon", "height_m", "azimuth_deg", "electrical_tilt_deg",
            "tx_power_dbm")  # fmt: skip
OPTIONAL = ("antenna", "rows", "mechanical_tilt_deg", "freq_ghz")
RANGES: dict[str, tuple[float, float]] = {
    "lat": (-90.0, 90.0),
    "lon": (-180.0, 180.0),
    "height_m": (1.0, 300.0),
    "azimuth_deg": (-360.0, 360.0),
    "electrical_tilt_deg": (-30.0, 30.0),
    "mechanical_tilt_deg": (-30.0, 30.0),
    "tx_power_dbm": (0.0, 70.0),
    "rows": (1.0, 64.0),
    "freq_ghz": (1.0, 100.0),
}
ANTENNAS = ("array", "tr38901", "gaussian")
SiteRow = dict[str, Any]


def _field(where: str, name: str, raw: Any) -> Any:
    """One field of a row, checked: a number within [`RANGES`][rainuav.radio.scene.sites.RANGES], an
    integer for ``rows``, an antenna name, or an id."""
    if name == "site_id":
        text = str(raw).strip() if raw is not None else ""
        if not text:
            raise InvalidInputError(f"{where}: column site_id is empty")
        return text
    if name == "antenna":
        text = str(raw).strip()
        if text not in ANTENNAS:
            raise InvalidInputError(f"{where}: column antenna must be one of {ANTENNAS}")
        return text
    try:
        v = float(raw)
    except (TypeError, ValueError):
        v = math.nan
    lo, hi = RANGES[name]
    if not (math.isfinite(v) and lo <= v <= hi):
        raise InvalidInputError(f"{where}: column {name} must be a number in [{lo:g}, {hi:g}] "
                                f"(got {raw!r})")  # fmt: skip
    if name == "rows":
        if v != int(v):
            raise InvalidInputError(f"{where}: column rows must be an integer (got {raw!r})")
        return int(v)
    return v


def _row(where: str, raw: dict[str, Any]) -> SiteRow:
    missing = [k for k in REQUIRED if raw.get(k) in (None, "")]
    if missing:
        raise InvalidInputError(f"{where}: column {missing[0]} is missing or empty")
    row = {k: _field(where, k, raw[k]) for k in REQUIRED}
    for k in OPTIONAL:
        if raw.get(k) not in (None, ""):
            row[k] = _field(where, k, raw[k])
    return row


def read_site_rows(path: str | os.PathLike[str]) -> list[SiteRow]:
    """The checked rows of a sites file (`.csv`, or `.geojson` / `.json`), one a sector.

    Args:
        path: The file.

    Returns:
        The rows.

    Raises:
        InvalidInputError: A file that cannot be read, lacks a column, has no sectors, or a value
            out of range (the file, the row and the column named).
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as err:
        raise InvalidInputError(
            f"sites file {p}: cannot be read ({err.__class__.__name__})"
        ) from err
    if p.suffix.lower() in (".geojson", ".json"):
        rows = _geojson_rows(p, text)
    else:
        reader = csv.DictReader(text.splitlines())
        header = [h.strip() for h in reader.fieldnames or []]
        missing = [k for k in REQUIRED if k not in header]
        if missing:
            raise InvalidInputError(f"sites file {p}: no column {missing[0]} in the header "
                                    f"(needs {', '.join(REQUIRED)})")  # fmt: skip
        rows = [
            _row(f"sites file {p}, line {k}", {(a or "").strip(): b for a, b in r.items()})
            for k, r in enumerate(reader, start=2)
        ]
    if not rows:
        raise InvalidInputError(f"sites file {p}: no sectors (one row per sector)")
    return rows


def _geojson_rows(p: Path, text: str) -> list[SiteRow]:
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as err:
        raise InvalidInputError(f"sites file {p}: not JSON ({err.msg}, line {err.lineno})") from err
    except RecursionError as err:  # nested deeper than any sites file
        raise InvalidInputError(
            f"sites file {p}: not JSON a sites list can be (nested too deep)"
        ) from err
    feats = doc.get("features") if isinstance(doc, dict) else None
    if not isinstance(feats, list) or doc.get("type") != "FeatureCollection":
        raise InvalidInputError(f"sites file {p}: must be a GeoJSON FeatureCollection")
    rows = []
    for k, f in enumerate(feats):
        where = f"sites file {p}, feature {k}"
        geom = f.get("geometry") if isinstance(f, dict) else None
        coords = geom.get("coordinates") if isinstance(geom, dict) else None
        if not (isinstance(geom, dict) and geom.get("type") == "Point" and isinstance(coords, list)
                and len(coords) >= 2):  # fmt: skip
            raise InvalidInputError(f"{where}: geometry must be a Point [lon, lat]")
        props = dict(f.get("properties") or {})
        props.update(lon=coords[0], lat=coords[1])
        rows.append(_row(where, props))
    return rows


def sites_from_rows(rows: list[SiteRow], georef: Georef, where: str = "sites") -> list[Site]:
    """The scenario's sites: sectors grouped by `site_id` into masts.

    Each mast at its position in the scenario's metres, each sector's azimuth and tilts converted to
    rainuav's conventions (the module's docstring).

    Args:
        rows: The sites file's rows.
        georef: Ties the scenario to the Earth.
        where: What the errors name (the file).

    Returns:
        The [`Site`][rainuav.radio.scene.parts.Site]s.

    Raises:
        InvalidInputError: Rows whose frequency differs, or a site's sectors that disagree on where
            the mast is.
    """
    masts: dict[str, list[SiteRow]] = {}
    for r in rows:
        masts.setdefault(r["site_id"], []).append(r)
    freqs = {r["freq_ghz"] for r in rows if "freq_ghz" in r}
    if len(freqs) > 1:
        raise InvalidInputError(f"{where}: column freq_ghz differs between rows "
                                f"({sorted(freqs)}); one carrier per scenario")  # fmt: skip
    sites = []
    for sid, sectors in masts.items():
        first = sectors[0]
        for r in sectors[1:]:
            if any(r[k] != first[k] for k in ("lat", "lon", "height_m")):
                raise InvalidInputError(
                    f"{where}: site {sid}: its sectors disagree on lat, lon or height_m"
                )
        x, y = georef.to_local(first["lat"], first["lon"], name=f"{where}: site {sid}")
        cells = [
            Cell(
                azimuth_deg=(90.0 - r["azimuth_deg"]) % 360.0,
                tilt_deg=-r.get("mechanical_tilt_deg", 0.0),
                antenna=r.get("antenna", "array"),
                rows=r.get("rows", 8),
                spacing=0.5,
                electrical_tilt_deg=-r["electrical_tilt_deg"],
                tx_power_dbm=r["tx_power_dbm"],
            )
            for r in sectors
        ]
        sites.append(Site(x_m=float(x), y_m=float(y), height_m=first["height_m"], cells=cells))
    return sites


def cell_names(rows: list[SiteRow]) -> list[str]:
    """Each cell's name, `site_id:k` (its k-th sector from 1, in the file's order).

    In the order [`sites_from_rows()`][rainuav.radio.scene.sites.sites_from_rows] makes the cells:
    what a measurement log's `cell` column may give.

    Args:
        rows: The sites file's rows.

    Returns:
        The names.
    """
    masts: dict[str, list[SiteRow]] = {}
    for r in rows:
        masts.setdefault(r["site_id"], []).append(r)
    return [f"{sid}:{k}" for sid, sectors in masts.items() for k in range(1, len(sectors) + 1)]
