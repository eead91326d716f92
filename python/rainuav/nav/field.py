"""The signal field the UAV flies through: pixel-centred bilinear sampling of a map in dB (SINR
or SIR, `rainuav._sampling`), with its input checked once, and the serving cell at the
nearest pixel when the map names one.

One class, [`SignalField`][rainuav.nav.field.SignalField], over worlds x instants x north x
east (``field(x, y, t_s, world)``, ``field.serving_cell(x, y, t_s)``, ``field.varies``): one map
(time is ignored), maps at instants ``t_s`` (a storm that moves), linear in time between them, or
a bank of worlds. The exact planner in space-time (``rainuav_core::planlevels``) reads the series
operation for operation as ``SignalField.__call__`` does."""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav._sampling import bilinear, in_time
from rainuav.errors import InvalidInputError
from rainuav.nav.task import SIGNALS

__all__ = [
    "SignalBank",
    "SignalField",
    "SignalSeries",
    "SirField",
    "blocked_at",
    "pixel_index",
    "read_signal",
    "signal_field",
]


def _checked(
    values_db: npt.ArrayLike,
    extent_m: Any,
    name: str,
    serving_cell: npt.ArrayLike | None,
    dims: str,
) -> tuple[np.ndarray, tuple[float, float, float, float], np.ndarray | None]:
    """The values (``dims``: ``"(H, W)"`` or ``"(K, H, W)"``), finite; the extent; the
    serving cells of the same shape, if given. Anything else: one line naming the field."""
    ndim = dims.count(",") + 1
    v = np.asarray(values_db, dtype=np.float64)
    if v.ndim != ndim or min(v.shape) < 1:
        raise InvalidInputError(f"{name} must be a {ndim}-D {dims} array (got shape {v.shape})")
    if not np.all(np.isfinite(v)):
        raise InvalidInputError(f"{name} must be finite everywhere (no NaN or inf)")
    e = np.asarray(extent_m, dtype=np.float64)
    if e.shape != (4,) or not np.all(np.isfinite(e)):
        raise InvalidInputError(f"extent_m must be (x_min, x_max, y_min, y_max) (got {extent_m!r})")
    if not (e[1] > e[0] and e[3] > e[2]):
        raise InvalidInputError(
            f"extent_m must have x_max > x_min and y_max > y_min (got {extent_m!r})"
        )
    serving = None
    if serving_cell is not None:
        sv = np.asarray(serving_cell)
        if sv.shape != v.shape:
            raise InvalidInputError(
                f"serving_cell must have the shape of {name}, {v.shape} (got {sv.shape})"
            )
        serving = sv.astype(np.int64)
    extent = (float(e[0]), float(e[1]), float(e[2]), float(e[3]))
    return np.ascontiguousarray(v), extent, serving


def pixel_index(
    shape: tuple[int, ...], extent: tuple[float, ...], x: Any, y: Any
) -> tuple[Any, Any]:
    """The (row, column) of the pixel holding each point ``(x, y)`` (clamped to the map)."""
    x0, x1, y0, y1 = extent
    h, w = shape[-2:]
    j = np.clip(np.floor((np.asarray(x, dtype=np.float64) - x0) / (x1 - x0) * w), 0, w - 1)
    i = np.clip(np.floor((np.asarray(y, dtype=np.float64) - y0) / (y1 - y0) * h), 0, h - 1)
    return i.astype(np.int64), j.astype(np.int64)


def _checked_probability(p: Any, shape: tuple[int, int]) -> np.ndarray:
    """``p`` as a read-only (H, W) float array of probabilities in [0, 1]."""
    a = np.asarray(p, dtype=np.float64)
    if a.shape != shape or not np.all((a >= 0) & (a <= 1)):
        raise InvalidInputError(
            f"outage_p must be a (H, W) = {shape} array of probabilities in [0, 1] (got {a.shape})"
        )
    a = np.ascontiguousarray(a)
    a.flags.writeable = False
    return a


def _checked_mask(mask: Any, shape: tuple[int, int]) -> np.ndarray | None:
    """``mask`` as a read-only (H, W) bool array of the map's pixels, or None."""
    if mask is None:
        return None
    m = np.asarray(mask)
    if m.shape != shape or m.dtype.kind not in "bui":
        raise InvalidInputError(
            f"not_flyable must be a (H, W) = {shape} bool array (got {m.shape})"
        )
    m = np.ascontiguousarray(m.astype(bool))
    m.flags.writeable = False
    return m


def blocked_at(field: Any, x: Any, y: Any) -> np.ndarray:
    """Whether the pixel holding each point ``(x, y)`` may not be entered.

    The field's ``not_flyable`` mask; False everywhere without one."""
    mask = getattr(field, "not_flyable", None)
    if mask is None:
        return np.zeros(np.broadcast(np.asarray(x), np.asarray(y)).shape, dtype=bool)
    return mask[pixel_index(mask.shape, field.extent, x, y)]


def read_signal(field: Any, x: Any, y: Any, t_s: Any, world: Any = None) -> Any:
    """The signal of ``field`` at ``(x, y)`` at ``t_s``, in a bank of world ``world``.

    ``field``: a map, maps in time or a bank (``world`` default 0)."""
    return field(x, y, t_s, world)


def _lerp(g: np.ndarray, k0: np.ndarray, k1: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Rows ``g[k0]`` and ``g[k1]`` mixed by ``f`` per row, as the fields mix slices."""
    out = g[k0]  # a copy; the rows between two slices are mixed in place
    mix = k0 != k1
    if mix.any():
        fm = f[mix][:, None]
        out[mix] = (1.0 - fm) * out[mix] + fm * g[k1[mix]]
    return out


class _PointCache:
    """Samples of every slice at fixed points (a UAV's whole-area grid), kept per points."""

    def __init__(self) -> None:
        self.rows: dict[bytes, np.ndarray] = {}

    def get(self, db: np.ndarray, extent: Any, points: np.ndarray) -> np.ndarray:
        key = points.tobytes()
        if key not in self.rows:
            k = np.arange(int(np.prod(db.shape[:-2])))[:, None]
            flat = db.reshape(-1, *db.shape[-2:])
            vals = bilinear(flat, extent, points[:, 0], points[:, 1], k)
            self.rows[key] = vals.reshape(*db.shape[:-2], len(points))
        return self.rows[key]


class SignalField:
    """One level's signal in dB (SINR or SIR): a map, maps in time or a bank of worlds.

    Over ``extent_m = (x_min, x_max, y_min, y_max)``, one class for every kind: ``values`` (P, K,
    H, W), P worlds' maps at the K instants ``t_s``. Bilinear
    in space within a slice (`rainuav._sampling.bilinear`), linear in time between the two
    slices around an instant, held before the first and after the last
    (``rainuav_core::planlevels``' signal in time, operation for operation); a point of a bank
    reads its own world. Made by:

    - ``SignalField(values_db (H, W), extent_m, ...)``: one map (time is ignored);
    - [`SignalField.series`][rainuav.nav.field.SignalField.series]`(values_db (K, H, W), t_s,
      extent_m, ...)` (also `SignalSeries`): maps in time, a storm that moves;
    - [`SignalField.bank`][rainuav.nav.field.SignalField.bank]`(values_db (P, K, H, W), t_s,
      extent_m)` (also `SignalBank`): several worlds in one array, each point reading its own;
      the UAVs of one training batch fly different storms through one call, and a world's slot
      is replaced in place ([`put()`][rainuav.nav.field.SignalField.put]) when the learner moves
      on.

    ``db`` is the values as given (``(H, W)``, ``(K, H, W)`` or ``(P, K, H, W)``). ``name`` is
    the array's name in error messages; ``serving_cell`` (the shape of ``db``; maps and series)
    is read at the nearest pixel of the latest slice at or before the instant; ``not_flyable``
    (H, W) marks the pixels a UAV may not enter ([`blocked_at()`][rainuav.nav.field.blocked_at]; a
    bank flies over open ground); ``outage_p`` (H, W, one map) the chance of outage."""

    def __init__(
        self,
        values_db: npt.ArrayLike,
        extent_m: tuple[float, float, float, float],
        name: str = "sinr_db",
        serving_cell: npt.ArrayLike | None = None,
        not_flyable: npt.ArrayLike | None = None,
        outage_p: npt.ArrayLike | None = None,
        *,
        t_s: npt.ArrayLike | None = None,
        banked: bool = False,
    ):
        """One map; with ``t_s``, maps in time; ``banked``: a bank (use the two makers)."""
        dims = "(P, K, H, W)" if banked else "(H, W)" if t_s is None else "(K, H, W)"
        self.db, self.extent, self.serving = _checked(values_db, extent_m, name, serving_cell, dims)
        self.values = self.db.reshape((1,) * (4 - self.db.ndim) + self.db.shape)
        self._map = self.values[0, 0] if self.values.shape[:2] == (1, 1) else None
        _, k, h, w = self.values.shape
        self.not_flyable = _checked_mask(not_flyable, (h, w))
        t = np.zeros(1) if t_s is None else np.asarray(t_s, dtype=np.float64)
        if t.shape != (k,) or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
            raise InvalidInputError(
                f"t_s must be {k} finite, strictly increasing instants (got {t.shape})"
            )
        self.t_s = np.ascontiguousarray(t)
        self.name = name
        self.banked = banked
        self.varies = k > 1
        """Whether the signal changes in time."""
        self.outage_p = None if outage_p is None else _checked_probability(outage_p, (h, w))
        self._points = _PointCache()
        self._last_brackets: tuple[Any, tuple[np.ndarray, np.ndarray, np.ndarray]] | None = None

    @classmethod
    def series(
        cls,
        values_db: npt.ArrayLike,
        t_s: npt.ArrayLike,
        extent_m: tuple[float, float, float, float],
        name: str = "sinr_db",
        serving_cell: npt.ArrayLike | None = None,
        not_flyable: npt.ArrayLike | None = None,
    ) -> SignalField:
        """Maps ``values_db`` (K, H, W) at the instants ``t_s`` (K,), s, strictly increasing;
        ``serving_cell`` (K, H, W), optional."""
        return cls(values_db, extent_m, name, serving_cell, not_flyable, t_s=t_s)

    @classmethod
    def bank(
        cls,
        values_db: npt.ArrayLike,
        t_s: npt.ArrayLike,
        extent_m: tuple[float, float, float, float],
        name: str = "sinr_db",
    ) -> SignalField:
        """Several worlds' signals, ``values_db`` (P, K, H, W), at the common instants ``t_s``
        (K,) over one extent, each read as its own series (a one-instant bank is P still maps)."""
        return cls(values_db, extent_m, name, t_s=t_s, banked=True)

    @property
    def worlds(self) -> int:
        """Worlds held (P)."""
        return self.values.shape[0]

    def put(self, world: int, values_db: npt.ArrayLike) -> None:
        """Replaces world ``world``'s maps (K, H, W) of a bank (checked: the bank's shape,
        finite)."""
        if not self.banked:
            raise InvalidInputError("put renews a world of a bank (SignalField.bank) only")
        v = np.asarray(values_db, dtype=np.float64)
        if v.shape != self.values.shape[1:] or not np.all(np.isfinite(v)):
            raise InvalidInputError(
                f"{self.name} must be finite, of shape {self.values.shape[1:]} (got {v.shape})"
            )
        self.values[world] = v
        self._points = _PointCache()  # samples of the old storm are stale

    def member(self, world: int) -> SignalField:
        """World ``world``'s signal on its own (a copy)."""
        v = self.values[world]
        if v.shape[0] == 1:
            return SignalField(v[0].copy(), self.extent, self.name)
        return SignalField.series(v.copy(), self.t_s, self.extent, self.name)

    def brackets(self, tau: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """For each instant of ``tau``: the slices around it and the later one's weight
        ``(k0, k1, f)``; ``k0 == k1`` at a slice's own instant and beyond the first or the
        last (``Timeline::bracket``). Read-only arrays; the last instants' brackets are kept
        and given again (an observation asks for the same instants twice)."""
        tau = np.asarray(tau, dtype=np.float64)
        key = tau.tobytes()  # the instants, whatever their shape
        if self._last_brackets is not None and self._last_brackets[0] == key:
            k0, k1, f = self._last_brackets[1]
            return k0.reshape(tau.shape), k1.reshape(tau.shape), f.reshape(tau.shape)
        t = self.t_s
        k = np.searchsorted(t, tau, side="left")
        hit = (k < len(t)) & (t[np.minimum(k, len(t) - 1)] == tau)
        k1 = np.where(hit, k, np.clip(k, 0, len(t) - 1))
        k0 = np.where(hit | (k == 0), k1, np.where(k == len(t), len(t) - 1, k - 1))
        lo, hi = t[k0], t[k1]
        f = np.where(k0 == k1, 0.0, (tau - lo) / np.where(hi > lo, hi - lo, 1.0))
        for a in (k0, k1, f):
            a.setflags(write=False)  # shared with the next caller of the same instants
        self._last_brackets = (key, (k0, k1, f))
        return k0, k1, f

    def __call__(self, x: Any, y: Any, t_s: Any = 0.0, world: Any = None) -> Any:
        """The signal at the points ``(x, y)`` at the instants ``t_s`` (a number, or one per
        point; a map ignores it), of world ``world`` (one per point, or one; default 0)."""
        if self._map is not None:  # one map
            return bilinear(self._map, self.extent, x, y)
        x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        flat = self.values.reshape(-1, *self.values.shape[2:])
        out = in_time(flat, self.extent, x, y, *self._rows(t_s, world))
        return out[()] if out.ndim == 0 else out

    def _rows(self, t_s: Any, world: Any) -> tuple[Any, Any, np.ndarray]:
        """[`brackets()`][rainuav.nav.field.SignalField.brackets] of ``t_s`` as rows of the
        worlds' slices stacked (world ``w``'s slice ``k`` is row ``w K + k``; default world 0)."""
        k0, k1, f = self.brackets(t_s)
        if world is None:
            return k0, k1, f
        base = np.asarray(world, dtype=np.int64) * self.values.shape[1]
        return base + k0, base + k1, f

    def chance(self, x: Any, y: Any, t_s: Any = None) -> Any:
        """The probability of outage at the points ``(x, y)``, bilinear as the map (the task's
        ``"chance"`` reward); needs ``outage_p``."""
        if self.outage_p is None:
            raise InvalidInputError(
                "reward 'chance' needs a field with outage_p (a map corrected by measurements, "
                "through rainuav.world.world_from)"
            )
        return bilinear(self.outage_p, self.extent, x, y)

    def serving_cell(self, x: Any, y: Any, t_s: Any = 0.0) -> Any:
        """The serving cell at the pixel holding ``(x, y)`` in the latest slice at or before
        ``t_s`` (a number, or one per point; a map ignores it; -1 where none is named)."""
        if not self.varies:
            shape = np.broadcast(np.asarray(x), np.asarray(y)).shape
        else:
            shape = np.broadcast(np.asarray(x), np.asarray(y), np.asarray(t_s)).shape
        if self.serving is None:
            return np.full(shape, -1, dtype=np.int64)
        i, j = pixel_index(self.db.shape, self.extent, x, y)
        if not self.varies:
            return self.serving[i, j]
        k = np.searchsorted(self.t_s, np.broadcast_to(t_s, shape), side="right") - 1
        return self.serving[np.maximum(k, 0), i, j]

    def frozen(self, t_s: float = 0.0) -> SignalField:
        """The weather of ``t_s`` held still: the one map the signal gives at that instant
        (what a tool that ignores the storm's motion plans on; a map: itself)."""
        if self.banked:
            raise InvalidInputError("frozen: a bank holds several worlds; take one (member)")
        if not self.varies:
            return self
        k0, k1, f = (int(a) if a.dtype.kind == "i" else float(a) for a in self.brackets(t_s))
        v = self.db[k0] if k0 == k1 else (1.0 - f) * self.db[k0] + f * self.db[k1]
        return SignalField(v, self.extent, self.name, not_flyable=self.not_flyable)

    def at_points(self, points: np.ndarray, t_s: Any, world: Any = None) -> np.ndarray:
        """(N, M): the signal at the fixed points (M, 2) at each of the N instants ``t_s`` (of
        world ``world[n]``), as `__call__` gives it; every slice is sampled once per set of
        points (until [`put()`][rainuav.nav.field.SignalField.put])."""
        g = self._points.get(self.values, self.extent, np.asarray(points, dtype=np.float64))
        g = g.reshape(-1, g.shape[-1])
        if len(g) == 1:
            return np.broadcast_to(g[0], (np.size(t_s), g.shape[-1]))
        return _lerp(g, *self._rows(np.atleast_1d(t_s), world))


SignalSeries = SignalField.series
"""Maps in time: [`SignalField.series`][rainuav.nav.field.SignalField.series]."""

SignalBank = SignalField.bank
"""A bank of worlds: [`SignalField.bank`][rainuav.nav.field.SignalField.bank]."""

SirField = SignalField
"""The old name (the field is whichever signal the task flies on)."""


def signal_field(
    radio_map: Any, sinr_db: Any, sir_db: Any, extent_m: Any, signal: str | None
) -> SignalField:
    """The field a task flies on: the ``signal`` map of ``radio_map``, or the one raw array
    given (``sinr_db`` or ``sir_db``, which then names the signal)."""
    if signal is not None and signal not in SIGNALS:
        raise InvalidInputError(f"signal must be one of {SIGNALS} (got {signal!r})")
    raw = {k: v for k, v in (("sinr", sinr_db), ("sir", sir_db)) if v is not None}
    if radio_map is not None:
        if raw:
            raise InvalidInputError(f"give radio_map or {next(iter(raw))}_db, not both")
        signal = signal or "sinr"
        values = getattr(radio_map, f"{signal}_db", None)
        if values is None:
            raise InvalidInputError(
                f"signal={signal!r}: radio_map has no {signal}_db (rebuild it with this version)"
            )
        serving = getattr(radio_map, "serving_cell", None)
        mask = getattr(radio_map, "not_flyable", None)
        return SignalField(values, radio_map.extent_m, f"{signal}_db", serving, mask)
    if len(raw) != 1:
        raise InvalidInputError("give radio_map, or exactly one of sinr_db and sir_db")
    kind, values = next(iter(raw.items()))
    if signal is not None and signal != kind:
        raise InvalidInputError(f"signal={signal!r} but the map given is {kind}_db")
    if extent_m is None:
        raise InvalidInputError(f"extent_m is required with {kind}_db")
    return SignalField(values, extent_m, f"{kind}_db")
