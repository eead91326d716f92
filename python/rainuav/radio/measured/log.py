"""A measurement log: what a drive test or a flight recorded, per cell, read into the map's frame.

A log is a CSV with a header row. Its columns (names matched without regard to case, spaces,
and a trailing unit in brackets, so ``RSRP (dBm)`` is ``rsrp``):

- where: ``lat``, ``lon`` (degrees, WGS 84; the scenario needs an ``[origin]``) or ``x_m``,
  ``y_m`` (the scenario's metres east and north);
- ``alt_m``: the receiver's height, m, above the ground under it (``altitude_reference =
  "msl"``: above mean sea level);
- ``cell``: which cell was measured: its 0-based index among the map's cells, or
  ``site_id:k``, the k-th sector (from 1) of that site in the sites file the scenario was placed
  from (``cell_names``);
- the level: ``rsrp_dbm`` (reference-signal received power, per resource element) or
  ``rss_dbm`` (the cell's power over the whole band, the map's own quantity);
- optional: ``time`` (seconds, or an ISO 8601 instant), ``sinr_db``, ``flight`` (which
  flight or drive a row belongs to: the calibration's cross-validation leaves one out),
  ``heading_deg`` (where the UAV's nose points, degrees clockwise from north, as autopilots log
  it; a row without one is kept, its heading unknown).

Drive-test tools name these columns their own way; [`ALIASES`][rainuav.radio.measured.log.ALIASES]
maps the common ones (``Latitude``, ``Longitude``, ``Altitude``, ``RSRP``, ``Cell``...).

**RSRP to the map's power.** RSRP is the power of one resource element (one 15 kHz subcarrier
of one symbol). The map's ``rss_dbm`` is the cell's power over the band, so a fully loaded cell
gives ``rss_dbm = rsrp_dbm + 10 log10(12 N_RB)``, with ``N_RB = floor(0.9 B / (12 Delta f))``
resource blocks in the bandwidth ``B`` at subcarrier spacing ``Delta f`` (LTE's 90% occupancy:
50 blocks, +27.8 dB, at 10 MHz and 15 kHz):
[`rss_from_rsrp()`][rainuav.radio.measured.log.rss_from_rsrp].

**Bad rows** are counted by reason and skipped: a missing or non-numeric value, a point off the
area, an unknown cell, an RSRP outside -160..-20 dBm (RSS: that range moved by the same
conversion), a receiver below the ground or more than 3 000 m above it (``alt_m``), a row with
fewer fields than the header, and exact duplicates of an earlier row. A file with no usable
row is refused in one line saying why the rows went."""

from __future__ import annotations

import csv
import math
import os
import re
from collections import Counter
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav._checks import check_fits
from rainuav.errors import InvalidInputError
from rainuav.radio.scene.scenario import Scenario
from rainuav.radio.scene.terrain import surface_at

__all__ = [
    "ALIASES",
    "MAX_HEIGHT_M",
    "MAX_ROWS",
    "RSRP_RANGE_DBM",
    "MeasurementLog",
    "read_log",
    "rss_from_rsrp",
]

RSRP_RANGE_DBM = (-160.0, -20.0)
"""The RSRP a log may report, dBm (3GPP TS 36.133 reports -156..-31)."""
MAX_HEIGHT_M = 3000.0
"""The highest a logged receiver may fly above the ground, m (a map's highest flight level)."""
MAX_ROWS = 2_000_000
"""The most rows a log may have (a 2-million-row log is about 100 MB of CSV): split a longer one."""
ALIASES: dict[str, tuple[str, ...]] = {
    "lat": ("lat", "latitude", "lat_deg", "gps_lat"),
    "lon": ("lon", "longitude", "lng", "long", "lon_deg", "gps_lon"),
    "x_m": ("x_m", "x", "east_m", "easting_m"),
    "y_m": ("y_m", "y", "north_m", "northing_m"),
    "alt_m": ("alt_m", "alt", "altitude", "altitude_m", "height", "height_m", "gps_alt"),
    "cell": ("cell", "cell_id", "cellid", "cell_name", "sector"),
    "rsrp_dbm": ("rsrp_dbm", "rsrp", "serving_rsrp", "servingcellrsrp", "ss_rsrp", "nr_rsrp"),
    "rss_dbm": ("rss_dbm", "rss", "received_power_dbm"),
    "sinr_db": ("sinr_db", "sinr", "rs_sinr", "ss_sinr"),
    "time": ("time", "timestamp", "time_s", "datetime", "utc"),
    "flight": ("flight", "flight_id", "drive", "log", "mission"),
    "heading_deg": ("heading_deg", "heading", "yaw_deg", "yaw", "hdg"),
}
"""Each column rainuav reads and the header names it accepts for it (after lower-casing, dropping
a bracketed unit and turning spaces and dashes into underscores)."""


def rss_from_rsrp(
    rsrp_dbm: npt.ArrayLike, bandwidth_hz: float, subcarrier_khz: float = 15.0
) -> Any:
    """The cell's power over the band from its RSRP, for a fully loaded carrier.

    RSRP is the power of one resource element (one subcarrier): the power over the band is
    `rsrp_dbm + 10 log10(12 N_RB)`, with `N_RB = floor(0.9 B / (12 Delta f))` resource blocks in
    the bandwidth `B` at spacing `Delta f` (LTE's 90% occupancy).

    Args:
        rsrp_dbm: RSRP, dBm per resource element (a number or an array).
        bandwidth_hz: The carrier's bandwidth, Hz.
        subcarrier_khz: The subcarrier spacing, kHz.

    Returns:
        The power over the band, dBm, of the shape of `rsrp_dbm`.

    Raises:
        InvalidInputError: A bandwidth that holds no resource block at that spacing.
    """
    blocks = math.floor(0.9 * bandwidth_hz / (12 * subcarrier_khz * 1e3) + 1e-9)
    if blocks < 1:
        raise InvalidInputError(
            f"bandwidth_hz {bandwidth_hz:g} holds no resource block at {subcarrier_khz:g} kHz"
        )
    return np.asarray(rsrp_dbm, dtype=float) + 10.0 * math.log10(12 * blocks)


@dataclass
class MeasurementLog:
    """The usable rows of a log in the map's frame, one entry per row."""

    x_m: npt.NDArray[np.float64]
    """East, m (the scenario's frame)."""
    y_m: npt.NDArray[np.float64]
    """North, m."""
    z_m: npt.NDArray[np.float64]
    """The receiver's height above sea level (above the flat ground without a terrain), m."""
    alt_m: npt.NDArray[np.float64]
    """The receiver's height above the ground under it, m."""
    cell: npt.NDArray[np.int64]
    """The map's cell index."""
    rss_dbm: npt.NDArray[np.float64]
    """The cell's measured power over the band, dBm (from RSRP where the log gave RSRP)."""
    flight: npt.NDArray[np.int64]
    """Which flight each row belongs to (0 where the log names none)."""
    time_s: npt.NDArray[np.float64] | None = None
    """Seconds since the log's first instant, where the log has a ``time`` column."""
    sinr_db: npt.NDArray[np.float64] | None = None
    """The SINR the receiver reported, dB, where the log has a ``sinr_db`` column (kept for the
    user; the fit uses the per-cell power: a SINR depends on every cell and on the load)."""
    heading_deg: npt.NDArray[np.float64] | None = None
    """Where the UAV's nose pointed, degrees clockwise from north (NaN where a row gave none),
    where the log has a ``heading_deg`` column."""
    rows: int = 0
    """Data rows in the file."""
    skipped: dict[str, int] = field(default_factory=dict)
    """Rows skipped, by reason."""
    source: str = ""
    """The file it was read from."""

    def __len__(self) -> int:
        return int(self.x_m.size)

    def summary(self) -> str:
        """What was read, in one line.

        Returns:
            The rows used and, by reason, how many were skipped.
        """
        why = ", ".join(f"{n} {k}" for k, n in sorted(self.skipped.items()))
        return f"{self.source}: {len(self)} of {self.rows} rows used" + (f" ({why})" if why else "")


def _norm(name: str) -> str:
    name = re.sub(r"[\[(].*?[\])]", "", name).strip().lower()
    return re.sub(r"[\s\-]+", "_", name)


def _columns(path: Path, header: list[str]) -> dict[str, int]:
    found: dict[str, int] = {}
    for i, raw in enumerate(header):
        n = _norm(raw)
        for key, names in ALIASES.items():
            if n in names and key not in found:
                found[key] = i
    where = ("lat", "lon") if "lat" in found or "lon" in found else ("x_m", "y_m")
    need = [*where, "alt_m", "cell"]
    missing = [k for k in need if k not in found]
    if "rsrp_dbm" not in found and "rss_dbm" not in found:
        missing.append("rsrp_dbm (or rss_dbm)")
    if missing:
        raise InvalidInputError(
            f"measurement log {path}: missing column(s) {', '.join(missing)} (header: "
            f"{', '.join(header)}); a log needs lat,lon (or x_m,y_m),alt_m,cell,rsrp_dbm"
        )
    return found


def _number(v: str) -> float:
    try:
        x = float(v)
    except ValueError:
        return math.nan
    return x


def _seconds(v: str) -> float:
    x = _number(v)
    if not math.isnan(x):
        return x
    try:
        return datetime.fromisoformat(v.strip().replace("Z", "+00:00")).timestamp()
    except ValueError:
        return math.nan


def read_log(
    path: str | os.PathLike[str],
    scn: Scenario,
    *,
    cell_names: list[str] | None = None,
    altitude_reference: str = "ground",
    subcarrier_khz: float = 15.0,
) -> MeasurementLog:
    """Reads a measurement log (CSV) into a scenario's frame.

    The module docstring gives the columns: positions become the scenario's metres, heights
    above the ground and above sea level, cells map indices, and power the map's ``rss_dbm``.
    Bad rows are counted and skipped (``MeasurementLog.summary()`` says how many, and why).

    Args:
        path: The CSV file.
        scn: The scenario of the map it will correct (with an ``[origin]`` for ``lat``/``lon``).
        cell_names: The ``site_id:k`` name of each map cell
            ([`rainuav.world.place`][rainuav.world.place] gives them), for a ``cell`` column of
            names.
        altitude_reference: What ``alt_m`` is above: ``"ground"`` or ``"msl"``.
        subcarrier_khz: The subcarrier spacing an RSRP column was measured at, kHz.

    Returns:
        The [`MeasurementLog`][rainuav.radio.measured.log.MeasurementLog].

    Raises:
        InvalidInputError: A file that cannot be read, is empty or too long, lacks a column it
            needs, or has no usable row (the message names the file and the column).
    """
    p = Path(path)
    if altitude_reference not in ("ground", "msl"):
        raise InvalidInputError(
            f"altitude_reference must be 'ground' or 'msl' (got {altitude_reference!r})"
        )
    try:
        # Rows are held as Python strings while read: about 30 times the file's size (a
        # million rows, 26 MB, peaked at 780 MB).
        check_fits(f"measurement log {p}", 35.0 * p.stat().st_size, "split the log")
        with p.open(newline="", encoding="utf-8-sig") as f:
            reader = csv.reader(f)
            header = next(reader, None)
            if header is None:
                raise InvalidInputError(f"measurement log {p}: the file is empty")
            cols = _columns(p, header)
            rows = []
            for r in reader:
                if not r or all(not v.strip() for v in r):
                    continue
                rows.append(r)
                if len(rows) > MAX_ROWS:
                    raise InvalidInputError(
                        f"measurement log {p}: more than {MAX_ROWS:,} rows; split it or average "
                        "it over pixels first"
                    )
    except OSError as err:
        raise InvalidInputError(f"measurement log {p}: cannot be read ({err.strerror})") from err
    except (UnicodeDecodeError, csv.Error) as err:
        raise InvalidInputError(f"measurement log {p}: not a CSV text file ({err})") from err
    return _to_log(p, scn, rows, cols, cell_names, altitude_reference, subcarrier_khz)


def _cell_index(raw: list[str], cells: int, names: list[str] | None) -> np.ndarray:
    lookup = {n.lower(): i for i, n in enumerate(names or [])}
    out = np.full(len(raw), -1, dtype=np.int64)
    for i, v in enumerate(raw):
        v = v.strip()
        if v.lower() in lookup:
            out[i] = lookup[v.lower()]
        elif re.fullmatch(r"\d+", v) and int(v) < cells:
            out[i] = int(v)
    return out


# Long: one pass over a log's columns; each filter (outside the area, unknown cells, values not
# finite or out of range) drops its rows and counts them for the summary line.
def _to_log(
    p: Path,
    scn: Scenario,
    rows: list[list[str]],
    cols: dict[str, int],
    cell_names: list[str] | None,
    altitude_reference: str,
    subcarrier_khz: float,
) -> MeasurementLog:
    n = len(rows)

    def column(key: str, conv: Any = _number) -> np.ndarray:
        i = cols[key]
        return np.array([conv(r[i]) if i < len(r) else math.nan for r in rows], dtype=float)

    skipped: Counter[str] = Counter()
    seen: set[tuple[str, ...]] = set()
    width = max(cols.values()) + 1
    short = np.array([len(r) < width for r in rows], dtype=bool)
    dup = np.zeros(n, dtype=bool)
    for i, r in enumerate(rows):
        if short[i]:  # a short row is not a duplicate of another short row: it is short
            continue
        key = tuple(v.strip() for v in r)
        dup[i] = key in seen
        seen.add(key)
    geo = "lat" in cols
    a, b = (column("lat"), column("lon")) if geo else (column("x_m"), column("y_m"))
    alt = column("alt_m")
    level = column("rsrp_dbm") if "rsrp_dbm" in cols else column("rss_dbm")
    lo, hi = RSRP_RANGE_DBM
    if "rsrp_dbm" in cols:
        good_level = (level >= lo) & (level <= hi)
        level = rss_from_rsrp(level, scn.bandwidth_hz, subcarrier_khz)
    else:
        shift = float(rss_from_rsrp(0.0, scn.bandwidth_hz, subcarrier_khz))
        good_level = (level >= lo + shift) & (level <= hi + shift)
    ncell = sum(len(s.cells) for s in scn.sites)
    cell = _cell_index([r[cols["cell"]] if cols["cell"] < len(r) else "" for r in rows],
                       ncell, cell_names)  # fmt: skip
    numeric = np.isfinite(a) & np.isfinite(b) & np.isfinite(alt) & np.isfinite(level)
    x, y = np.full(n, np.nan), np.full(n, np.nan)
    if geo:
        g = scn.georef
        if g is None:
            raise InvalidInputError(
                f"measurement log {p}: gives lat and lon but the scenario has no [origin]; "
                "give x_m,y_m or place the scenario"
            )
        ok = numeric & (np.abs(a) <= 90) & (np.abs(b) <= 180)
        if ok.any():
            x[ok], y[ok] = g.to_local(a[ok], b[ok], name=f"measurement log {p}")
        numeric = ok
    else:
        x, y = a, b
    ar = scn.area
    inside = numeric & (x >= ar.x_min_m) & (x <= ar.x_max_m) & (y >= ar.y_min_m) & (y <= ar.y_max_m)
    height_ok = np.zeros(n, dtype=bool)
    if inside.any():  # the receiver's height above the ground: what a map can be built at
        g = surface_at(scn, x[inside], y[inside])
        h = alt[inside] - g if altitude_reference == "msl" else alt[inside]
        height_ok[inside] = (h >= 0.0) & (h <= MAX_HEIGHT_M)
    reasons = [
        ("short rows (fewer fields than the header)", short),
        ("duplicate rows", dup),
        ("missing or non-numeric values", ~short & ~dup & ~numeric),
        ("off the area", ~dup & numeric & ~inside),
        ("unknown cells", ~dup & inside & (cell < 0)),
        (f"levels outside RSRP {lo:g}..{hi:g} dBm", ~dup & inside & (cell >= 0) & ~good_level),
        (
            f"alt_m outside 0..{MAX_HEIGHT_M:g} m above the ground",
            ~dup & inside & (cell >= 0) & good_level & ~height_ok,
        ),
    ]
    for why, m in reasons:
        if m.any():
            skipped[why] = int(m.sum())
    use = ~dup & inside & (cell >= 0) & good_level & height_ok
    if not use.any():
        raise InvalidInputError(_no_row(p, n, skipped, x, y, numeric, scn))
    ground = surface_at(scn, x[use], y[use])
    if altitude_reference == "msl":
        z, above = alt[use], alt[use] - ground
    else:
        z, above = ground + alt[use], alt[use]
    flight = np.zeros(use.sum(), dtype=np.int64)
    if "flight" in cols:
        names = [r[cols["flight"]].strip() if cols["flight"] < len(r) else "" for r in rows]
        ids = {v: i for i, v in enumerate(dict.fromkeys(names))}
        flight = np.array([ids[v] for v in names], dtype=np.int64)[use]
    t = None
    if "time" in cols:
        t = column("time", _seconds)[use]
        t = t - np.nanmin(t) if np.isfinite(t).any() else None
    return MeasurementLog(
        x_m=x[use], y_m=y[use], z_m=z, alt_m=above, cell=cell[use], rss_dbm=level[use],
        flight=flight, time_s=t, rows=n, skipped=dict(skipped), source=str(p),
        sinr_db=column("sinr_db")[use] if "sinr_db" in cols else None,
        heading_deg=_headings(column("heading_deg")[use]) if "heading_deg" in cols else None,
    )  # fmt: skip


def _headings(h: np.ndarray) -> np.ndarray:
    """Headings in 0..360 degrees; NaN where a value is missing or outside -360..720."""
    ok = np.isfinite(h) & (h >= -360.0) & (h <= 720.0)
    return np.where(ok, np.mod(np.where(ok, h, 0.0), 360.0), np.nan)


def _no_row(
    p: Path, n: int, skipped: Counter[str], x: Any, y: Any, numeric: Any, scn: Scenario
) -> str:
    if n == 0:
        return f"measurement log {p}: no data row"
    why = ", ".join(f"{k}: {v}" for k, v in skipped.most_common())
    msg = f"measurement log {p}: no usable row of {n} ({why})"
    if skipped.get("off the area") and numeric.any():
        ar = scn.area
        cx, cy = (ar.x_min_m + ar.x_max_m) / 2, (ar.y_min_m + ar.y_max_m) / 2
        d = float(np.hypot(np.nanmedian(x[numeric]) - cx, np.nanmedian(y[numeric]) - cy))
        msg += f"; its median point lies {d / 1e3:.1f} km from the area's centre: another place?"
    return msg
