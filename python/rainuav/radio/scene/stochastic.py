"""Stochastic rain fields: spatially correlated rain with a power-law spectrum, a wet fraction
and a mean rate, carried by one storm velocity and evolving in time (``Medium(kind="field",
field=StochasticRain(...))``; ``medium.at(t)`` is the rate map at t).

**The field** (the STEPS way of making rain, Seed 2003; the noise from ``pysteps``). A Gaussian
noise field ``N`` of zero mean and unit variance whose 2-D power spectrum falls as ``|k|^-beta`` is
made by filtering white noise in Fourier space
(``pysteps.noise.fftgenerators.generate_noise_2d_fft_filter``) on a periodic square of side
``side_m`` from the origin (default 4 km: twice the presets' area), on a grid of at most
[`MAX_GRID`][rainuav.radio.scene.stochastic.MAX_GRID] nodes a side (about 10 m). Rain falls where
``N > z`` with ``z`` the ``1 - wet_fraction`` quantile of the standard normal; there it is
log-normal, ``R = c exp(sigma N)`` (``sigma`` = ``log_sd``), with ``c`` set so that the expected
mean over the area is ``mean_rate_mm_h``: ``E[exp(sigma N); N > z] = exp(sigma^2 / 2) (1 - Phi(z -
sigma))``. Rates are capped at 500 mm/h.

**In time.** The field moves with the storm velocity ``(vx, vy)``: the square is periodic, so
the field at t is the field at 0 shifted by ``v t`` exactly (sampled bilinearly, wrapping); it
only comes back after ``side_m / |v|`` (400 s at 10 m/s). Like a rain cell, the weather of an
instant keeps its motion: ``StochasticRain.t_s`` is the instant it shows, and
``Medium.at(t)`` moves it on by t. pysteps' semi-Lagrangian
extrapolation would do the same shift by interpolation and leave the inflow edge undefined, so
the shift is done here. The field also evolves: independent noise fields at knots
``lifetime_s`` apart are blended, ``N(t) = cos(pi s / 2) N_k + sin(pi s / 2) N_k+1`` with ``s``
the fraction of the way from knot k to k + 1, which keeps ``N`` Gaussian with unit variance at
every instant and changes it continuously (a Lagrangian decorrelation time of about
``lifetime_s``; convective rain decorrelates in 10-30 minutes).

``pysteps`` is an optional dependency (``pip install '.[weather]' from the rainuav clone``); without
it a field is refused in one line."""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav._checks import check_integer
from rainuav._checks import check_number as _num
from rainuav.errors import InvalidInputError

__all__ = ["MAX_GRID", "StochasticRain", "field_rates", "nodes", "noise_field"]

MAX_GRID = 512
"""The most noise nodes along a side of the periodic square."""


@dataclass
class StochasticRain:
    """A stochastic rain field (module docstring); all rates in mm/h."""

    seed: int = 0
    """Seeds every noise field of this weather."""
    mean_rate_mm_h: float = 10.0
    """Expected mean rate over the area (wet and dry), mm/h."""
    wet_fraction: float = 0.4
    """Expected share of the area with rain."""
    beta: float = 3.0
    """Slope of the noise's 2-D power spectrum, ``|k|^-beta`` (radar rain: about 2.5-3.5)."""
    log_sd: float = 1.0
    """Standard deviation of log rate where it rains (log-normal)."""
    vx_m_s: float = 0.0
    """Storm velocity, east, m/s."""
    vy_m_s: float = 0.0
    """Storm velocity, north, m/s."""
    lifetime_s: float = 0.0
    """Knot spacing of the evolution, s (0: the field only moves)."""
    side_m: float = 4000.0
    """Side of the periodic square the field lives on, from the origin, m (larger than the
    area and the distance the storm travels in a flight, or rain comes round again)."""
    t_s: float = 0.0
    """The instant this weather shows, s after the field's time 0."""

    def at(self, t_s: float) -> StochasticRain:
        """The field some seconds on: moved and evolved, its motion kept.

        Args:
            t_s: Seconds after the field's instant.

        Returns:
            A new [`StochasticRain`][rainuav.radio.scene.stochastic.StochasticRain].
        """
        return dataclasses.replace(self, t_s=self.t_s + t_s)

    def check(self, where: str = "medium.field") -> None:
        """Checks the field's settings.

        Args:
            where: The name the error gives the field.

        Raises:
            InvalidInputError: The first field out of range (a lifetime too short, a speed over 60
                m/s, ...), named.
        """
        check_integer(f"{where}.seed", self.seed, 0, 2**63 - 1)
        _num(f"{where}.mean_rate_mm_h", self.mean_rate_mm_h, 0.0, 200.0, " mm/h")
        _num(f"{where}.wet_fraction", self.wet_fraction, 0.01, 1.0, "")
        _num(f"{where}.beta", self.beta, 1.0, 5.0, "")
        _num(f"{where}.log_sd", self.log_sd, 0.0, 3.0, "")
        for k in ("vx_m_s", "vy_m_s"):
            _num(f"{where}.{k}", getattr(self, k), -60.0, 60.0, " m/s")
        if math.hypot(self.vx_m_s, self.vy_m_s) > 60.0:
            raise InvalidInputError(f"{where}: speed must be at most 60 m/s")
        life = _num(f"{where}.lifetime_s", self.lifetime_s, 0.0, 1e7, " s")
        if life and life < 60.0:
            raise InvalidInputError(
                f"{where}.lifetime_s must be 0 (frozen) or at least 60 s (got {life:g})"
            )
        _num(f"{where}.side_m", self.side_m, 100.0, 1e5, " m")
        _num(f"{where}.t_s", self.t_s, -1e7, 1e7, " s")

    @property
    def moves(self) -> bool:
        return bool(self.vx_m_s or self.vy_m_s or self.lifetime_s)


def _pysteps() -> Any:
    import contextlib
    import io

    try:
        # pysteps announces its configuration file on stdout when imported: keep it quiet.
        with contextlib.redirect_stdout(io.StringIO()):
            from pysteps.noise import fftgenerators
    except ImportError as err:
        raise InvalidInputError(
            "stochastic rain fields need pysteps: pip install '.[weather]' from the rainuav clone"
        ) from err
    return fftgenerators


@functools.lru_cache(maxsize=16)
def noise_field(seed: int, knot: int, n: int, beta: float) -> np.ndarray:
    """The Gaussian noise of one knot of a field: zero mean, unit variance, 2-D spectrum
    `|k|^-beta`.

    Cached (read-only).

    Args:
        seed: The field's seed.
        knot: The knot's index in time.
        n: The nodes a side.
        beta: The spectrum's exponent.

    Returns:
        (n, n).
    """
    fft = _pysteps()
    k = np.hypot(*np.meshgrid(np.fft.fftfreq(n) * n, np.fft.fftfreq(n) * n))
    with np.errstate(divide="ignore"):
        amplitude = np.where(k > 0, k ** (-beta / 2.0), 0.0)
    spec = {"field": amplitude, "input_shape": (n, n), "use_full_fft": True}
    rng = np.random.RandomState(np.random.SeedSequence([seed, knot]).generate_state(1)[0])
    out = np.asarray(fft.generate_noise_2d_fft_filter(spec, randstate=rng), dtype=float)
    out.setflags(write=False)
    return out


def nodes(side_m: float) -> int:
    """The noise nodes along a side of the square: about 10 m apart, a power of two.

    At most [`MAX_GRID`][rainuav.radio.scene.stochastic.MAX_GRID].

    Args:
        side_m: The side, m.

    Returns:
        The number of nodes.
    """
    return int(min(MAX_GRID, 2 ** math.ceil(math.log2(max(side_m / 10.0, 16.0)))))


def field_rates(f: StochasticRain, x: npt.ArrayLike, y: npt.ArrayLike) -> np.ndarray:
    """The rain rate of a field at its instant at points, mm/h.

    Args:
        f: The field (at its `t_s`).
        x: East, m.
        y: North, m.

    Returns:
        Rates, mm/h.
    """
    from scipy.special import ndtri
    from scipy.stats import norm

    n, t = nodes(f.side_m), f.t_s
    knot, s = divmod(t / f.lifetime_s, 1.0) if f.lifetime_s else (0.0, 0.0)
    a = noise_field(f.seed, int(knot), n, f.beta)
    if s:
        b = noise_field(f.seed, int(knot) + 1, n, f.beta)
        a = math.cos(math.pi * s / 2) * a + math.sin(math.pi * s / 2) * b
    # Node (i, j) sits at (j d, i d); the field moves with v: sample at x - v t.
    d = f.side_m / n
    fx = ((np.asarray(x, dtype=float) - f.vx_m_s * t) / d) % n
    fy = ((np.asarray(y, dtype=float) - f.vy_m_s * t) / d) % n
    j0, i0 = np.floor(fx).astype(int) % n, np.floor(fy).astype(int) % n
    j1, i1 = (j0 + 1) % n, (i0 + 1) % n
    tx, ty = fx - np.floor(fx), fy - np.floor(fy)
    noise = (a[i0, j0] * (1 - tx) * (1 - ty) + a[i0, j1] * tx * (1 - ty)
             + a[i1, j0] * (1 - tx) * ty + a[i1, j1] * tx * ty)  # fmt: skip
    z = float(ndtri(1.0 - f.wet_fraction)) if f.wet_fraction < 1.0 else -np.inf
    wet_mean = math.exp(f.log_sd**2 / 2) * float(norm.sf(z - f.log_sd))
    c = f.mean_rate_mm_h / wet_mean
    return np.where(noise > z, np.minimum(c * np.exp(f.log_sd * noise), 500.0), 0.0)
