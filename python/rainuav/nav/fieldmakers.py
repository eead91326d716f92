"""The ways to make a [`SignalField`][rainuav.nav.field.SignalField] besides one map: maps in time,
a bank of worlds, a stack of flight levels, and levels joined from one field each."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Self

import numpy as np
import numpy.typing as npt

from rainuav.errors import InvalidInputError

__all__ = ["FieldMakers"]


class FieldMakers:
    """The makers of [`SignalField`][rainuav.nav.field.SignalField], which it is mixed into (each
    calls the field's constructor)."""

    @classmethod
    def series(
        cls,
        values_db: npt.ArrayLike,
        t_s: npt.ArrayLike,
        extent_m: tuple[float, float, float, float],
        name: str = "sinr_db",
        serving_cell: npt.ArrayLike | None = None,
        not_flyable: npt.ArrayLike | None = None,
    ) -> Self:
        """Maps in time: a storm that moves.

        Args:
            values_db: The signal, dB, (K, H, W): K maps.
            t_s: Their instants (K,), s, strictly increasing.
            extent_m: `(x_min, x_max, y_min, y_max)`, m.
            name: The array's name in error messages.
            serving_cell: The serving cell (K, H, W), optional.
            not_flyable: The pixels a UAV may not enter (H, W), optional.

        Returns:
            The [`SignalField`][rainuav.nav.field.SignalField], linear in time between the slices.
        """
        return cls(values_db, extent_m, name, serving_cell, not_flyable, t_s=t_s)

    @classmethod
    def bank(
        cls,
        values_db: npt.ArrayLike,
        t_s: npt.ArrayLike,
        extent_m: tuple[float, float, float, float],
        altitudes_m: npt.ArrayLike | None = None,
        name: str = "sinr_db",
    ) -> Self:
        """Several worlds' signals in one field, each read as its own series.

        A one-instant bank is P still maps; a bank flies over open ground (no pixel closed).

        Args:
            values_db: The signal, dB, (P, K, H, W), or (P, K, L, H, W) on the levels `altitudes_m`.
            t_s: The common instants (K,), s.
            extent_m: `(x_min, x_max, y_min, y_max)`, m, one for every world.
            altitudes_m: The levels' altitudes (L,), m, lowest first; None: one level.
            name: The array's name in error messages.

        Returns:
            The [`SignalField`][rainuav.nav.field.SignalField]; a world's slot is replaced in place
            by [`put()`][rainuav.nav.field.SignalField.put].
        """
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
    ) -> Self:
        """Flight levels from a stack of maps.

        Args:
            signal_db: The signal, dB, (L, H, W), or (T, L, H, W) at the instants `t_s`.
            altitudes_m: The levels' altitudes (L,), m, lowest first.
            extent_m: `(x_min, x_max, y_min, y_max)`, m.
            t_s: The instants (T,), s, with a (T, L, H, W) stack only.
            not_flyable: The pixels a UAV may not enter (L, H, W), optional.
            serving_cell: The serving cell (the stack's shape), optional.

        Returns:
            The [`SignalField`][rainuav.nav.field.SignalField] among those levels.

        Raises:
            InvalidInputError: A stack of another rank, or `t_s` without a stack in time (or the
                reverse).
        """
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
    def of_levels(cls, fields: Sequence[Self], altitudes_m: npt.ArrayLike) -> Self:
        """Flight levels from one field a level (a copy).

        Args:
            fields: One [`SignalField`][rainuav.nav.field.SignalField] of one level for each level,
                all of one kind (maps, maps in time or banks), size and area.
            altitudes_m: The levels' altitudes, m, lowest first.

        Returns:
            The field among those levels.

        Raises:
            InvalidInputError: Fields of several kinds, sizes, instants or areas.
        """
        if not fields or not all(isinstance(f, cls) and f.altitudes_m is None for f in fields):
            raise InvalidInputError("fields must be SignalFields of one level each")
        if len({(f.banked, f.varies) for f in fields}) != 1:
            raise InvalidInputError(
                "fields must be all maps, all maps in time (SignalField.series) or all banks "
                "(SignalField.bank)"
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
