"""Type stubs for the Rust extension ``rainuav._core`` (crates/rainuav-py).

Array arguments are 1-D float64 C-contiguous arrays (read as zero-copy views); results are
fresh arrays handed over without copying. ``rainuav.medium`` wraps these with broadcasting.
"""

from typing import Any, final

import numpy as np
import numpy.typing as npt

__all__ = [
    "DropSizeDistribution",
    "MediumConfig",
    "PeMarcher",
    "Prisms",
    "RainMediumKernel",
    "RaySlicer",
    "__version__",
    "available_memory_bytes",
    "axial_ratio",
    "bullington_loss",
    "check_memory",
    "depolarisation_factors",
    "effective_medium",
    "gauss_legendre",
    "gaussian_beam",
    "itu_p838",
    "knife_edge_loss_db",
    "mie_forward",
    "plan_optimal_levels",
    "ray_departures",
    "ray_power",
    "ray_walls",
    "sample_slices",
    "terminal_velocity_m_s",
    "utd_wedge",
    "water_permittivity",
]

__version__: str

_F = npt.NDArray[np.float64]
_I = npt.NDArray[np.int64]
_C = npt.NDArray[np.complex128]
_C64 = npt.NDArray[np.complex64]
_B = npt.NDArray[np.bool_]

@final
class DropSizeDistribution:
    """A drop-size distribution N(D) in m^-3 mm^-1."""

    @staticmethod
    def marshall_palmer() -> DropSizeDistribution:
        """Marshall-Palmer: N = 8000 exp(-4.1 R^-0.21 D) m^-3 mm^-1."""
    @staticmethod
    def gamma(
        n0: float, mu: float, lambda_coeff: float, lambda_exp: float, n0_exp: float = 0.0
    ) -> DropSizeDistribution:
        """Gamma: N = n0 R^n0_exp D^mu exp(-lambda_coeff R^lambda_exp D)."""
    @staticmethod
    def table(diameter_mm: _F, density: _F) -> DropSizeDistribution:
        """A tabulated N(D), linearly interpolated; scales with R / table_rain_rate_mm_h."""
    @property
    def table_rain_rate_mm_h(self) -> float | None:
        """The rain rate the table carries (Atlas fall speeds); None for parametric forms."""
    def density(self, diameter_mm: _F, rain_rate_mm_h: _F) -> _F:
        """N(D) for pairs (diameter_mm[i], rain_rate_mm_h[i]); zero rate gives zero."""

@final
class MediumConfig:
    """Options of the rain medium (validated on construction)."""

    def __new__(
        cls,
        *,
        model: str,
        polarization: str,
        shape: str,
        temperature_c: float,
        wind_speed_m_s: float,
        wind_model: str,
        dsd: DropSizeDistribution,
        nodes_per_panel: int = 16,
    ) -> MediumConfig: ...

@final
class RainMediumKernel:
    """The rain medium at one frequency, precomputed on the quadrature nodes."""

    def __new__(cls, freq_hz: float, config: MediumConfig) -> RainMediumKernel: ...
    @property
    def nodes(self) -> int:
        """Number of quadrature nodes."""
    def evaluate(self, rain_rate_mm_h: _F) -> tuple[_C, _C, _F]:
        """(eps, n, gamma_db_per_km) for each rain rate."""

def water_permittivity(freq_hz: _F, temperature_c: _F) -> _C:
    """Water permittivity (double Debye, Im <= 0) for pairs of frequency and temperature."""

def effective_medium(freq_hz: _F, rain_rate_mm_h: _F, config: MediumConfig) -> tuple[_C, _C, _F]:
    """(eps, n, gamma_db_per_km) for pairs (freq_hz[i], rain_rate_mm_h[i])."""

def itu_p838(freq_hz: _F, rain_rate_mm_h: _F, tilt_deg: float, elevation_deg: float) -> _F:
    """ITU-R P.838-3 specific attenuation in dB/km for pairs."""

def mie_forward(m: complex, x: float) -> tuple[complex, float, float]:
    """Bohren-Huffman Mie (S(0), Q_ext, Q_sca) for m (Im m >= 0) and size parameter x."""

def gauss_legendre(n: int) -> tuple[_F, _F]:
    """Gauss-Legendre nodes and weights on [-1, 1] (Golub-Welsch)."""

def depolarisation_factors(axial_ratio: float) -> tuple[float, float]:
    """Depolarisation factors (Lx, Lz) of an oblate spheroid, axial ratio in (0, 1]."""

def axial_ratio(shape: str, diameter_mm: float) -> float:
    """Axial ratio (minor/major) of a drop under a shape rule."""

def terminal_velocity_m_s(diameter_mm: float) -> float:
    """Atlas et al. (1973) terminal fall speed, m/s."""

@final
class PeMarcher:
    """A split-step PE march in progress; ``rainuav.pwe.march`` drives it in chunks."""

    def __new__(
        cls,
        u0: _C64,
        *,
        dx_m: float,
        dy_m: float,
        dz_m: float,
        freq_hz: float,
        propagator: str,
        ground: str,
        absorber: float,
        x_absorber_every: int = 1,
        n_fixed: _C | None = None,
    ) -> PeMarcher: ...
    @property
    def steps_done(self) -> int:
        """Steps done so far."""
    def advance(
        self,
        steps: int,
        *,
        n_uniform: complex | None = None,
        n_fixed: bool = False,
        n_steps: _C | None = None,
        n_cross_range: _C | None = None,
        mask_fixed: _B | None = None,
        mask_steps: _B | None = None,
        heights_fixed: _F | None = None,
        heights_steps: _F | None = None,
        record_rows: npt.NDArray[np.uint64],
        rows_out: _C64 | None = None,
        record_column: int | None = None,
        column_out: _C64 | None = None,
        row_offsets: npt.NDArray[np.int64] | None = None,
    ) -> None:
        """Advances ``steps`` steps without the GIL; per-step inputs cover these steps."""
    def finish(self) -> _C64:
        """Hands the final (nx, ny) field over without copying; the marcher is spent."""

def gaussian_beam(
    nx: int,
    ny: int,
    dx_m: float,
    dy_m: float,
    *,
    freq_hz: float,
    height_m: float,
    elevation_deg: float,
    beamwidth_deg: float,
) -> _C64:
    """Gaussian-beam aperture (nx, ny) complex64."""

def check_memory(bytes: int) -> None:
    """Refuses a job needing ``bytes`` if it exceeds 80% of the available memory."""

def available_memory_bytes() -> int | None:
    """Memory this machine reports as available (Linux ``MemAvailable``), bytes."""

def sample_slices(
    slices: _F,
    extent_m: tuple[float, float, float, float],
    x: _F,
    y: _F,
    k0: _I,
    k1: _I,
    f: _F,
) -> _F:
    """The signal at many points, each between two slices of a stack (S, H, W): bilinear in
    space, linear in time (``(1 - f) v0 + f v1``; ``v0`` where ``k0 == k1``). The 1-D arrays
    are contiguous; ``x`` and ``y`` of one length N, ``k0``, ``k1`` and ``f`` one value per row
    of consecutive points: N of them, or a divisor R of N (point n reads row n // (N / R))."""

def plan_optimal_levels(
    sinr_db: _F,
    t_s: _F,
    starts: _F,
    task: dict[str, Any],
    blocked: npt.NDArray[np.uint8] | None = None,
) -> list[tuple[float, npt.NDArray[np.uint8], _F, npt.NDArray[np.uint64]]]:
    """Exact plans among levels, the signal (K, L, H, W) at the instants t_s (one slice: a
    signal that does not change): six moves, starts (N, 3) x, y, level (-1: the best); the
    task's items as ``rainuav.nav.planner.rust_task`` builds them (geometry, rewards,
    horizon, clock, climbs and descents in ticks); each plan a (return, actions, path (T+1,
    3): x, y, level, ticks (T+1,))."""

def ray_power(
    tx_m: _F,
    tx_power_mw: _F,
    g_direct: _F,
    g_reflect: _F,
    x_m: _F,
    y_m: _F,
    *,
    altitude_m: float,
    pixel_m: tuple[float, float],
    freq_hz: float,
    ground: str,
    eps_ground: tuple[float, float],
    polarization: str,
    gamma_db_per_m: float,
    gamma_raster: _F | None,
    gamma_origin_step: tuple[float, float, float, float],
    buildings: _F,
    heights: _F | None,
    heights_origin_step: tuple[float, float, float, float],
    terrain: _F | None = None,
    terrain_origin_step: tuple[float, float, float, float] | None = None,
    altitude_msl: bool = False,
    terrain_roughness_m: float = 0.0,
    terms_only: bool = False,
    prisms: Prisms | None = None,
    walls: _F | None = None,
    geometry: _F | None = None,
    geometry_sites: _F | None = None,
) -> _F:
    """Received power (mW) of every transmitter at every pixel, (M, H, W); with
    ``terms_only``, its clear-air parts and its rays' lengths [direct, reflect, cross, d1, d2,
    wall, d3], (M, H, W, 7). ``terrain``: heights above sea level at nodes (the ground under
    everything); ``altitude_msl``: the flight altitude above sea level instead of above the
    terrain; ``prisms``: buildings besides the boxes; ``walls`` (M, H, W, 2): each cell's wall
    rays per pixel (clear-air power mW, mean length m); ``geometry`` (S, H, W, 7) with
    ``geometry_sites`` (S, 3): paths traced by ``ray_departures(..., full=True)``."""

@final
class Prisms:
    """Buildings as prisms on the terrain: footprint rings and roof heights, with a bucket
    grid, built once and passed to the ray functions."""

    def __new__(cls, xy: _F, ring_starts: _I, prism_rings: _I, tops: _F) -> Prisms: ...
    def __len__(self) -> int: ...
    def height_at(self, x: _F, y: _F) -> _F:
        """The tallest roof (m above the terrain) over each point; 0 where none."""

def ray_walls(
    sites: _F,
    x_m: _F,
    y_m: _F,
    walls: _F,
    wall_eps: _F,
    *,
    altitude_m: float,
    freq_hz: float,
    polarization: str,
    buildings: _F,
    heights: _F | None,
    heights_origin_step: tuple[float, float, float, float],
    terrain: _F | None = None,
    terrain_origin_step: tuple[float, float, float, float] | None = None,
    altitude_msl: bool = False,
    terrain_roughness_m: float = 0.0,
    prisms: Prisms | None = None,
    prism_eps: _F | None = None,
) -> tuple[_I, _I, _F, _F, _F, _F, _I]:
    """Every ray the walls (K, 6: ax, ay, bx, by, base, top) reflect from each site to each
    pixel, once or twice: (site, pixel, az_deg, el_deg, factor per mW for isotropic antennas,
    length_m, kind: 1 one wall, 2 two walls, 3 a corner); with ``prism_eps`` (P, 2), also the
    rays the prisms' corners diffract into the pixels they hide."""

def utd_wedge(
    n: float,
    phi1: float,
    phi2: _F,
    *,
    l_m: float,
    sin_beta0: float,
    k: float,
    r0: complex,
    rn: complex,
) -> _C:
    """The UTD coefficient of a finitely conducting wedge (ITU-R P.526-15 section 6) at each
    diffraction angle ``phi2`` (rad), sqrt(m)."""

def knife_edge_loss_db(nu: _F) -> _F:
    """ITU-R P.526's knife-edge loss J(nu), dB, of each ``nu``."""

def bullington_loss(
    d_m: _F,
    h_m: _F,
    *,
    d_total_m: float,
    h_ts_m: float,
    h_rs_m: float,
    wavelength_m: float,
) -> tuple[float, float, float, float]:
    """The Bullington loss of a profile: (loss_db, knife_edge_db, edge_d_m, edge_h_m)."""

def ray_departures(
    sites: _F,
    x_m: _F,
    y_m: _F,
    *,
    altitude_m: float,
    freq_hz: float,
    ground: str,
    buildings: _F,
    heights: _F | None,
    heights_origin_step: tuple[float, float, float, float],
    terrain: _F | None = None,
    terrain_origin_step: tuple[float, float, float, float] | None = None,
    altitude_msl: bool = False,
    terrain_roughness_m: float = 0.0,
    prisms: Prisms | None = None,
    full: bool = False,
    polarization: str = "h",
) -> _F:
    """Departure elevations (degrees) toward which each site's gains are taken, (S, H, W, 2):
    the direct ray's (the diffracting edge, else the pixel) and the reflected ray's; with
    ``full``, each path's geometry (S, H, W, 7): d1, d2, loss_db, el_direct, el_reflect (rad),
    psi, reflect; ``polarization`` sets the roofs' wedge coefficients in the loss."""

@final
class RaySlicer:
    """Every cell's rays traced once; the power at any instant from its rain."""

    def __new__(
        cls,
        terms: _F,
        sites: _F,
        site_of: _I,
        x_m: _F,
        y_m: _F,
        *,
        node_spacing_m: float,
    ) -> RaySlicer: ...
    def power(
        self,
        *,
        gamma_db_per_m: float,
        gamma_raster: _F | None,
        gamma_origin_step: tuple[float, float, float, float],
        rss_dbm_out: npt.NDArray[np.float32] | None = None,
        rss_floor_dbm: float = ...,
    ) -> _F:
        """Power (mW) of every cell at every pixel, (M, H, W), through this rain."""
