"""The signal field the UAV flies through, sampled as the planners sample it.

Pixel-centred bilinear sampling of a map in dB (SINR or SIR, `rainuav._sampling`), with its input
checked once ([`rainuav.nav.fieldinput`][rainuav.nav.fieldinput]), and the serving cell at the
nearest pixel when the map names one. One class, [`SignalField`][rainuav.nav.field.SignalField],
over worlds x instants x levels x north x east (``field(x, y, t_s, world, level=...)``,
``field.serving_cell(x, y, t_s, level)``, ``field.varies``, ``field.altitudes_m``): one map (time
is ignored), maps at instants ``t_s`` (a storm that moves), linear in time between them, or a
bank of worlds, on one level or among flight levels. The exact planners
(``rainuav_core::planning::planlevels``) read it operation for operation as ``SignalField.__call__``
does."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav._sampling import bilinear, in_time
from rainuav.errors import InvalidInputError
from rainuav.nav.fieldinput import (
    checked_altitudes,
    checked_mask,
    checked_probability,
    checked_values,
    pixel_index,
)

__all__ = [
    "SignalBank",
    "SignalField",
    "SignalSeries",
    "SirField",
    "blocked_at",
    "field_digest",
    "pixel_index",
    "read_signal",
]


def blocked_at(field: Any, x: Any, y: Any) -> np.ndarray:
    """Whether the pixel holding each point ``(x, y)`` may not be entered (on the lowest level).

    The field's ``not_flyable`` mask; False everywhere without one."""
    return field.blocked(x, y, 0)


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
    """The signal in dB (SINR or SIR) the UAV flies through, whatever its axes.

    A map, maps in time, a bank of worlds, each on one level or on several flight levels. Over
    ``extent_m = (x_min, x_max, y_min, y_max)``, one class for every kind: ``values`` (P, K,
    L, H, W), P worlds' maps at the K instants ``t_s`` on the L levels at ``altitudes_m``. Bilinear
    in space within a slice (`rainuav._sampling.bilinear`), linear in time between the two
    slices around an instant, held before the first and after the last
    (``rainuav_core::planning::planlevels``' signal in time, operation for operation); a point of a
    bank reads its own world, a point among levels its own level. Made by:

    - ``SignalField(values_db (H, W), extent_m, ...)``: one map (time is ignored);
    - [`SignalField.series`][rainuav.nav.field.SignalField.series]`(values_db (K, H, W), t_s,
      extent_m, ...)` (also `SignalSeries`): maps in time, a storm that moves;
    - [`SignalField.bank`][rainuav.nav.field.SignalField.bank]`(values_db (P, K, H, W), t_s,
      extent_m)` (also `SignalBank`): several worlds in one array, each point reading its own;
      the UAVs of one training batch fly different storms through one call, and a world's slot
      is replaced in place ([`put()`][rainuav.nav.field.SignalField.put]) when the learner moves
      on;
    - with ``altitudes_m`` (L,), each of these with a level axis before north and east (``(L,
      H, W)``, ``(K, L, H, W)``, ``(P, K, L, H, W)``): the flight levels, lowest first, a UAV
      flies among ([`from_stack()`][rainuav.nav.field.SignalField.from_stack]; a band of one
      level is flown with six moves as well).

    ``db`` is the values as given. ``name`` is the array's name in error messages;
    ``serving_cell`` (the shape of ``db``; maps and series) is read at the nearest pixel of the
    latest slice at or before the instant; ``not_flyable`` ((H, W), or (L, H, W) among levels)
    marks the pixels a UAV may not enter ([`blocked()`][rainuav.nav.field.SignalField.blocked]; a
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
        altitudes_m: npt.ArrayLike | None = None,
    ):
        """One map; with ``t_s``, maps in time; ``banked``: a bank (use the makers); with
        ``altitudes_m``, on those levels."""
        lv = "L, " if altitudes_m is not None else ""
        dims = f"(P, K, {lv}H, W)" if banked else f"({lv}H, W)" if t_s is None else f"(K, {lv}H, W)"
        self.db, self.extent, self.serving = checked_values(
            values_db, extent_m, name, serving_cell, dims
        )
        full = self.db if altitudes_m is not None else self.db[..., None, :, :]
        self.values = full.reshape((1,) * (5 - full.ndim) + full.shape)
        self._map = self.values[0, 0, 0] if self.values.shape[:3] == (1, 1, 1) else None
        _, k, nl, h, w = self.values.shape
        self.altitudes_m = None if altitudes_m is None else checked_altitudes(altitudes_m, nl)
        """The levels' altitudes, m, lowest first; None: the plane of one level."""
        self.levels = nl
        """The levels (L; 1 for the plane)."""
        mask_shape = (h, w) if altitudes_m is None else (nl, h, w)
        self.not_flyable = checked_mask(not_flyable, mask_shape)
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
        self.outage_p = None if outage_p is None else checked_probability(outage_p, (h, w))
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
        altitudes_m: npt.ArrayLike | None = None,
        name: str = "sinr_db",
    ) -> SignalField:
        """Several worlds' signals, ``values_db`` (P, K, H, W), or (P, K, L, H, W) on the levels
        ``altitudes_m``, at the common instants ``t_s`` (K,) over one extent, each read as its
        own series (a one-instant bank is P still maps; flat open ground: no pixel closed)."""
        return cls(values_db, extent_m, name, t_s=t_s, banked=True, altitudes_m=altitudes_m)

    @classmethod
    def from_stack(
        cls,
        signal_db: npt.ArrayLike,
        altitudes_m: npt.ArrayLike,
        extent_m: tuple[float, float, float, float],
        *,
        t_s: npt.ArrayLike | None = None,
        not_flyable: npt.ArrayLike | None = None,
        serving_cell: npt.ArrayLike | None = None,
    ) -> SignalField:
        """The levels at ``altitudes_m`` from a stack (L, H, W), or (T, L, H, W) at the instants
        ``t_s``; ``not_flyable`` (L, H, W) and ``serving_cell`` (the stack's shape) optional."""
        sig = np.asarray(signal_db, dtype=np.float64)
        if sig.ndim not in (3, 4):
            raise InvalidInputError(
                f"signal_db must be (L, H, W) or (T, L, H, W) (got {sig.shape})"
            )
        if (sig.ndim == 4) != (t_s is not None):
            raise InvalidInputError("t_s goes with a (T, L, H, W) stack, and only with one")
        return cls(sig, extent_m, "sinr_db", serving_cell, not_flyable, t_s=t_s,
                   altitudes_m=altitudes_m)  # fmt: skip

    @classmethod
    def of_levels(cls, fields: Sequence[SignalField], altitudes_m: npt.ArrayLike) -> SignalField:
        """The levels at ``altitudes_m`` from one field a level (all of one kind, over one
        area; a copy)."""
        if not fields or not all(
            isinstance(f, SignalField) and f.altitudes_m is None for f in fields
        ):
            raise InvalidInputError("fields must be SignalFields of one level each")
        if len({(f.banked, f.varies) for f in fields}) != 1:
            raise InvalidInputError(
                "fields must be all maps, all maps in time (SignalSeries) or all banks (SignalBank)"
            )
        if len({f.db.shape for f in fields}) != 1 or len({f.t_s.tobytes() for f in fields}) != 1:
            raise InvalidInputError(
                "the levels' fields must hold as many worlds and instants, of one size"
            )
        if len({f.extent for f in fields}) != 1:
            raise InvalidInputError("the levels' fields must cover one area (one extent)")
        f0 = fields[0]
        axis = f0.db.ndim - 2
        stack = np.stack([f.db for f in fields], axis=axis)
        masks = [f.not_flyable for f in fields]
        mask = (
            None
            if all(m is None for m in masks)
            else np.stack([np.zeros(f0.db.shape[-2:], bool) if m is None else m for m in masks])
        )
        servings = [f.serving for f in fields]
        serving = None if any(s is None for s in servings) else np.stack(servings, axis=axis)
        return cls(stack, f0.extent, f0.name, serving, mask, t_s=f0.t_s if f0.varies or
                   f0.banked else None, banked=f0.banked, altitudes_m=altitudes_m)  # fmt: skip

    @property
    def worlds(self) -> int:
        """Worlds held (P)."""
        return self.values.shape[0]

    def put(self, world: int, values_db: npt.ArrayLike) -> None:
        """Replaces world ``world``'s maps ((K, H, W), among levels (K, L, H, W)) of a bank
        (checked: the bank's shape, finite)."""
        if not self.banked:
            raise InvalidInputError("put renews a world of a bank (SignalField.bank) only")
        v = np.asarray(values_db, dtype=np.float64)
        if v.shape != self.db.shape[1:] or not np.all(np.isfinite(v)):
            raise InvalidInputError(
                f"{self.name} must be finite, of shape {self.db.shape[1:]} (got {v.shape})"
            )
        self.db[world] = v
        self._points = _PointCache()  # samples of the old storm are stale

    def member(self, world: int) -> SignalField:
        """World ``world``'s signal on its own (a copy)."""
        v = self.db[world].copy()
        t_s = None if not self.varies else self.t_s
        return SignalField(v[0] if t_s is None else v, self.extent, self.name, t_s=t_s,
                           altitudes_m=self.altitudes_m)  # fmt: skip

    def level(self, k: int) -> SignalField:
        """Level ``k``'s signal as a field of one level (a copy)."""
        if self.altitudes_m is None:
            return self
        axis = self.db.ndim - 3
        pick = (slice(None),) * axis + (k,)
        serving = None if self.serving is None else self.serving[pick]
        mask = None if self.not_flyable is None else self.not_flyable[k]
        t_s = self.t_s if self.varies or self.banked else None
        return SignalField(self.db[pick].copy(), self.extent, self.name, serving, mask,
                           t_s=t_s, banked=self.banked)  # fmt: skip

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

    def __call__(self, x: Any, y: Any, t_s: Any = 0.0, world: Any = None, level: Any = None) -> Any:
        """The signal at the points ``(x, y)`` at the instants ``t_s`` (a number, or one per
        point; a map ignores it), of world ``world`` (one per point, or one; default 0), on
        ``level`` (among levels; one per point, or one; default 0)."""
        if self._map is not None:  # one map
            return bilinear(self._map, self.extent, x, y)
        x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        flat = self.values.reshape(-1, *self.values.shape[3:])
        out = in_time(flat, self.extent, x, y, *self._rows(t_s, world, level))
        return out[()] if out.ndim == 0 else out

    def _rows(self, t_s: Any, world: Any, level: Any = None) -> tuple[Any, Any, np.ndarray]:
        """[`brackets()`][rainuav.nav.field.SignalField.brackets] of ``t_s`` as rows of the
        slices stacked (world ``w``'s slice ``k`` on level ``l`` is row ``(w K + k) L + l``;
        default world and level 0)."""
        k0, k1, f = self.brackets(t_s)
        _, kk, nl = self.values.shape[:3]
        if world is not None:
            base = np.asarray(world, dtype=np.int64) * kk
            k0, k1 = base + k0, base + k1
        if nl > 1:
            lv = 0 if level is None else np.asarray(level, dtype=np.int64)
            k0, k1 = k0 * nl + lv, k1 * nl + lv
        return k0, k1, f

    def chance(self, x: Any, y: Any, t_s: Any = None) -> Any:
        """The probability of outage at the points ``(x, y)``, bilinear as the map (the task's
        ``"chance"`` reward); needs ``outage_p``."""
        if self.outage_p is None:
            raise InvalidInputError(
                "reward 'chance' needs a field with outage_p (a map corrected by measurements, "
                "through rainuav.world.world_from)"
            )
        return bilinear(self.outage_p, self.extent, x, y)

    def serving_cell(self, x: Any, y: Any, t_s: Any = 0.0, level: Any = None) -> Any:
        """The serving cell at the pixel holding ``(x, y)`` in the latest slice at or before
        ``t_s`` (a number, or one per point; a map ignores it), on ``level`` (among levels;
        default 0); -1 where none is named."""
        among = self.altitudes_m is not None
        parts = [np.asarray(x), np.asarray(y)]
        if self.varies:
            parts.append(np.asarray(t_s))
        if among and level is not None:
            parts.append(np.asarray(level))
        shape = np.broadcast(*parts).shape
        if self.serving is None:
            return np.full(shape, -1, dtype=np.int64)
        i, j = pixel_index(self.db.shape, self.extent, x, y)
        at: tuple[Any, ...] = (i, j)
        if among:
            at = (np.broadcast_to(0 if level is None else level, shape), *at)
        if self.varies:
            k = np.searchsorted(self.t_s, np.broadcast_to(t_s, shape), side="right") - 1
            at = (np.maximum(k, 0), *at)
        return self.serving[at]

    def blocked(self, x: Any, y: Any, level: Any = 0) -> np.ndarray:
        """Whether the pixel holding ``(x, y)`` may not be entered (on ``level`` among levels)."""
        mask = self.not_flyable
        if mask is None:
            return np.zeros(np.broadcast(np.asarray(x), np.asarray(y)).shape, dtype=bool)
        i, j = pixel_index(mask.shape, self.extent, x, y)
        if mask.ndim == 2:
            return mask[i, j]
        return mask[np.broadcast_to(level, np.broadcast(i, j, np.asarray(level)).shape), i, j]

    def flyable(self, x: float, y: float) -> np.ndarray:
        """(L,) bool: the levels a UAV may fly at over ``(x, y)``."""
        every = np.arange(self.levels)
        return ~self.blocked(np.full(self.levels, x), np.full(self.levels, y), every)

    def frozen(self, t_s: float = 0.0) -> SignalField:
        """The weather of ``t_s`` held still: the one map the signal gives at that instant
        (what a tool that ignores the storm's motion plans on; a map: itself)."""
        if self.banked:
            raise InvalidInputError("frozen: a bank holds several worlds; take one (member)")
        if not self.varies:
            return self
        k0, k1, f = (int(a) if a.dtype.kind == "i" else float(a) for a in self.brackets(t_s))
        v = self.db[k0] if k0 == k1 else (1.0 - f) * self.db[k0] + f * self.db[k1]
        return SignalField(v, self.extent, self.name, not_flyable=self.not_flyable,
                           altitudes_m=self.altitudes_m)  # fmt: skip

    def at_points(self, points: np.ndarray, t_s: Any, world: Any = None) -> np.ndarray:
        """(N, M), among levels (N, L, M): the signal at the fixed points (M, 2) at each of the
        N instants ``t_s`` (of world ``world[n]``), as `__call__` gives it; every slice is sampled
        once per set of points (until [`put()`][rainuav.nav.field.SignalField.put])."""
        g = self._points.get(self.values, self.extent, np.asarray(points, dtype=np.float64))
        g = g.reshape(-1, g.shape[-1])
        n = np.size(t_s)
        if self.altitudes_m is None:
            if len(g) == 1:
                return np.broadcast_to(g[0], (n, g.shape[-1]))
            return _lerp(g, *self._rows(np.atleast_1d(t_s), world))
        t = np.atleast_1d(t_s)
        return np.stack(
            [
                _lerp(g, *self._rows(t, 0 if world is None else world, k))
                for k in range(self.levels)
            ],
            axis=1,
        )


SignalSeries = SignalField.series
"""Maps in time: [`SignalField.series`][rainuav.nav.field.SignalField.series]."""

SignalBank = SignalField.bank
"""A bank of worlds: [`SignalField.bank`][rainuav.nav.field.SignalField.bank]."""

SirField = SignalField
"""The old name (the field is whichever signal the task flies on)."""


def field_digest(field: SignalField) -> str:
    """A digest of what a field flies (its values, area, instants, levels and closed pixels):
    a run records it, so that a map swapped into its folder is refused, not flown."""
    import hashlib

    h = hashlib.sha256()
    levels = [] if field.altitudes_m is None else field.altitudes_m
    closed = [] if field.not_flyable is None else field.not_flyable
    extent = np.asarray(field.extent, dtype=np.float64)
    for a in (field.values, extent, field.t_s, np.asarray(levels, np.float64),
              np.asarray(closed, bool)):  # fmt: skip
        arr = np.ascontiguousarray(a)
        h.update(str((arr.dtype.str, arr.shape)).encode())
        h.update(arr.tobytes())
    return h.hexdigest()
