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

from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav._sampling import PointCache, bilinear, in_time, lerp_rows
from rainuav.errors import InvalidInputError
from rainuav.nav.fieldinput import (
    checked_altitudes,
    checked_mask,
    checked_probability,
    checked_values,
    pixel_index,
)
from rainuav.nav.fieldmakers import FieldMakers

__all__ = [
    "SignalField",
    "field_digest",
    "pixel_index",
]


class SignalField(FieldMakers):
    """The signal in dB (SINR or SIR) the UAV flies through, whatever its axes.

    A map, maps in time, a bank of worlds, each on one level or on several flight levels. Over
    ``extent_m = (x_min, x_max, y_min, y_max)``, one class for every kind: ``values`` (P, K,
    L, H, W), P worlds' maps at the K instants ``t_s`` on the L levels at ``altitudes_m``. Bilinear
    in space within a slice (`rainuav._sampling.bilinear`), linear in time between the two
    slices around an instant, held before the first and after the last
    (``rainuav_core::planning::planlevels``' signal in time, operation for operation); a point of a
    bank reads its own world, a point among levels its own level. Made by the constructor (one
    map, time ignored) and by its makers: [`series()`][rainuav.nav.fieldmakers.FieldMakers.series]
    (maps in time, a storm that moves), [`bank()`][rainuav.nav.fieldmakers.FieldMakers.bank]
    (several worlds in one array, the storms of one training batch, each renewed in place by
    [`put()`][rainuav.nav.field.SignalField.put]), and among flight levels
    [`from_stack()`][rainuav.nav.fieldmakers.FieldMakers.from_stack] and
    [`of_levels()`][rainuav.nav.fieldmakers.FieldMakers.of_levels] (a level axis before north and
    east; a band of one level is flown with six moves as well).

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
        """One map; with `t_s`, maps in time; with `altitudes_m`, on those levels.

        Args:
            values_db: The signal, dB: (H, W); (K, H, W) with `t_s`; (P, K, H, W) banked; a level
                axis (L) before north and east with `altitudes_m`.
            extent_m: `(x_min, x_max, y_min, y_max)`, m.
            name: The array's name in error messages.
            serving_cell: The serving cell, of the shape of `values_db`, optional.
            not_flyable: The pixels a UAV may not enter, (H, W) or (L, H, W), optional.
            outage_p: The chance of outage (H, W), one map only, optional.
            t_s: The instants (K,), s, strictly increasing.
            banked: A bank of worlds (use [`bank()`][rainuav.nav.fieldmakers.FieldMakers.bank]).
            altitudes_m: The levels' altitudes (L,), m, lowest first.

        Raises:
            InvalidInputError: An array of the wrong shape or with values that are not finite,
                instants that do not increase, or altitudes that do not match the level axis.
        """
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
        self._points = PointCache()
        self._last_brackets: tuple[Any, tuple[np.ndarray, np.ndarray, np.ndarray]] | None = None

    @property
    def worlds(self) -> int:
        """Worlds held (P)."""
        return self.values.shape[0]

    def put(self, world: int, values_db: npt.ArrayLike) -> None:
        """Replaces one world of a bank, in place.

        Args:
            world: The world's index.
            values_db: Its maps, (K, H, W), among levels (K, L, H, W): finite, the bank's shape.

        Raises:
            InvalidInputError: A field that is not a bank, or maps of another shape or not finite.
        """
        if not self.banked:
            raise InvalidInputError("put renews a world of a bank (SignalField.bank) only")
        v = np.asarray(values_db, dtype=np.float64)
        if v.shape != self.db.shape[1:] or not np.all(np.isfinite(v)):
            raise InvalidInputError(
                f"{self.name} must be finite, of shape {self.db.shape[1:]} (got {v.shape})"
            )
        self.db[world] = v
        self._points = PointCache()  # samples of the old storm are stale

    def member(self, world: int) -> SignalField:
        """One world of a bank on its own (a copy).

        Args:
            world: The world's index.

        Returns:
            Its [`SignalField`][rainuav.nav.field.SignalField].
        """
        v = self.db[world].copy()
        t_s = None if not self.varies else self.t_s
        return SignalField(v[0] if t_s is None else v, self.extent, self.name, t_s=t_s,
                           altitudes_m=self.altitudes_m)  # fmt: skip

    def level(self, k: int) -> SignalField:
        """One level's signal as a field of one level (a copy).

        Args:
            k: The level's index.

        Returns:
            Its [`SignalField`][rainuav.nav.field.SignalField] (the field itself where it has one
            level).
        """
        if self.altitudes_m is None:
            return self
        axis = self.db.ndim - 3
        pick = (slice(None),) * axis + (k,)
        serving = None if self.serving is None else self.serving[pick]
        mask = None if self.not_flyable is None else self.not_flyable[k]
        t_s = self.t_s if self.varies or self.banked else None
        return SignalField(self.db[pick].copy(), self.extent, self.name, serving, mask,
                           t_s=t_s, banked=self.banked)  # fmt: skip

    def brackets(self, tau: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The slices around each instant and the later one's weight.

        `k0 == k1` at a slice's own instant and beyond the first or the last (the Rust core's
        `Timeline::bracket`). The last instants' brackets are kept and given again (an observation
        asks for the same instants twice).

        Args:
            tau: Instants, s (any shape).

        Returns:
            `(k0, k1, f)`, read-only arrays of the shape of `tau`.
        """
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

    def __call__(
        self,
        x: npt.ArrayLike,
        y: npt.ArrayLike,
        t_s: npt.ArrayLike = 0.0,
        world: npt.ArrayLike | None = None,
        level: npt.ArrayLike | None = None,
    ) -> Any:
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

    def chance(self, x: npt.ArrayLike, y: npt.ArrayLike, t_s: npt.ArrayLike | None = None) -> Any:
        """The probability of outage at points, bilinear as the map (the task's "chance" reward).

        Args:
            x: East, m.
            y: North, m.
            t_s: Ignored (one map).

        Returns:
            The probability, of the broadcast shape of `x` and `y`.

        Raises:
            InvalidInputError: The field has no `outage_p`.
        """
        if self.outage_p is None:
            raise InvalidInputError(
                "reward 'chance' needs a field with outage_p (a map corrected by measurements, "
                "through rainuav.world.world_from)"
            )
        return bilinear(self.outage_p, self.extent, x, y)

    def serving_cell(
        self,
        x: npt.ArrayLike,
        y: npt.ArrayLike,
        t_s: npt.ArrayLike = 0.0,
        level: npt.ArrayLike | None = None,
    ) -> Any:
        """The serving cell at the pixel holding each point, in the latest slice at or before the
        instant.

        Args:
            x: East, m.
            y: North, m.
            t_s: Time, s, a number or one per point (a map ignores it).
            level: The level among levels, one or one per point; None: 0.

        Returns:
            int64 of the points' shape; -1 where no cell is named.
        """
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

    def blocked(self, x: npt.ArrayLike, y: npt.ArrayLike, level: npt.ArrayLike = 0) -> np.ndarray:
        """Whether the pixel holding each point may not be entered.

        Args:
            x: East, m.
            y: North, m.
            level: The level among levels, one or one per point.

        Returns:
            bool, of the points' shape.
        """
        mask = self.not_flyable
        if mask is None:
            return np.zeros(np.broadcast(np.asarray(x), np.asarray(y)).shape, dtype=bool)
        i, j = pixel_index(mask.shape, self.extent, x, y)
        if mask.ndim == 2:
            return mask[i, j]
        return mask[np.broadcast_to(level, np.broadcast(i, j, np.asarray(level)).shape), i, j]

    def flyable(self, x: float, y: float) -> np.ndarray:
        """The levels a UAV may fly at over a point.

        Args:
            x: East, m.
            y: North, m.

        Returns:
            (L,) bool.
        """
        every = np.arange(self.levels)
        return ~self.blocked(np.full(self.levels, x), np.full(self.levels, y), every)

    def frozen(self, t_s: float = 0.0) -> SignalField:
        """The weather of one instant held still: the one map the signal gives then.

        What a tool that ignores the storm's motion plans on.

        Args:
            t_s: The instant, s.

        Returns:
            A field of one map (a map returns itself).

        Raises:
            InvalidInputError: The field is a bank (take one world with
                [`member()`][rainuav.nav.field.SignalField.member]).
        """
        if self.banked:
            raise InvalidInputError("frozen: a bank holds several worlds; take one (member)")
        if not self.varies:
            return self
        k0, k1, f = (int(a) if a.dtype.kind == "i" else float(a) for a in self.brackets(t_s))
        v = self.db[k0] if k0 == k1 else (1.0 - f) * self.db[k0] + f * self.db[k1]
        return SignalField(v, self.extent, self.name, not_flyable=self.not_flyable,
                           altitudes_m=self.altitudes_m)  # fmt: skip

    def at_points(
        self, points: np.ndarray, t_s: npt.ArrayLike, world: npt.ArrayLike | None = None
    ) -> np.ndarray:
        """The signal at fixed points at many instants, as `__call__` gives it.

        Every slice is sampled once per set of points (until
        [`put()`][rainuav.nav.field.SignalField.put]).

        Args:
            points: The points (M, 2), m.
            t_s: N instants, s.
            world: The world of each instant (N,), in a bank; None: world 0.

        Returns:
            (N, M), among levels (N, L, M).
        """
        g = self._points.get(self.values, self.extent, np.asarray(points, dtype=np.float64))
        g = g.reshape(-1, g.shape[-1])
        n = np.size(t_s)
        if self.altitudes_m is None:
            if len(g) == 1:
                return np.broadcast_to(g[0], (n, g.shape[-1]))
            return lerp_rows(g, *self._rows(np.atleast_1d(t_s), world))
        t = np.atleast_1d(t_s)
        return np.stack(
            [
                lerp_rows(g, *self._rows(t, 0 if world is None else world, k))
                for k in range(self.levels)
            ],
            axis=1,
        )


def field_digest(field: SignalField) -> str:
    """A digest of what a field flies: its values, area, instants, levels and closed pixels.

    A run records it, so that a map swapped into its folder is refused, not flown.

    Args:
        field: The field.

    Returns:
        The SHA-256 digest, as hexadecimal text.
    """
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
