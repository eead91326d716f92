"""A radio map as data: [`RadioMap`][rainuav.radio.outputs.mapdata.RadioMap] (received power per
cell, serving cell, SIR and SINR at the flight altitude), its .npz form, the checks a map file must
pass, and keeping a map in the cache. [`rainuav.radio.outputs.maps`][rainuav.radio.outputs.maps]
builds maps; [`rainuav.radio.outputs.timemap`][rainuav.radio.outputs.timemap] builds them in
time."""

from __future__ import annotations

import dataclasses
import json
import os
import warnings
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav._io import write_atomic
from rainuav.errors import CacheWarning, InvalidInputError
from rainuav.radio.outputs.cache import cache_dir
from rainuav.radio.outputs.mapchecks import check_arrays, check_map_arrays
from rainuav.radio.outputs.plot import plot_map
from rainuav.radio.outputs.sinr import RSS_FLOOR_DBM
from rainuav.radio.scene.presets import DEFAULT_MIN_DB, SINR_THRESHOLDS_DB
from rainuav.radio.scene.scenario import Scenario
from rainuav.signals import Signal, read_arrays, signal_name, toml_of

__all__ = [
    "FORMAT_VERSION",
    "RadioMap",
    "default_min_db",
    "read_npz",
    "store",
    "write_npz",
]

FORMAT_VERSION = 2
"""Version of the .npz layout written by
[`RadioMap.save()`][rainuav.radio.outputs.mapdata.RadioMap.save]."""


@dataclass
class RadioMap:
    """Received power per cell, serving cell, SIR and SINR at the flight altitude."""

    x_m: npt.NDArray[np.float64]
    """(W,) pixel-centre east coordinates."""
    y_m: npt.NDArray[np.float64]
    """(H,) pixel-centre north coordinates."""
    extent_m: tuple[float, float, float, float]
    """(x_min, x_max, y_min, y_max) of the area."""
    altitude_m: float
    """Flight altitude, m."""
    rss_dbm: npt.NDArray[np.float64]
    """(M, H, W) received power per cell, isotropic receiver, dBm (-250 where unreached)."""
    serving_cell: npt.NDArray[np.int64]
    """(H, W) the strongest cell (-1 where none reaches)."""
    sir_db: npt.NDArray[np.float64]
    """(H, W) SIR in dB, clipped to [-40, 60]."""
    sinr_db: npt.NDArray[np.float64]
    """(H, W) SINR in dB, clipped to [-40, 60]."""
    scenario: Scenario
    """The scenario the map was built from."""
    cell_site: npt.NDArray[np.int64]
    """(M,) the site index of each cell."""
    pe_share: npt.NDArray[np.float32] = None  # type: ignore[assignment]
    """(M, H, W) which engine produced each cell's power at each pixel: the PE's share of
    it (0: rays alone, 1: the PE alone; all 0 if not given)."""
    pe_cone_deg: npt.NDArray[np.float64] = None  # type: ignore[assignment]
    """(M, 2) each cell's PE cone, half-widths across range and in height, degrees (0: no
    PE for that cell, or not given)."""
    build_seconds: float = 0.0
    """Wall time of the build (0 when loaded from the cache)."""
    timings: dict[str, float] = dataclasses.field(default_factory=dict)
    """Seconds per phase of the build: source, screens, march, resample (empty if cached)."""
    not_flyable: npt.NDArray[np.bool_] | None = None
    """(H, W) the pixels a UAV may not enter: terrain or obstacles within the clearance of the
    flight height
    ([`rainuav.radio.scene.terrain.not_flyable()`][rainuav.radio.scene.terrain.not_flyable]); None
    over flat open ground."""
    prior_rss_dbm: npt.NDArray[np.float64] | None = None
    """(M, H, W) a map corrected by measurements
    ([`rainuav.radio.measured`][rainuav.radio.measured]): the physics map it started from, dBm;
    None for a physics map."""
    rss_std_db: npt.NDArray[np.float64] | None = None
    """(M, H, W) a corrected map: the standard deviation of the local mean ``rss_dbm``
    predicts, dB; None for a physics map (its prior spreads:
    [`rainuav.radio.measured.prior.prior_spread()`][rainuav.radio.measured.prior.prior_spread])."""
    rss_sample_std_db: npt.NDArray[np.float64] | None = None
    """(M, H, W) a corrected map: the standard deviation of one sample around the local mean
    (fast fading, the UAV's antenna and airframe, the receiver), dB; a link's outage, sample by
    sample, uses it and ``rss_std_db`` in quadrature. None for a physics map, or a corrected
    map saved before it was kept."""
    fit: dict[str, Any] | None = None
    """A corrected map: its calibration, residual fields and cross-validated error (what
    ``fit.json`` holds); None for a physics map."""

    _ARRAYS = (
        "x_m",
        "y_m",
        "rss_dbm",
        "serving_cell",
        "sir_db",
        "sinr_db",
        "cell_site",
        "pe_share",
        "pe_cone_deg",
    )
    _MEASURED = ("prior_rss_dbm", "rss_std_db", "rss_sample_std_db")

    def __post_init__(self) -> None:
        if self.pe_share is None:
            self.pe_share = np.zeros(np.shape(self.rss_dbm), np.float32)
        if self.pe_cone_deg is None:
            self.pe_cone_deg = np.zeros((len(self.rss_dbm), 2))

    def default_min_db(self, signal: str = "sinr") -> float:
        """The outage threshold a navigation task on this map uses unless told otherwise.

        Args:
            signal: "sinr" or "sir".

        Returns:
            For SINR the preset's documented threshold, dB (`presets.SINR_THRESHOLDS_DB`, by the
            scenario's name); for SIR, and for scenarios of no preset, 10 dB (the paper's minimum
            SIR).
        """
        return default_min_db(self.scenario.name, signal)

    def as_signal(self, signal: str = "sinr", *, scenario_toml: bool = True) -> Signal:
        """The map as one [`Signal`][rainuav.signals.Signal] (one world, instant and level), bit for
        bit, with its serving cells and not-flyable pixels.

        Args:
            signal: "sinr" or "sir".
            scenario_toml: Carry the scenario as TOML.

        Returns:
            The signal.

        Raises:
            InvalidInputError: An unknown signal, or one the map does not hold.
        """
        name = signal_name(signal)
        if getattr(self, name) is None:  # e.g. a map object of a release without a noise model
            raise InvalidInputError(
                f"signal={signal!r}: the map has no {name} (rebuild it with this version)"
            )
        nf = None if self.not_flyable is None else self.not_flyable[None]
        return Signal.from_axes(getattr(self, name), ("north", "east"), self.extent_m,
                                altitudes_m=[self.altitude_m], serving_cell=self.serving_cell,
                                name=name, not_flyable=nf,
                                scenario_toml=toml_of(self.scenario, scenario_toml))  # fmt: skip

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Writes the map as an .npz file, atomically.

        The arrays go in as arrays and the scenario as TOML text, so the file is data (no pickles).

        Args:
            path: The file to write.

        Returns:
            The path written.
        """
        arrays = {k: getattr(self, k) for k in self._ARRAYS}
        arrays["extent_m"] = np.asarray(self.extent_m, dtype=np.float64)
        arrays["altitude_m"] = np.float64(self.altitude_m)
        if self.not_flyable is not None:
            arrays["not_flyable"] = np.asarray(self.not_flyable, dtype=bool)
        for k in self._MEASURED:
            if getattr(self, k) is not None:
                arrays[k] = np.asarray(getattr(self, k), dtype=np.float64)
        if self.fit is not None:
            arrays["fit_json"] = np.asarray(json.dumps(self.fit))
        return write_npz(path, arrays, self.scenario, FORMAT_VERSION)

    @classmethod
    def load(
        cls, path: str | os.PathLike[str], known: tuple[str, Scenario] | None = None
    ) -> RadioMap:
        """Reads a map written by [`save()`][rainuav.radio.outputs.mapdata.RadioMap.save], checked.

        The round trip is bit-exact.

        Args:
            path: The .npz file.
            known: `(digest, scenario)` the caller looked the file up by (a cache hit): where the
                file's digest is that one, the map carries the caller's scenario, never the stored
                one (whose DEM or footprint file may have moved since: the key is their contents).

        Returns:
            The [`RadioMap`][rainuav.radio.outputs.mapdata.RadioMap].

        Raises:
            InvalidInputError: A file that is missing, not a radio map, of another format version,
                or whose arrays have the wrong shapes or values out of range.
        """
        need = (*cls._ARRAYS, "extent_m", "altitude_m")
        data, scn = read_npz(path, "radio map", need, FORMAT_VERSION, known)
        if data["extent_m"].shape != (4,):
            raise InvalidInputError(f"{path}: not a rainuav radio map (bad metadata)")
        check_map_arrays(path, data, scn)
        mask = data.get("not_flyable")
        if mask is not None and (mask.shape != scn.area.shape or mask.dtype != bool):
            raise InvalidInputError(
                f"{path}: not_flyable must be a bool array of shape {scn.area.shape}"
            )
        ext = tuple(float(v) for v in data["extent_m"])
        shape = data["rss_dbm"].shape
        extra = {k: data[k] for k in cls._MEASURED if k in data}
        ranges = {"prior_rss_dbm": (RSS_FLOOR_DBM, 100.0), "rss_std_db": (0.0, 200.0),
                  "rss_sample_std_db": (0.0, 200.0)}  # fmt: skip
        check_arrays(path, extra | {k: data[k] for k in ("x_m", "y_m")}, scn,
                     {k: shape for k in extra}, {k: ranges[k] for k in extra})  # fmt: skip
        fit = _fit_of(path, data.get("fit_json"))
        return cls(
            x_m=data["x_m"],
            y_m=data["y_m"],
            extent_m=ext,  # type: ignore[arg-type]
            altitude_m=float(data["altitude_m"]),
            rss_dbm=data["rss_dbm"],
            serving_cell=data["serving_cell"],
            sir_db=data["sir_db"],
            sinr_db=data["sinr_db"],
            scenario=scn,
            cell_site=data["cell_site"],
            pe_share=data["pe_share"],
            pe_cone_deg=data["pe_cone_deg"],
            not_flyable=mask,
            fit=fit,
            **extra,
        )

    def plot(self, kind: str = "sir", cell: int | None = None, ax: Any = None) -> Any:
        """Draws the map in dB with the sites marked.

        Args:
            kind: "sir", "sinr" or "rss".
            cell: With "rss", the one cell to draw; None: the strongest cell at each pixel.
            ax: A matplotlib Axes to draw on; None: a new figure.

        Returns:
            The matplotlib Axes ([`plot_map()`][rainuav.radio.outputs.plot.plot_map]).
        """
        return plot_map(self, kind, cell, ax)

    def coverage(self, sir_min_db: float = 10.0) -> float:
        """The share of the area where the SIR reaches a threshold.

        Args:
            sir_min_db: The threshold, dB.

        Returns:
            The share of pixels with SIR >= `sir_min_db`, in [0, 1].
        """
        return float(np.mean(self.sir_db >= sir_min_db))


def default_min_db(scenario_name: str, signal: str = "sinr") -> float:
    """The outage threshold of a task on a signal over a map of a named scenario.

    Args:
        scenario_name: The scenario's name.
        signal: "sinr" or "sir".

    Returns:
        dB ([`RadioMap.default_min_db()`][rainuav.radio.outputs.mapdata.RadioMap.default_min_db]).
    """
    if signal == "sinr":
        return SINR_THRESHOLDS_DB.get(scenario_name, DEFAULT_MIN_DB)
    return DEFAULT_MIN_DB


def _fit_of(path: Any, raw: np.ndarray | None) -> dict[str, Any] | None:
    if raw is None:
        return None
    try:
        fit = json.loads(str(raw)) if raw.dtype.kind == "U" else None
    except (json.JSONDecodeError, RecursionError):  # not JSON, or nested deeper than a fit
        fit = None
    if not isinstance(fit, dict):
        raise InvalidInputError(f"{path}: fit_json is not a JSON object")
    return fit


def write_npz(
    path: str | os.PathLike[str], arrays: dict[str, Any], scn: Scenario, version: int
) -> Path:
    """Writes arrays, a scenario as TOML and a format version as one .npz (no pickles), atomically.

    How maps and map series are saved.

    Args:
        path: The file.
        arrays: The arrays by name.
        scn: The scenario.
        version: The file's format version.

    Returns:
        The path written.
    """
    meta = {
        "format_version": np.int64(version),
        "scenario_toml": np.asarray(scn.to_toml_string()),
        "digest": np.asarray(scn.digest()),
    }

    def write(tmp: Path) -> None:
        with tmp.open("wb") as fh:
            np.savez(fh, **arrays, **meta)

    return write_atomic(path, write)


def read_npz(
    path: str | os.PathLike[str],
    what: str,
    need: Iterable[str],
    version: int,
    known: tuple[str, Scenario] | None = None,
) -> tuple[dict[str, np.ndarray], Scenario]:
    """The arrays and the scenario of an .npz written by `write_npz()`, never unpickled.

    Args:
        path: The file.
        what: The kind of file, for the messages.
        need: The arrays it must hold.
        version: The format version this rainuav reads.
        known: `(digest, scenario)` the caller looked the file up by (the map cache): where the
            file's stored digest is that one, its scenario is that scenario and its TOML is not
            parsed again (seconds for a radar weather's rate maps).

    Returns:
        `(arrays, scenario)`.

    Raises:
        InvalidInputError: A file unreadable, missing an array of `need`, of another format version,
            or with a scenario that is not valid (named).
    """
    data = read_arrays(path, what)
    missing = {*need, "scenario_toml"} - set(data)
    if missing:
        raise InvalidInputError(f"{path}: not a rainuav {what} (missing {sorted(missing)})")
    v = data.get("format_version", np.array(-1))
    if v.shape != () or not np.issubdtype(v.dtype, np.integer):
        raise InvalidInputError(f"{path}: not a rainuav {what} (no format_version)")
    if int(v) != version:
        raise InvalidInputError(f"{path}: {what} format {int(v)}, this rainuav reads {version}")
    if data["scenario_toml"].dtype.kind != "U":
        raise InvalidInputError(f"{path}: not a rainuav {what} (bad metadata)")
    stored = data.get("digest")
    if known is not None and stored is not None and stored.dtype.kind == "U":
        if str(stored) == known[0]:
            return data, known[1]
    try:
        scn = Scenario.from_toml_string(str(data["scenario_toml"]))
    except InvalidInputError as err:
        raise InvalidInputError(f"{path}: its scenario is not valid ({err})") from err
    return data, scn


def store(rm: Any, path: Path) -> None:
    """Keeps a map (or a map series: anything with `save`) in the cache.

    A cache that cannot be written is a [`CacheWarning`][rainuav.errors.CacheWarning]: the map is
    the caller's all the same.

    Args:
        rm: The map.
        path: Its cache file.
    """
    try:
        rm.save(path)
    except OSError as err:
        warnings.warn(
            f"radio-map cache {cache_dir()} cannot be written ({err.strerror or err}); the map "
            "is not kept for next time (set RAINUAV_CACHE_DIR to a writable folder)",
            CacheWarning,
            stacklevel=3,
        )
