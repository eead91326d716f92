"""Where a scenario lies on the Earth: its georeference.

A scenario's positions are metres east (``x``) and north (``y``) of an origin. A
[`Georef`][rainuav.geo.Georef] ties that origin to a latitude and longitude (WGS 84) through an
azimuthal equidistant projection centred on it (PROJ's ``aeqd``, through pyproj): distances and
bearings from the origin are exact, and over the few kilometres of a drone's flight the scale error
elsewhere stays below 1e-6 (it grows as (d / R)^2 / 6 with the distance d from the origin: 4e-7 at
10 km), so a scenario's metres are ground metres. A UTM zone would serve as well inside one zone,
but breaks at its edges and is not centred on the area; a plain equirectangular approximation errs
by metres over kilometres.

Needs pyproj (the ``geo`` extra: ``pip install '.[geo]' from the rainuav clone``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav.errors import InvalidInputError

__all__ = ["MAX_ABS_LAT", "Georef", "check_latlon", "geodesic_m", "latlon_text", "pyproj_module"]

MAX_ABS_LAT = 85.0
"""Origins nearer the poles are refused: a drone's lattice of east and north moves has no
meaning at a pole, and the projection's north turns fast near one."""


def pyproj_module() -> Any:
    """pyproj, imported where it is installed.

    Returns:
        The `pyproj` module.

    Raises:
        InvalidInputError: pyproj is not installed (the line says how to install it).
    """
    try:
        import pyproj
    except ImportError as err:
        raise InvalidInputError(
            "georeferenced input needs pyproj: pip install '.[geo]' from the rainuav clone"
        ) from err
    return pyproj


def latlon_text(lat: float, lon: float, digits: int = 5) -> str:
    """A latitude and longitude as people read them: `33.86880 S, 151.20930 E`.

    Args:
        lat: Degrees north.
        lon: Degrees east.
        digits: Decimals.

    Returns:
        The text.
    """
    ns = "N" if lat >= 0 else "S"
    ew = "E" if lon >= 0 else "W"
    return f"{abs(lat):.{digits}f} {ns}, {abs(lon):.{digits}f} {ew}"


def check_latlon(
    name: str, lat: npt.ArrayLike, lon: npt.ArrayLike
) -> tuple[np.ndarray, np.ndarray]:
    """Latitudes and longitudes as float arrays, checked.

    Args:
        name: What the error names (a field or a file's column).
        lat: Degrees north.
        lon: Degrees east.

    Returns:
        `(lat, lon)` as float arrays.

    Raises:
        InvalidInputError: A value that is not finite, |lat| > 90 or |lon| > 180 degrees.
    """
    la = np.asarray(lat, dtype=np.float64)
    lo = np.asarray(lon, dtype=np.float64)
    if not (np.all(np.isfinite(la)) and np.all(np.isfinite(lo))):
        raise InvalidInputError(f"{name}: latitude and longitude must be finite numbers")
    if np.any(np.abs(la) > 90.0) or np.any(np.abs(lo) > 180.0):
        raise InvalidInputError(
            f"{name}: latitude must be in [-90, 90] and longitude in [-180, 180] degrees"
        )
    return la, lo


@dataclass(frozen=True)
class Georef:
    """The origin of a scenario's metres at (``lat_deg``, ``lon_deg``), WGS 84."""

    lat_deg: float
    """Latitude of the origin, degrees north (|lat| <= 85)."""
    lon_deg: float
    """Longitude of the origin, degrees east (-180..180)."""

    def __post_init__(self) -> None:
        for name in ("lat_deg", "lon_deg"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
                raise InvalidInputError(f"origin {name} must be a finite number (got {v!r})")
        if abs(self.lat_deg) > MAX_ABS_LAT:
            raise InvalidInputError(
                f"origin lat_deg must be within +-{MAX_ABS_LAT} degrees (got {self.lat_deg}): "
                "the lattice of east and north moves breaks down near a pole"
            )
        if abs(self.lon_deg) > 180.0:
            raise InvalidInputError(f"origin lon_deg must be in [-180, 180] (got {self.lon_deg})")

    @property
    def proj4(self) -> str:
        """The projection, as a PROJ string."""
        return (
            f"+proj=aeqd +lat_0={self.lat_deg!r} +lon_0={self.lon_deg!r} +x_0=0 +y_0=0 "
            "+datum=WGS84 +units=m +no_defs"
        )

    def _transformers(self) -> tuple[Any, Any]:
        cached = getattr(self, "_cache", None)
        if cached is None:
            pyproj = pyproj_module()
            local = pyproj.CRS.from_proj4(self.proj4)
            fwd = pyproj.Transformer.from_crs("EPSG:4326", local, always_xy=True)
            inv = pyproj.Transformer.from_crs(local, "EPSG:4326", always_xy=True)
            cached = (fwd, inv)
            object.__setattr__(self, "_cache", cached)
        return cached

    def to_local(
        self, lat: npt.ArrayLike, lon: npt.ArrayLike, name: str = "position"
    ) -> tuple[Any, Any]:
        """Metres east and north of the origin of points given in degrees.

        Args:
            lat: Latitudes, degrees.
            lon: Longitudes, degrees.
            name: What an error names.

        Returns:
            `(x, y)`, m east and north.

        Raises:
            InvalidInputError: Coordinates that are not finite or out of range.
        """
        la, lo = check_latlon(name, lat, lon)
        x, y = self._transformers()[0].transform(lo, la)
        return x, y

    def to_latlon(self, x: npt.ArrayLike, y: npt.ArrayLike) -> tuple[Any, Any]:
        """The latitude and longitude of points given in metres east and north of the origin.

        Args:
            x: Metres east.
            y: Metres north.

        Returns:
            `(lat, lon)`, degrees.

        Raises:
            InvalidInputError: `x` or `y` not finite.
        """
        xs, ys = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        if not (np.all(np.isfinite(xs)) and np.all(np.isfinite(ys))):
            raise InvalidInputError("x and y must be finite numbers of metres")
        lon, lat = self._transformers()[1].transform(xs, ys)
        return lat, lon


def geodesic_m(
    lat1: npt.ArrayLike, lon1: npt.ArrayLike, lat2: npt.ArrayLike, lon2: npt.ArrayLike
) -> Any:
    """The geodesic distance on the WGS 84 ellipsoid (pyproj's `Geod`: Karney's algorithm).

    Args:
        lat1: The first points' latitudes, degrees.
        lon1: Their longitudes, degrees.
        lat2: The second points' latitudes, degrees.
        lon2: Their longitudes, degrees.

    Returns:
        The distances, m, of the broadcast shape.
    """
    la1, lo1 = check_latlon("first point", lat1, lon1)
    la2, lo2 = check_latlon("second point", lat2, lon2)
    _, _, d = pyproj_module().Geod(ellps="WGS84").inv(lo1, la1, lo2, la2)
    return d
