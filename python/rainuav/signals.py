"""One signal with named axes: the maps a UAV flies through, whatever their dimensions.

A [`Signal`][rainuav.signals.Signal] holds one array of a signal in dB (SINR by default) over
the axes [`AXES`][rainuav.signals.AXES], ``(world, time, level, north, east)``, and what reading
it needs: the instants of the time axis, the altitudes of the level axis, the area, the
serving cell of every value and the pixels a UAV may not enter at each level. A plain map has
size 1 on the first three axes; maps in time (a storm that moves) have ``time > 1``; the maps of
every flight level have ``level > 1``; a bank of storms flown at once has ``world > 1``.

One file format holds any of them (``signal.npz``:
[`Signal.save()`][rainuav.signals.Signal.save], [`Signal.load()`][rainuav.signals.Signal.load]);
[`rainuav.radio.outputs.signals.load_signal()`][rainuav.radio.outputs.signals.load_signal] also
reads the three files the radio maps are saved in (``radiomap.npz``, ``radiomap_series.npz``,
``radiolevels.npz``), and [`rainuav.nav.levelfield.field_of()`][rainuav.nav.levelfield.field_of]
turns a signal into the field the environment and the planner read.

Files are data: read without pickles, every array checked (shapes, finite values, the axes'
order), a bad file refused in one line naming it and the field."""

from __future__ import annotations

import json
import os
import zipfile
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav._io import write_atomic
from rainuav.cellpowers import CellPowers
from rainuav.errors import InvalidInputError

__all__ = ["AXES", "FORMAT", "FORMAT_VERSION", "SIGNALS", "Signal", "signal_name", "toml_of"]

AXES = ("world", "time", "level", "north", "east")
"""The axes of every signal, in the order its array holds them."""
SIGNALS = ("sinr", "sir")
"""The signals a map holds and a task flies."""
FORMAT = "rainuav.signal"
"""What a signal file says it is (its ``format`` entry)."""
FORMAT_VERSION = 1
"""Version of the layout [`Signal.save()`][rainuav.signals.Signal.save] writes."""


def signal_name(signal: str) -> str:
    """The array name of a signal (``"sinr"`` -> ``"sinr_db"``), checked.

    Args:
        signal: One of [`SIGNALS`][rainuav.signals.SIGNALS].

    Returns:
        Its name with ``_db``.

    Raises:
        InvalidInputError: Another signal.
    """
    if signal not in SIGNALS:
        raise InvalidInputError(f"signal must be one of {SIGNALS} (got {signal!r})")
    return f"{signal}_db"


def toml_of(scenario: Any, keep: bool = True) -> str:
    """A scenario's TOML for a signal's ``scenario_toml`` ('' where none, or not kept).

    Args:
        scenario: A scenario (anything with ``to_toml_string()``), or None.
        keep: Carry it (a radar weather's TOML takes seconds to write: False leaves it out).

    Returns:
        The TOML, or ''.
    """
    return scenario.to_toml_string() if keep and scenario is not None else ""


def _extent(extent_m: Any) -> tuple[float, float, float, float]:
    e = np.asarray(extent_m, dtype=np.float64)
    if e.shape != (4,) or not np.all(np.isfinite(e)) or not (e[1] > e[0] and e[3] > e[2]):
        raise InvalidInputError(
            f"extent_m must be (x_min, x_max, y_min, y_max) with x_max > x_min and y_max > y_min "
            f"(got {extent_m!r})"
        )
    return (float(e[0]), float(e[1]), float(e[2]), float(e[3]))


def _axis(name: str, v: Any, n: int) -> np.ndarray:
    """The coordinates of an axis of size ``n``: finite, strictly increasing."""
    a = np.asarray(v, dtype=np.float64).reshape(-1)
    if a.shape != (n,) or not np.all(np.isfinite(a)) or np.any(np.diff(a) <= 0):
        raise InvalidInputError(
            f"{name} must be {n} finite, strictly increasing values (got shape {a.shape})"
        )
    a = np.ascontiguousarray(a)
    a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False)
class Signal:
    """A signal in dB over ``(world, time, level, north, east)``, checked when made.

    Anything out of shape or not finite is one line naming the field (module docs)."""

    values: npt.NDArray[np.floating]
    """(P, T, L, H, W), dB, finite: world, time, level, north (rows, south first), east."""
    extent_m: tuple[float, float, float, float]
    """(x_min, x_max, y_min, y_max), m: the area the pixels tile."""
    t_s: npt.NDArray[np.float64]
    """(T,) the instants of the time axis, s, strictly increasing (``[0.0]`` for one)."""
    altitudes_m: npt.NDArray[np.float64]
    """(L,) the altitudes of the level axis, m, strictly increasing."""
    name: str = "sinr_db"
    """Which signal: ``"sinr_db"`` or ``"sir_db"``."""
    serving_cell: npt.NDArray[np.integer] | None = None
    """The values' shape: the serving cell of each (-1: none); None: not known."""
    not_flyable: npt.NDArray[np.bool_] | None = None
    """(L, H, W): the pixels a UAV may not enter at each level; None: all open."""
    scenario_toml: str = ""
    """The scenario the signal was built from, as TOML ('' for none): metadata, never read
    back as code."""
    powers: CellPowers | None = None
    """Every cell's power and its two spreads over the same axes (what drawing the SINR needs:
    the ``"chance"`` reward); None: not carried."""

    def __post_init__(self) -> None:
        v = np.asarray(self.values)
        if v.ndim != len(AXES) or min(v.shape) < 1 or v.dtype.kind != "f":
            raise InvalidInputError(
                f"values must be a floating {len(AXES)}-D array over {AXES} (got {v.dtype} "
                f"of shape {v.shape})"
            )
        if not np.all(np.isfinite(v)):
            raise InvalidInputError("values must be finite everywhere (no NaN or inf)")
        if self.name not in ("sinr_db", "sir_db"):
            raise InvalidInputError(f"name must be 'sinr_db' or 'sir_db' (got {self.name!r})")
        _, t, lv, h, w = v.shape
        put = object.__setattr__  # frozen: the checked forms replace what was handed in
        put(self, "values", np.ascontiguousarray(v))
        put(self, "extent_m", _extent(self.extent_m))
        put(self, "t_s", _axis("t_s", self.t_s, t))
        put(self, "altitudes_m", _axis("altitudes_m", self.altitudes_m, lv))
        if self.serving_cell is not None:
            s = np.asarray(self.serving_cell)
            if s.shape != v.shape or s.dtype.kind not in "iu":
                raise InvalidInputError(
                    f"serving_cell must be an integer array of the values' shape {v.shape} "
                    f"(got {s.dtype} of shape {s.shape})"
                )
            put(self, "serving_cell", np.ascontiguousarray(s))
        if self.not_flyable is not None:
            m = np.asarray(self.not_flyable)
            if m.shape != (lv, h, w) or m.dtype != bool:
                raise InvalidInputError(
                    f"not_flyable must be a bool (level, north, east) = {(lv, h, w)} array "
                    f"(got {m.dtype} of shape {m.shape})"
                )
            put(self, "not_flyable", np.ascontiguousarray(m))
        if self.powers is not None:
            self.powers.fits(v.shape)

    @classmethod
    def from_axes(
        cls,
        values: npt.ArrayLike,
        dims: tuple[str, ...],
        extent_m: Any,
        *,
        t_s: npt.ArrayLike = (0.0,),
        altitudes_m: npt.ArrayLike = (0.0,),
        serving_cell: npt.ArrayLike | None = None,
        **meta: Any,
    ) -> Signal:
        """The signal of an array whose axes are named, in any order.

        The axes are moved into the signal's order and the axes it lacks added with size 1; e.g.
        `Signal.from_axes(sinr, ("level", "north", "east"), extent, altitudes_m=alts)`.

        Args:
            values: The signal, dB.
            dims: One name for each axis of `values`, each once, from [`AXES`][rainuav.signals.AXES]
                (`north` and `east` among them).
            extent_m: `(x_min, x_max, y_min, y_max)`, m.
            t_s: The instants of the time axis, s.
            altitudes_m: The altitudes of the level axis, m.
            serving_cell: The serving cell, with `values`' axes; None: none named.
            **meta: The signal's other fields (`name`, `scenario_toml`, ...).

        Returns:
            The [`Signal`][rainuav.signals.Signal].

        Raises:
            InvalidInputError: `dims` that do not name each axis once, or do not fit the array.
        """
        bad = [d for d in dims if d not in AXES]
        if bad or len(set(dims)) != len(dims) or not {"north", "east"} <= set(dims):
            raise InvalidInputError(
                f"dims must name each axis once, north and east among them, from {AXES} "
                f"(got {dims!r})"
            )

        def canonical(a: npt.ArrayLike, what: str) -> np.ndarray:
            arr = np.asarray(a)
            if arr.ndim != len(dims):
                raise InvalidInputError(
                    f"{what} must have one axis a name of dims {dims} (got shape {arr.shape})"
                )
            arr = np.transpose(arr, [dims.index(d) for d in AXES if d in dims])
            return np.expand_dims(arr, [k for k, d in enumerate(AXES) if d not in dims])

        v = canonical(values, "values")
        s = None if serving_cell is None else canonical(serving_cell, "serving_cell")
        return cls(v, extent_m, np.asarray(t_s, np.float64), np.asarray(altitudes_m, np.float64),
                   serving_cell=s, **meta)  # fmt: skip

    def as_signal(self, signal: str = "sinr", *, scenario_toml: bool = True) -> Signal:
        """This signal, where it is the one asked for: every map kind answers ``as_signal``.

        Args:
            signal: "sinr" or "sir".
            scenario_toml: Unused (the signal keeps its own).

        Returns:
            Itself.

        Raises:
            InvalidInputError: A signal of another name.
        """
        if self.name != signal_name(signal):
            raise InvalidInputError(f"the signal is {self.name}, not {signal_name(signal)}")
        return self

    @property
    def sizes(self) -> dict[str, int]:
        """Each axis's size, by name."""
        return dict(zip(AXES, self.values.shape, strict=True))

    def take(self, *, world: int | None = None, time: int | None = None,
             level: int | None = None) -> Signal:  # fmt: skip
        """The signal at one world, instant or level; each given index keeps its axis, with size 1.

        E.g. `take(level=0)`: the lowest level's signal.

        Args:
            world: The world's index.
            time: The instant's index.
            level: The level's index.

        Returns:
            A new [`Signal`][rainuav.signals.Signal].

        Raises:
            InvalidInputError: An index out of its axis.
        """
        idx: list[Any] = [slice(None)] * len(AXES)
        for k, (axis, i) in enumerate((("world", world), ("time", time), ("level", level))):
            if i is not None:
                n = self.values.shape[k]
                if not isinstance(i, int | np.integer) or not -n <= i < n:
                    raise InvalidInputError(f"{axis} must be an index in 0..{n - 1} (got {i!r})")
                idx[k] = slice(int(i) % n, int(i) % n + 1)
        at = tuple(idx)
        lv = at[2]
        return replace(
            self,
            values=self.values[at],
            t_s=self.t_s[at[1]],
            altitudes_m=self.altitudes_m[lv],
            serving_cell=None if self.serving_cell is None else self.serving_cell[at],
            not_flyable=None if self.not_flyable is None else self.not_flyable[lv],
            powers=None if self.powers is None else self.powers.take(at),
        )

    def to_xarray(self) -> Any:
        """The values as an `xarray.DataArray`, the axes named.

        Its coordinates are the instants, the altitudes and the pixels' centres in m.

        Returns:
            The `DataArray`.

        Raises:
            InvalidInputError: xarray is not installed (the `weather` extra).
        """
        try:
            import xarray as xr
        except ImportError as err:  # pragma: no cover - depends on the installed extras
            raise InvalidInputError(
                "to_xarray needs xarray: pip install 'rainuav[weather]'"
            ) from err
        p, _, _, h, w = self.values.shape
        x0, x1, y0, y1 = self.extent_m
        coords = {
            "world": np.arange(p),
            "time": self.t_s,
            "level": self.altitudes_m,
            "north": y0 + (np.arange(h) + 0.5) * (y1 - y0) / h,
            "east": x0 + (np.arange(w) + 0.5) * (x1 - x0) / w,
        }
        return xr.DataArray(self.values, coords=coords, dims=AXES, name=self.name)

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Writes the signal as one .npz (`signal.npz`; no pickles), atomically.

        Args:
            path: The file.

        Returns:
            The path written.
        """
        arrays: dict[str, Any] = {
            "values": self.values,
            "t_s": self.t_s,
            "altitudes_m": self.altitudes_m,
            "extent_m": np.asarray(self.extent_m, np.float64),
            "meta_json": np.asarray(json.dumps({
                "format": FORMAT, "format_version": FORMAT_VERSION, "axes": list(AXES),
                "name": self.name, "scenario_toml": self.scenario_toml,
            })),
        }  # fmt: skip
        if self.serving_cell is not None:
            arrays["serving_cell"] = self.serving_cell
        if self.not_flyable is not None:
            arrays["not_flyable"] = self.not_flyable
        if self.powers is not None:
            arrays |= self.powers.arrays()

        def write(tmp: Path) -> None:
            with tmp.open("wb") as fh:
                np.savez(fh, **arrays)

        return write_atomic(path, write)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> Signal:
        """Reads a file written by [`save()`][rainuav.signals.Signal.save], bit for bit.

        Args:
            path: The file.

        Returns:
            The [`Signal`][rainuav.signals.Signal], every array checked.

        Raises:
            InvalidInputError: A file that is not a signal file, of another format version, missing
                arrays or with arrays out of range (named).
        """
        data = read_arrays(path, "signal file")
        meta = _signal_meta(data)
        if meta is None:
            raise InvalidInputError(f"{path}: not a rainuav signal file (no {FORMAT} metadata)")
        if meta.get("format_version") != FORMAT_VERSION or meta.get("axes") != list(AXES):
            raise InvalidInputError(
                f"{path}: a signal file of format version {meta.get('format_version')!r} with "
                f"axes {meta.get('axes')!r}; this version reads {FORMAT_VERSION} with {AXES}"
            )
        missing = {"values", "t_s", "altitudes_m", "extent_m"} - set(data)
        if missing:
            raise InvalidInputError(
                f"{path}: not a rainuav signal file (missing {sorted(missing)})"
            )
        try:
            return cls(data["values"], data["extent_m"], data["t_s"], data["altitudes_m"],
                       str(meta.get("name", "")), data.get("serving_cell"),
                       data.get("not_flyable"), str(meta.get("scenario_toml", "")),
                       CellPowers.from_arrays(data))  # fmt: skip
        except InvalidInputError as err:
            raise InvalidInputError(f"{path}: {err}") from None


def _npz(path: str | os.PathLike[str], what: str, read: Callable[[Any], Any]) -> Any:
    """``read`` of the opened .npz (never unpickled), or one line naming the file (``what``:
    the kind of file, for the message)."""
    try:
        with np.load(path, allow_pickle=False) as z:
            return read(z)
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as err:
        raise InvalidInputError(f"{path}: not a readable {what} ({err})") from err


def read_arrays(path: str | os.PathLike[str], what: str) -> dict[str, np.ndarray]:
    """Every array of an .npz, read without pickles.

    Args:
        path: The file.
        what: What the error calls the file ("radio map", "signal").

    Returns:
        The arrays by name.

    Raises:
        InvalidInputError: A file that is missing or not a readable .npz (named).
    """
    return _npz(path, what, lambda z: {k: z[k] for k in z.files})


def array_names(path: str | os.PathLike[str], what: str) -> set[str]:
    """The names of an .npz's arrays, none of them read.

    Args:
        path: The file.
        what: What the error calls the file.

    Returns:
        The names.

    Raises:
        InvalidInputError: A file that is missing or not a readable .npz (named).
    """
    return _npz(path, what, lambda z: set(z.files))


def _signal_meta(data: dict[str, np.ndarray]) -> dict[str, Any] | None:
    """A signal file's metadata (its ``meta_json``), or None where the arrays are not one."""
    raw = data.get("meta_json")
    if raw is None or raw.dtype.kind != "U" or raw.ndim != 0:
        return None
    try:
        meta = json.loads(str(raw))
    except (json.JSONDecodeError, RecursionError):
        return None
    return meta if isinstance(meta, dict) and meta.get("format") == FORMAT else None
