"""3-D split-step parabolic-equation propagation ([physics reference, section
4][4-the-split-step-parabolic-equation]).

Frame of one transmitter: z = range (the march axis), x = cross-range, y = height. Fields are
``u[ix, iy]`` (complex64) on ``x = (ix - nx//2) dx_m``, ``y = iy dy_m``; with a ground, row
``iy = 0`` is the ground. The full field is ``E = u exp(-j k0 z)``.

The march runs in Rust (rustfft, rayon) without the GIL, in chunks of about a quarter of a
second, so Ctrl-C stops it within a second and a progress bar or callback can follow it.

Memory: the field, a propagator table (a quarter of a field, half with a ground) and, only
for an (nx, ny) refractive index constant along range, its phase screen, and with
``x_absorber_every`` above 1 a second propagator table (half a field): at most 3 copies of
the field, plus the recorded rows ``(len(record_rows), steps, nx)`` and column
``(steps, ny)``. The job's bytes are estimated before anything is allocated and a job that
would not fit in 80% of the available memory is refused with the number.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav import _core
from rainuav._checks import as_real_scalar, check_choice
from rainuav.errors import InvalidInputError
from rainuav.pwe_sources import _positive, gaussian_beam, pattern_source

__all__ = ["Marched", "gaussian_beam", "march", "pattern_source"]

PROPAGATORS = ("wide", "narrow")
GROUNDS = ("pec-h", "pec-v")

Complex64Array = npt.NDArray[np.complex64]


@dataclass(frozen=True)
class Marched:
    """Result of [`march()`][rainuav.pwe.march]."""

    field: Complex64Array
    """(nx, ny) complex64: the field after the last step."""
    rows: Complex64Array
    """(len(record_rows), steps, nx) complex64: the recorded rows after each step."""
    column: Complex64Array | None = None
    """(steps, ny) complex64: the vertical plane at ``record_column`` after each step."""


def _field(name: str, value: Any) -> Complex64Array:
    arr = np.asarray(value)
    if arr.ndim != 2:
        raise InvalidInputError(f"{name} must be a 2-D (nx, ny) array (got shape {arr.shape})")
    if not (np.issubdtype(arr.dtype, np.number) or arr.dtype == np.bool_):
        raise InvalidInputError(f"{name} must be numeric (got dtype {arr.dtype})")
    # Finiteness is checked in Rust, in the same pass that copies the field in.
    return np.ascontiguousarray(arr, dtype=np.complex64)


def _integer(name: str, value: Any, lo: int, hi: int | None = None) -> int:
    """An integer within lo..hi (no upper bound without hi); bools are refused."""
    ok = not isinstance(value, bool) and isinstance(value, (int, np.integer))
    if not ok or value < lo or (hi is not None and value > hi):
        allowed = f">= {lo}" if hi is None else f"within {lo}..{hi}"
        raise InvalidInputError(f"{name} must be an integer {allowed} (got {value!r})")
    return int(value)


def _index(n: Any) -> np.ndarray | complex:
    if np.isscalar(n) or (isinstance(n, np.ndarray) and n.ndim == 0):
        z = complex(n)  # type: ignore[arg-type]
        if not np.isfinite(z):
            raise InvalidInputError(f"n must be finite (got {n!r})")
        return z
    arr = np.asarray(n)
    if not np.issubdtype(arr.dtype, np.number):
        raise InvalidInputError(f"n must be numbers (got dtype {arr.dtype})")
    arr = np.ascontiguousarray(arr, dtype=np.complex128)
    if not np.all(np.isfinite(arr)):
        raise InvalidInputError("n must be finite everywhere")
    return arr


def _obstacle(obs: Any, nx: int, ny: int, steps: int | None) -> dict[str, np.ndarray]:
    """Sorts an obstacle description into the core's keyword arguments."""
    if obs is None:
        return {}
    arr = np.asarray(obs)
    if arr.dtype == np.bool_:
        if arr.shape == (nx, ny):
            return {"mask_fixed": np.ascontiguousarray(arr)}
        if arr.ndim == 3 and arr.shape[1:] == (nx, ny) and (steps is None or len(arr) == steps):
            return {"mask_steps": np.ascontiguousarray(arr)}
    elif np.issubdtype(arr.dtype, np.number):
        h = np.ascontiguousarray(arr, dtype=np.float64)
        if np.isnan(h).any():
            raise InvalidInputError("obstacles heights must not be NaN")
        if h.shape == (nx,):
            return {"heights_fixed": h}
        if h.ndim == 2 and h.shape[1] == nx and (steps is None or len(h) == steps):
            return {"heights_steps": h}
    raise InvalidInputError(
        "obstacles must be a bool mask (nx, ny) or (steps, nx, ny), heights in metres (nx,) "
        f"or (steps, nx), or a callable of the step (got shape {arr.shape}, dtype {arr.dtype}; "
        f"nx={nx}, ny={ny}, steps={steps})"
    )


# Long: every input is checked once, one line each, before the core allocates anything; then
# the loop feeds the core its chunks. Split, the checked inputs would travel as a dozen
# arguments between the halves.
def march(
    u0: npt.ArrayLike,
    *,
    dx_m: float,
    dy_m: float,
    dz_m: float,
    steps: int,
    freq_hz: float,
    n: Any = 1.0,
    propagator: str = "wide",
    ground: str | None = None,
    absorber: float = 0.0,
    record_rows: Sequence[int] = (),
    obstacles: Any = None,
    record_column: int | None = None,
    progress: bool | Callable[[int, int], None] = False,
    n_cross_range: npt.ArrayLike | None = None,
    x_absorber_every: int = 1,
    record_offsets: npt.ArrayLike | None = None,
) -> Marched:
    """Marches the aperture field ``u0`` (nx, ny) over ``steps`` range steps of ``dz_m``.

    Args:
        u0: (nx, ny) aperture at z = 0 (converted to complex64). ``u0[ix, iy]``.
        dx_m: cross-range spacing, m (> 0).
        dy_m: height spacing, m (> 0).
        dz_m: range step, m (> 0).
        steps: number of range steps (>= 1).
        freq_hz: frequency (1e6-1e12 Hz).
        n: refractive index: a complex scalar (homogeneous, e.g. rain from
            [`rainuav.medium.effective_index()`][rainuav.medium.effective_index]), an (nx, ny) array
            constant along range,
            a (steps, nx, ny) array, or a callable ``n(step) -> scalar | (nx, ny)``.
        propagator: ``"wide"`` (exact spectral; evanescent waves decay) or ``"narrow"``
            (paraxial, the paper's).
        ground: ``None`` (periodic in y), ``"pec-h"`` or ``"pec-v"`` (flat PEC at ``iy = 0``
            for horizontal / vertical polarisation, by images).
        absorber: fraction (0-0.45) of the lateral edges and the top (and bottom without a
            ground) over which a cos^2 window tapers the field to zero every step.
        record_rows: rows ``iy`` (flight altitudes) recorded after every step.
        obstacles: ``None``; a bool mask (nx, ny) used every step or (steps, nx, ny); heights
            in metres (nx,) every step or (steps, nx), zeroing ``y <= height``; or a callable
            ``obstacles(step)`` returning any of these per step.
        record_column: optionally a column ``ix`` whose vertical plane is recorded.
        progress: ``True`` for a progress bar, or a callable ``(done, total)``.
        n_cross_range: instead of ``n``, a (steps, nx) index varying with cross-range only
            (rain cells: rate varies horizontally, not with height); one factor per row.
        x_absorber_every: on steps with a uniform ``n`` and no obstacles (and no recorded
            column), apply the lateral part of the window every this many steps, as the
            window to this power (1-64). The march then stays in the spectral domain and
            runs its x transforms only on those steps (1.5-1.8x faster per step at 7 on a
            2500 x 1296 grid, BENCHMARKS.md). The strips' absorption is sampled that much
            more coarsely in range: keep the distance the widest angle crosses between
            windows well inside a strip (the radio-map engine allows an eighth).
        record_offsets: optionally (steps, nx) integers: after step ``s`` column ``ix``
            records the rows ``record_rows + record_offsets[s, ix]`` (a receiver surface that
            follows the ground); the shifted rows must stay within the grid.

    Returns:
        [`Marched`][rainuav.pwe.Marched] with ``field`` (nx, ny), ``rows`` (len(record_rows), steps,
        nx) and
        ``column`` (steps, ny) or None, all complex64.
    """
    u = _field("u0", u0)
    nx, ny = u.shape
    dx, dy, dz = (_positive(k, v) for k, v in (("dx_m", dx_m), ("dy_m", dy_m), ("dz_m", dz_m)))
    steps = _integer("steps", steps, 1)
    freq = as_real_scalar("freq_hz", freq_hz)
    prop = check_choice("propagator", propagator, PROPAGATORS)
    gnd = "none" if ground is None else check_choice("ground", ground, GROUNDS)
    absorb = as_real_scalar("absorber", absorber)
    every = _integer("x_absorber_every", x_absorber_every, 1, 64)
    rows_idx = np.asarray(record_rows, dtype=np.int64).reshape(-1)
    if rows_idx.size and (rows_idx.min() < 0 or rows_idx.max() >= ny):
        raise InvalidInputError(f"record_rows must be within 0..{ny - 1} (got {record_rows!r})")
    if record_column is not None and not (0 <= int(record_column) < nx):
        raise InvalidInputError(f"record_column must be within 0..{nx - 1} (got {record_column})")
    offsets = None
    if record_offsets is not None:
        offsets = np.ascontiguousarray(np.asarray(record_offsets), dtype=np.int64)
        if offsets.shape != (steps, nx):
            raise InvalidInputError(
                f"record_offsets must have shape ({steps}, {nx}) (got {offsets.shape})"
            )
        if rows_idx.size and (
            rows_idx.min() + offsets.min() < 0 or rows_idx.max() + offsets.max() >= ny
        ):
            raise InvalidInputError(f"record_offsets move the recorded rows out of 0..{ny - 1}")

    n_callable = callable(n)
    n_val = None if n_callable else _index(n)
    n_fixed = None
    if isinstance(n_val, np.ndarray):
        if n_val.shape == (nx, ny):
            n_fixed = n_val
        elif n_val.shape != (steps, nx, ny):
            raise InvalidInputError(
                f"n must be a scalar, ({nx}, {ny}), ({steps}, {nx}, {ny}) or a callable "
                f"(got shape {n_val.shape})"
            )
    n_cross = None
    if n_cross_range is not None:
        if n_callable or not (isinstance(n_val, complex) and n_val == 1):
            raise InvalidInputError("give either n or n_cross_range, not both")
        n_cross = _index(n_cross_range)
        if not isinstance(n_cross, np.ndarray) or n_cross.shape != (steps, nx):
            raise InvalidInputError(
                f"n_cross_range must have shape ({steps}, {nx}) (got {np.shape(n_cross_range)})"
            )
    obs_callable = callable(obstacles)
    obs_kw = {} if obs_callable else _obstacle(obstacles, nx, ny, steps)

    # Estimate every byte before allocating anything big.
    c64 = 8
    table = (ny // 2 + 1 if gnd == "none" else ny + 1) * (nx // 2 + 1) * c64
    bytes_needed = (
        2 * nx * ny * c64  # field + the handed-over copy of u0
        + table
        + ((nx // 2 + 1) * (ny + 1) * c64 if every > 1 else 0)
        + (nx * ny * c64 if n_fixed is not None else 0)
        + rows_idx.size * steps * nx * c64
        + (steps * ny * c64 if record_column is not None else 0)
    )
    _core.check_memory(int(bytes_needed))

    marcher = _core.PeMarcher(
        u,
        dx_m=dx,
        dy_m=dy,
        dz_m=dz,
        freq_hz=freq,
        propagator=prop,
        ground=gnd,
        absorber=absorb,
        x_absorber_every=every,
        n_fixed=n_fixed,
    )
    rows_out = np.zeros((rows_idx.size, steps, nx), dtype=np.complex64)
    column_out = None if record_column is None else np.zeros((steps, ny), dtype=np.complex64)
    rows_u64 = rows_idx.astype(np.uint64)

    bar = None
    report: Callable[[int, int], None] | None = None
    if progress is True:
        from tqdm.auto import tqdm

        bar = tqdm(total=steps, desc="PE march", unit="step")
    elif callable(progress):
        report = progress

    per_step = bool(n_callable or obs_callable)
    done, chunk = 0, 1
    try:
        while done < steps:
            k = 1 if per_step else min(chunk, steps - done)
            kw: dict[str, Any] = {}
            if n_callable:
                nv = _index(n(done))
                if isinstance(nv, np.ndarray):
                    if nv.shape != (nx, ny):
                        raise InvalidInputError(
                            f"n({done}) must be a scalar or ({nx}, {ny}) (got {nv.shape})"
                        )
                    kw["n_steps"] = nv[None]
                else:
                    kw["n_uniform"] = nv
            elif n_cross is not None:
                kw["n_cross_range"] = n_cross[done : done + k]
            elif isinstance(n_val, complex):
                kw["n_uniform"] = n_val
            elif n_fixed is not None:
                kw["n_fixed"] = True
            else:
                kw["n_steps"] = n_val[done : done + k]  # type: ignore[index]
            if obs_callable:
                o = _obstacle(obstacles(done), nx, ny, None)
                kw.update({(key.replace("_fixed", "_steps")): v[None] for key, v in o.items()})
            else:
                for key, v in obs_kw.items():
                    kw[key] = v[done : done + k] if key.endswith("_steps") else v
            if offsets is not None:
                kw["row_offsets"] = offsets[done : done + k]
            t0 = time.perf_counter()
            marcher.advance(
                k,
                record_rows=rows_u64,
                rows_out=rows_out,
                record_column=record_column,
                column_out=column_out,
                **kw,
            )
            dt = time.perf_counter() - t0
            done += k
            # Aim for ~0.25 s per chunk: Ctrl-C and progress respond between chunks.
            chunk = max(1, min(4 * chunk, int(0.25 * k / max(dt, 1e-6))))
            if bar is not None:
                bar.update(k)
            if report is not None:
                report(done, steps)
    finally:
        if bar is not None:
            bar.close()
    return Marched(field=marcher.finish(), rows=rows_out, column=column_out)
