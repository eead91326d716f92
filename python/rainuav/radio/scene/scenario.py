"""Scenarios: the cellular network, the weather and the airspace, as dataclasses with a TOML
form. Validated on construction; errors name the field and the allowed range.

Conventions (documented choices the design paper leaves open):

- Global frame: x east, y north, metres; heights above a flat ground at 0.
- A cell's ``azimuth_deg`` is its boresight direction in the horizontal plane, counter-
  clockwise from +x (0 = east, 90 = north); ``tilt_deg`` is its elevation (positive up).
- Transmit power defaults to 46 dBm per cell (a 40 W macro sector); the receiver noise is
  thermal noise over ``bandwidth_hz`` plus ``noise_figure_db`` ([physics reference, section
  9][9-noise-and-sinr]), by default 10 MHz and 9 dB: -104 + 9 = -95 dBm (``noise_dbm`` overrides
  it).
- Rain fills every column from the ground up; it varies horizontally (rain cells, rate maps)
  but not with height below the flight altitude.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import tomli_w
import tomllib

from rainuav._checks import check_choice as _choice
from rainuav._checks import check_number as _num
from rainuav._io import plain, read_toml, write_atomic
from rainuav.errors import InvalidInputError
from rainuav.geo import Georef
from rainuav.radio.engines import ENGINES as _ENGINES
from rainuav.radio.scene.area import DEFAULT_MIN_CLEARANCE_M, Area, FootprintsFile, TerrainFile
from rainuav.radio.scene.cell import Cell, Pattern
from rainuav.radio.scene.parts import Building, Origin, PESettings, Site
from rainuav.radio.scene.stochastic import StochasticRain
from rainuav.radio.scene.weather import Medium, RainCell

THERMAL_NOISE_DBM_HZ = -174.0
"""Thermal noise density at 290 K, dBm/Hz."""

ENGINES = tuple(_ENGINES)
"""Propagation engines ([`rainuav.radio.engines`][rainuav.radio.engines])."""
GROUNDS = ("pec", "none", "very-dry", "medium-dry", "wet")
"""Grounds: perfectly conducting, none (free space), or ITU-R P.527 dielectric soils."""

__all__ = [
    "DEFAULT_MIN_CLEARANCE_M",
    "Area",
    "Building",
    "Cell",
    "FootprintsFile",
    "Medium",
    "Origin",
    "PESettings",
    "Pattern",
    "RainCell",
    "Scenario",
    "Site",
    "TerrainFile",
]


@dataclass
class Scenario:
    """A network, the weather and the airspace. ``Scenario.from_toml(path)`` / ``.to_toml``."""

    name: str = "custom"
    """A label."""
    freq_hz: float = 4.9e9
    """Carrier frequency, Hz (1e9-1e11)."""
    polarization: str = "h"
    """'h' or 'v': sets the ground's image sign and the rain's polarisation."""
    bandwidth_hz: float = 10e6
    """Receiver bandwidth, Hz (sets the thermal noise)."""
    noise_figure_db: float = 9.0
    """Receiver noise figure, dB (0-30)."""
    noise_dbm: float | None = None
    """Receiver noise power, dBm, overriding ``-174 + 10 log10(bandwidth_hz) +
    noise_figure_db`` ([physics reference, section 9][9-noise-and-sinr]) when set."""
    area: Area = field(default_factory=Area)
    """The airspace."""
    sites: list[Site] = field(default_factory=list)
    """Base-station sites."""
    medium: Medium = field(default_factory=lambda: Medium(kind="clear"))
    """The weather."""
    ground: str = "pec"
    """'pec' (flat perfectly conducting ground), 'none' (free space), or a dielectric soil of
    ITU-R P.527: 'very-dry', 'medium-dry', 'wet' (rays only: the PE's ground is PEC)."""
    engine: str = "hybrid"
    """'hybrid' (the PE inside its cone, rays outside), 'ray' or 'pe' (its cone only)."""
    buildings: list[Building] = field(default_factory=list)
    """Buildings (boxes)."""
    height_map_m: list[list[float]] | None = None
    """Optional obstacle heights (m) over the area, rows south to north, columns west to east;
    each value covers its pixel of the area (nearest sample). Combined with ``buildings``."""
    pe: PESettings = field(default_factory=PESettings)
    """Gridding of the PE marches."""
    origin: Origin | None = None
    """Where (0, 0) lies on the Earth, if the scenario is georeferenced (``[origin]`` with
    ``lat_deg``, ``lon_deg``: [`rainuav.geo.Georef`][rainuav.geo.Georef], an azimuthal equidistant
    projection on WGS 84); every position then has a latitude and longitude too."""
    terrain: TerrainFile | None = None
    """The terrain (``[terrain] file = "dem.tif"``; needs ``origin``): heights are then above
    it (a site's antenna over the terrain at the site; the UAV over the terrain under it, or
    above sea level: ``area.altitude_reference``), and buildings and ``height_map_m`` stand on
    it ([physics reference, section 12][12-terrain-buildings-diffraction-and-reflections]). None: a
    flat ground at 0."""
    footprints: FootprintsFile | None = None
    """Buildings from a footprint file (``[footprints] file = "buildings.geojson"``; needs
    ``origin``): prisms standing on the terrain beside ``buildings``; they diffract, block and
    reflect ([physics reference, section 12][12-terrain-buildings-diffraction-and-reflections])."""

    def __post_init__(self) -> None:
        self.check()

    # -- validation -------------------------------------------------------------------------
    # Long: one check per field of the scenario, in the order of its fields: a flat list, each line
    # naming its field.
    def check(self) -> None:
        """Checks every field; raises InvalidInputError naming the first bad one."""
        _num("freq_hz", self.freq_hz, 1e9, 1e11, " Hz")
        _choice("polarization", self.polarization, ("h", "v"))
        _num("bandwidth_hz", self.bandwidth_hz, 1e3, 1e10, " Hz")
        _num("noise_figure_db", self.noise_figure_db, 0.0, 30.0, " dB")
        if self.noise_dbm is not None:
            _num("noise_dbm", self.noise_dbm, -200.0, 50.0, " dBm")
        _choice("ground", self.ground, GROUNDS)
        _choice("engine", self.engine, ENGINES)
        self.area.check()
        self.medium.check()
        self.pe.check()
        if self.origin is not None:
            self.georef  # noqa: B018 - checks the origin (one line naming the field)
        if self.terrain is not None:
            if not isinstance(self.terrain, TerrainFile) or not isinstance(self.terrain.file, str):
                raise InvalidInputError("terrain must be a table with file = 'DEM.tif'")
            _num("terrain.roughness_m", self.terrain.roughness_m, 0.0, 100.0, " m")
            if self.origin is None:
                raise InvalidInputError(
                    "terrain needs [origin] (lat_deg, lon_deg): where the area lies on the Earth"
                )
            if _ENGINES[self.engine].marches and self.ground == "none":
                raise InvalidInputError(
                    f"engine {self.engine!r} over terrain needs a ground (the march's floor): "
                    "ground = 'pec', or engine = 'ray'"
                )
        if self.footprints is not None:
            if not isinstance(self.footprints, FootprintsFile) or not isinstance(
                self.footprints.file, str
            ):
                raise InvalidInputError("footprints must be a table with file = 'FILE.geojson'")
            if self.origin is None:
                raise InvalidInputError(
                    "footprints need [origin] (lat_deg, lon_deg): where the area lies on the Earth"
                )
            from rainuav.ground.footprints import MATERIALS

            _choice("footprints.material", self.footprints.material, tuple(sorted(MATERIALS)))
            _num("footprints.default_height_m", self.footprints.default_height_m, 0.5, 1000.0, " m")
        a = self.area
        if not self.sites:
            raise InvalidInputError("sites must hold at least one site")
        seen: set[tuple[float, float]] = set()
        for i, s in enumerate(self.sites):
            w = f"sites[{i}]"
            _num(f"{w}.x_m", s.x_m, a.x_min_m, a.x_max_m, " m (inside the area)")
            _num(f"{w}.y_m", s.y_m, a.y_min_m, a.y_max_m, " m (inside the area)")
            _num(f"{w}.height_m", s.height_m, 1.0, 1000.0, " m")
            if (s.x_m, s.y_m) in seen:
                raise InvalidInputError(f"{w} overlaps another site at ({s.x_m}, {s.y_m})")
            seen.add((s.x_m, s.y_m))
            if not s.cells:
                raise InvalidInputError(f"{w}.cells must hold at least one cell (a beam)")
            beams: set[tuple[float, float]] = set()
            for j, c in enumerate(s.cells):
                c.check(f"{w}.cells[{j}]")
                key = (c.azimuth_deg % 360.0, c.tilt_deg, c.key())
                if key in beams:
                    raise InvalidInputError(
                        f"{w}.cells[{j}] overlaps another cell of the site "
                        "(same antenna, azimuth and tilt)"
                    )
                beams.add(key)
        if self.height_map_m is not None:
            hm = np.asarray(self.height_map_m, dtype=float)
            if hm.ndim != 2 or min(hm.shape) < 1:
                raise InvalidInputError(f"height_map_m must be a 2-D table (got shape {hm.shape})")
            if not (np.all(np.isfinite(hm)) and hm.min() >= 0 and hm.max() <= 1000):
                raise InvalidInputError("height_map_m must be within 0..1000 m")
        for i, b in enumerate(self.buildings):
            w = f"buildings[{i}]"
            for k in ("x0_m", "x1_m", "y0_m", "y1_m"):
                _num(f"{w}.{k}", getattr(b, k), -1e6, 1e6, " m")
            if not (b.x1_m > b.x0_m and b.y1_m > b.y0_m):
                raise InvalidInputError(f"{w} must have x1_m > x0_m and y1_m > y0_m")
            _num(f"{w}.height_m", b.height_m, 0.1, 1000.0, " m")
            for j, s in enumerate(self.sites):
                if (
                    b.x0_m <= s.x_m <= b.x1_m
                    and b.y0_m <= s.y_m <= b.y1_m
                    and (b.height_m >= s.height_m)
                ):
                    raise InvalidInputError(
                        f"sites[{j}] is inside {w}, which is as tall as its antenna"
                    )

    @property
    def noise_power_dbm(self) -> float:
        """The receiver noise for SINR: ``noise_dbm`` if set, else thermal noise
        ``-174 dBm/Hz + 10 log10(bandwidth_hz) + noise_figure_db``."""
        if self.noise_dbm is not None:
            return float(self.noise_dbm)
        return THERMAL_NOISE_DBM_HZ + 10.0 * math.log10(self.bandwidth_hz) + self.noise_figure_db

    # -- identity ---------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """The scenario as plain data.

        Returns:
            A dict of its fields (TOML- and JSON-ready; None fields dropped).
        """

        return plain(self)

    def digest(self) -> str:
        """A hash of every field.

        Two scenarios with the same digest describe the same network, weather and airspace. The
        radio-map cache keys on it together with the engine's fingerprint
        ([`engine_fingerprint()`][rainuav.radio.outputs.cache.engine_fingerprint]). A terrain or
        footprints file enters by its content.

        Returns:
            The digest, as hexadecimal text.

        Raises:
            InvalidInputError: A terrain or footprints file that cannot be read.
        """
        d = _digest_form(self)
        if self.terrain is not None:
            # The map follows the DEM's contents, not its name.
            from rainuav.ground import file_digest

            try:
                d["terrain"] = {"sha256": file_digest(self.terrain.file)}
            except OSError as err:
                raise InvalidInputError(
                    f"terrain file {self.terrain.file}: cannot be read ({err.strerror})"
                ) from err
        if self.footprints is not None:
            from rainuav.ground import file_digest

            try:
                d["footprints"] = {
                    "sha256": file_digest(self.footprints.file),
                    "material": self.footprints.material,
                    "default_height_m": self.footprints.default_height_m,
                }
            except OSError as err:
                raise InvalidInputError(
                    f"footprints file {self.footprints.file}: cannot be read ({err.strerror})"
                ) from err
        text = json.dumps(d, sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()[:32]

    # -- TOML -------------------------------------------------------------------------------
    def to_toml(self, path: str | Path) -> Path:
        """Writes the scenario as TOML, atomically.

        Args:
            path: The file to write.

        Returns:
            The path written.
        """
        text = tomli_w.dumps(self.to_dict())
        return write_atomic(path, lambda tmp: tmp.write_text(text))

    def to_toml_string(self) -> str:
        """The scenario as TOML text.

        Returns:
            What [`to_toml()`][rainuav.radio.scene.scenario.Scenario.to_toml] writes.
        """
        return tomli_w.dumps(self.to_dict())

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Scenario:
        """Builds a scenario from plain data, validated.

        Args:
            d: A dict of fields, as [`to_dict()`][rainuav.radio.scene.scenario.Scenario.to_dict]
                gives (nested tables as dicts).

        Returns:
            The [`Scenario`][rainuav.radio.scene.scenario.Scenario].

        Raises:
            InvalidInputError: An unknown key, or a field of the wrong kind or outside its range
                (named).
        """
        return _build(cls, d, "scenario")

    @classmethod
    def from_toml(cls, path: str | Path) -> Scenario:
        """Reads a scenario from a TOML file, validated.

        Args:
            path: The file.

        Returns:
            The [`Scenario`][rainuav.radio.scene.scenario.Scenario].

        Raises:
            InvalidInputError: A missing, unreadable or malformed file (named), or a field out of
                range.
        """
        d = read_toml(path, "scenario file")
        for key in ("terrain", "footprints"):
            t = d.get(key)
            if isinstance(t, dict) and isinstance(t.get("file"), str):
                d[key] = {**t, "file": str(Path(path).parent / Path(t["file"]).expanduser())}
        return cls.from_dict(d)

    @classmethod
    def from_toml_string(cls, text: str) -> Scenario:
        """Reads a scenario from TOML text, validated.

        Args:
            text: The scenario as TOML.

        Returns:
            The [`Scenario`][rainuav.radio.scene.scenario.Scenario].

        Raises:
            InvalidInputError: Text that is not TOML, an unknown key, or a field out of range.
        """
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as err:
            raise InvalidInputError(f"scenario: not valid TOML ({err})") from err
        return cls.from_dict(data)

    @property
    def georef(self) -> Georef | None:
        """The scenario's georeference, or None where it has no origin."""
        if self.origin is None:
            return None
        if not isinstance(self.origin, Origin):
            raise InvalidInputError("origin must be a table with lat_deg and lon_deg")
        return Georef(self.origin.lat_deg, self.origin.lon_deg)

    def replace(self, **changes: Any) -> Scenario:
        """A copy with fields changed, validated.

        Args:
            **changes: New values of fields, by name.

        Returns:
            The new [`Scenario`][rainuav.radio.scene.scenario.Scenario].
        """
        return dataclasses.replace(self, **changes)


_NESTED: dict[tuple[type, str], type] = {
    (Scenario, "area"): Area,
    (Scenario, "origin"): Origin,
    (Scenario, "terrain"): TerrainFile,
    (Scenario, "footprints"): FootprintsFile,
    (Scenario, "medium"): Medium,
    (Scenario, "pe"): PESettings,
    (Medium, "field"): StochasticRain,
    (Cell, "pattern"): Pattern,
}
_LISTS: dict[tuple[type, str], type] = {
    (Scenario, "sites"): Site,
    (Scenario, "buildings"): Building,
    (Site, "cells"): Cell,
    (Medium, "cells"): RainCell,
}


def _build(cls: type, d: Any, where: str) -> Any:
    if not isinstance(d, dict):
        raise InvalidInputError(f"{where} must be a table (got {type(d).__name__})")
    names = {f.name for f in dataclasses.fields(cls)}
    unknown = set(d) - names
    if unknown:
        raise InvalidInputError(
            f"{where}: unknown field(s) {sorted(unknown)}; known: {sorted(names)}"
        )
    kwargs: dict[str, Any] = {}
    for k, v in d.items():
        if (cls, k) in _NESTED and v is not None:
            kwargs[k] = _build(_NESTED[(cls, k)], v, f"{where}.{k}" if where != "scenario" else k)
        elif (cls, k) in _LISTS:
            if not isinstance(v, list):
                raise InvalidInputError(f"{k} must be a list")
            kwargs[k] = [_build(_LISTS[(cls, k)], x, f"{k}[{i}]") for i, x in enumerate(v)]
        else:
            kwargs[k] = v
    try:
        return cls(**kwargs)
    except TypeError as err:
        raise InvalidInputError(f"{where}: {err}") from err


def _digest_form(v: Any) -> Any:
    """What [`Scenario.digest()`][rainuav.radio.scene.scenario.Scenario.digest] hashes: the
    fields as [`Scenario.to_dict()`][rainuav.radio.scene.scenario.Scenario.to_dict] gives them
    (None dropped), but a grid (a list of lists of numbers: a rain-rate map in time, a height map)
    as its shape and the SHA-256 of its values as float64, where the JSON text of a radar file's
    half a million rates took seconds to write."""
    if dataclasses.is_dataclass(v) and not isinstance(v, type):
        return {
            f.name: _digest_form(x)
            for f in dataclasses.fields(v)
            if (x := getattr(v, f.name)) is not None
        }
    if isinstance(v, dict):
        return {k: _digest_form(x) for k, x in v.items() if x is not None}
    if isinstance(v, list | tuple):
        if v and isinstance(v[0], list | tuple | np.ndarray):
            try:
                a = np.ascontiguousarray(np.asarray(v, dtype=np.float64))
            except (TypeError, ValueError):
                a = None
            if a is not None and a.ndim >= 2:
                return {"grid": list(a.shape), "sha256": hashlib.sha256(a.tobytes()).hexdigest()}
        return [_digest_form(x) for x in v]
    if isinstance(v, np.ndarray):
        a = np.ascontiguousarray(v, dtype=np.float64)
        return {"grid": list(a.shape), "sha256": hashlib.sha256(a.tobytes()).hexdigest()}
    return v
