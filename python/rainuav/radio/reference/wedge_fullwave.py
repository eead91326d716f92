"""Which wedge coefficient is right for a building's corner: a full-wave reference on one wedge.

The tracer ([`rainuav.radio.reference.tracer`][rainuav.radio.reference.tracer]) runs with the
wedge coefficient of ITU-R P.526-15 section 6 in place of its own
([`tracer_wedge`][rainuav.radio.reference.tracer_wedge]). On a perfectly conducting wedge the
exact eigenfunction series settles which is right (``tests/test_wedge_exact.py``); a concrete
corner has no such series. This module solves Maxwell's equations on one:

- **The scene.** A right-angled corner (exterior angle 270 degrees, ``n = 1.5``) of a solid
  block of an ITU-R P.2040 material, its edge along z; a line source (a current along the edge
  for the field along it, soft; a magnetic one for the field across it, hard) at ``rho_m`` from
  the edge and ``phi1_deg`` from the lit face; the field on a circle of the same radius, at
  every ``phi`` from that face, against the source's in free space. In two dimensions: every ray
  meets the edge at right angles, as a horizontal path meets a building's vertical corner.
- **The full-wave reference.** The finite-difference frequency-domain solver of ceviche (a kept
  package: Hughes, Minkov, Williamson and Fan, ACS Photonics 2019) on a square grid of
  ``points_per_wavelength`` cells a free-space wavelength, with its perfectly matched layers:
  the field with the block over the field without it, at the same points (the grid's own
  dispersion cancels in the ratio). On a conducting block it is checked against the exact
  series for a line source (``4 pi / (n pi) sum J_nu(k rho<) H_nu(k rho>) sin(nu phi') sin(nu
  phi)``, ``nu = m / n``, soft; cosines and ``eps_m`` for hard).
- **The asymptotic methods.** Geometrical optics (the incident field where the source is seen,
  the lit face's reflection with the P.2040 half-space's Fresnel coefficient where it exists)
  plus the edge's diffracted field ``u_i(Q) D exp(-j k s) / sqrt(s)`` (``L = s s' / (s + s')``),
  with ``D`` either the standard's
  ([`p526_coefficient()`][rainuav.radio.reference.wedge_fullwave.p526_coefficient], the ray
  engine's ``utd_wedge``) or what the tracer's path solver gives for the same corner in three
  dimensions with either coefficient
  ([`tracer_coefficient()`][rainuav.radio.reference.wedge_fullwave.tracer_coefficient]).

``experiments/wedge_fullwave.py`` prints the comparison; ``tests/test_wedge_fullwave.py`` checks
it on a small case.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass

import numpy as np

from rainuav.ground.footprints import material_permittivity

__all__ = [
    "FACES",
    "REFERENCE_PHI_DEG",
    "WedgeCase",
    "exact_pec",
    "fdfd_total",
    "p526_coefficient",
    "reference_corner",
    "tracer_coefficient",
    "utd_total",
]

C = 299_792_458.0
N = 1.5
"""The corner's exterior angle over pi (a right-angled corner)."""
PML_CELLS = 30
"""The perfectly matched layer's depth, cells (about a wavelength at 30 cells a wavelength)."""


@dataclass(frozen=True)
class WedgeCase:
    """One corner, one source, one circle of field points (module docstring)."""

    freq_hz: float = 3.5e9
    material: str = "concrete"
    """A P.2040 material of ``rainuav.ground.footprints.MATERIALS`` (``"metal"``: conducting)."""
    phi1_deg: float = 45.0
    """The source's angle from the lit face, degrees (0-90: one face lit, a shadow behind)."""
    rho_m: float = 0.5
    """The source's and the field points' distance from the edge, m."""
    points_per_wavelength: float = 40.0

    def __post_init__(self) -> None:
        if not 0.0 < self.phi1_deg < 90.0:
            raise ValueError(f"phi1_deg is in (0, 90) (got {self.phi1_deg})")
        if self.rho_m <= 0.0 or self.points_per_wavelength < 10.0:
            raise ValueError("rho_m > 0 and points_per_wavelength >= 10")

    @property
    def k(self) -> float:
        """The free-space wavenumber, rad/m."""
        return 2.0 * math.pi * self.freq_hz / C

    @property
    def eps(self) -> complex:
        """The block's complex relative permittivity (``eps_r - j sigma / (omega eps_0)``)."""
        return material_permittivity(self.material, self.freq_hz)

    def grid(self) -> tuple[np.ndarray, float, tuple[float, float]]:
        """The FDFD grid: its cell centres, its cell size, and the source snapped to a cell centre.

        Returns:
            `(centres along either axis (m; the edge on a cell boundary at 0), cell size m, source
            (x, y) m)`.
        """
        dl = C / self.freq_hz / self.points_per_wavelength
        cells = round(2.3 * self.rho_m / dl) + 2 * PML_CELLS
        x = (np.arange(cells) - cells / 2 + 0.5) * dl
        angle = math.pi - math.radians(self.phi1_deg)
        sx = x[np.argmin(abs(x - self.rho_m * math.cos(angle)))]
        sy = x[np.argmin(abs(x - self.rho_m * math.sin(angle)))]
        return x, dl, (float(sx), float(sy))

    def source(self) -> tuple[float, float]:
        """The snapped source's place relative to the edge.

        Returns:
            `(distance from the edge m, angle from the lit face rad)`.
        """
        _, _, (sx, sy) = self.grid()
        return math.hypot(sx, sy), math.pi - math.atan2(sy, sx)

    def points(self, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The field points on the case's circle.

        Args:
            phi: Angles from the lit face, rad.

        Returns:
            `(x, y)`, m.
        """
        angle = math.pi - np.asarray(phi, dtype=float)
        return self.rho_m * np.cos(angle), self.rho_m * np.sin(angle)


def _fresnel(eps: complex, graze: np.ndarray, soft: bool) -> np.ndarray:
    """A half-space's reflection coefficient at grazing angle ``graze``: TE for the field along
    the edge (soft), TM across it."""
    s, c = np.sin(graze), np.cos(graze)
    root = np.sqrt(eps - c * c + 0j)
    return (s - root) / (s + root) if soft else (eps * s - root) / (eps * s + root)


def fdfd_total(case: WedgeCase, phi: np.ndarray, soft: bool) -> np.ndarray:
    """The full-wave field over the source's in free space, by ceviche's FDFD.

    Args:
        case: The wedge case.
        phi: Angles from the lit face, rad.
        soft: The soft (TE) polarisation; False: hard.

    Returns:
        Complex ratios (`exp(+j w t)`, as the UTD's).
    """
    free = dataclasses.replace(case, material="air")
    points = tuple(np.asarray(phi, dtype=float))
    return _fdfd(case, points, soft) / _fdfd(free, points, soft)


@functools.lru_cache(maxsize=8)
def _fdfd(case: WedgeCase, phi: tuple[float, ...], soft: bool) -> np.ndarray:
    # The field at phi with the block (free space where case.material is "air"); the free
    # space's solve is shared by the materials of one grid.
    from ceviche import fdfd_ez, fdfd_hz
    from scipy.interpolate import RegularGridInterpolator

    x, dl, (sx, sy) = case.grid()
    xx, yy = np.meshgrid(x, x, indexing="ij")
    src = np.zeros(xx.shape)
    src[np.argmin(abs(x - sx)), np.argmin(abs(x - sy))] = 1.0
    eps = 1.0 + 0.0j if case.material == "air" else case.eps
    eps_grid = np.where((xx < 0.0) & (yy < 0.0), eps, 1.0 + 0.0j)
    solver = fdfd_ez if soft else fdfd_hz
    # ceviche returns (Hx, Hy, Ez) or (Ex, Ey, Hz): the field along the edge is last.
    u = solver(2.0 * math.pi * case.freq_hz, dl, eps_grid, [PML_CELLS, PML_CELLS]).solve(src)[2]
    return RegularGridInterpolator((x, x), u)(np.c_[case.points(np.array(phi))])


def exact_pec(case: WedgeCase, phi: np.ndarray, soft: bool) -> np.ndarray:
    """The exact field of the line source on a perfectly conducting corner.

    The eigenfunction series (the module's docstring).

    Args:
        case: The wedge case.
        phi: Angles from the lit face, rad.
        soft: The soft polarisation; False: hard.

    Returns:
        Complex ratios.
    """
    from scipy.special import hankel2, jv

    rho_s, phi1 = case.source()
    k = case.k
    near, far = min(case.rho_m, rho_s), max(case.rho_m, rho_s)
    m = np.arange(0, int(N * (k * far + 80.0)))
    nu = (m / N)[:, None]
    base = jv(nu, k * near) * hankel2(nu, k * far)
    phi = np.asarray(phi, dtype=float)[None]
    if soft:
        total = (4.0 / N) * (base * np.sin(nu * phi1) * np.sin(nu * phi))[1:].sum(0)
    else:
        eps_m = np.where(m == 0, 1.0, 2.0)[:, None]
        total = (2.0 / N) * (eps_m * base * np.cos(nu * phi1) * np.cos(nu * phi)).sum(0)
    px, py = case.points(phi[0])
    _, _, (sx, sy) = case.grid()
    return total / hankel2(0, k * np.hypot(px - sx, py - sy))


FACES = ("p526", "incident")
"""Where each face's coefficient is taken: P.526's angles (``phi1`` on the lit face, ``n pi -
phi`` on the other: the engine's corners), or the incident ray's angle with each face, -1 where
it does not light the face (Sionna RT's choice after Hashimoto et al.: the engine's roof edges
beside the line)."""


def p526_coefficient(
    case: WedgeCase, phi: np.ndarray, soft: bool, faces: str = "p526"
) -> np.ndarray:
    """The standard's coefficient `D` (the ray engine's `utd_wedge`).

    Each face's P.2040 coefficient as `faces` says
    ([`FACES`][rainuav.radio.reference.wedge_fullwave.FACES]).

    Args:
        case: The wedge case.
        phi: Angles from the lit face, rad.
        soft: The soft polarisation; False: hard.
        faces: How the faces' coefficients are taken.

    Returns:
        Complex `D`.

    Raises:
        ValueError: `faces` not one of `FACES`.
    """
    from rainuav import _core

    if faces not in FACES:
        raise ValueError(f"faces is one of {', '.join(FACES)} (got {faces!r})")
    rho_s, phi1 = case.source()
    s = case.rho_m
    eps = case.eps
    r0 = complex(_fresnel(eps, np.array(phi1), soft))
    phi = np.asarray(phi, dtype=float)
    if faces == "p526":
        rn = _fresnel(eps, N * math.pi - phi, soft)
    else:  # the source (0 < phi1 < 90 degrees) does not light the far face
        rn = np.full(phi.shape, -1.0 + 0j)
    return np.array(
        [
            _core.utd_wedge(N, phi1, np.array([p]), l_m=s * rho_s / (s + rho_s), sin_beta0=1.0,
                            k=case.k, r0=r0, rn=complex(q))[0]
            for p, q in zip(np.asarray(phi, dtype=float), rn, strict=True)
        ]
    )  # fmt: skip


def utd_total(case: WedgeCase, phi: np.ndarray, soft: bool, d: np.ndarray) -> np.ndarray:
    """Geometrical optics plus the edge's diffracted field of a coefficient.

    Args:
        case: The wedge case.
        phi: Angles from the lit face, rad.
        soft: The soft polarisation; False: hard.
        d: The edge's coefficient at each angle.

    Returns:
        Complex ratios.
    """
    from scipy.special import hankel2

    phi = np.asarray(phi, dtype=float)
    rho_s, phi1 = case.source()
    _, _, (sx, sy) = case.grid()
    px, py = case.points(phi)
    k = case.k
    direct = hankel2(0, k * np.hypot(px - sx, py - sy))
    image = np.hypot(px - sx, py + sy)
    lit = (phi < math.pi + phi1).astype(complex)
    reflected = (phi < math.pi - phi1) * _fresnel(case.eps, np.arcsin((py + sy) / image), soft)
    reflected = reflected * hankel2(0, k * image) / direct
    s = case.rho_m
    diffracted = hankel2(0, k * rho_s) * d * np.exp(-1j * k * s) / math.sqrt(s) / direct
    return lit + reflected + diffracted


def tracer_coefficient(
    case: WedgeCase, phi: np.ndarray, soft: bool, coefficient: str = "sionna"
) -> np.ndarray:
    """The coefficient `D` the tracer's path solver gives for the same corner in three dimensions.

    A block of 20 m, 40 m tall, the source and the field points 20 m up: every ray meets the
    vertical edge at right angles. `|a_d / a_free| sqrt(s s' (s + s')) / r` of the edge's path, in
    the engine's sign convention (the tracer's basis across the edge points the other way: its hard
    coefficient's sign is turned).

    Args:
        case: The wedge case.
        phi: Angles from the lit face, rad.
        soft: The soft polarisation; False: hard.
        coefficient: The tracer's wedge coefficient
            ([`COEFFICIENTS`][rainuav.radio.reference.tracer_wedge.COEFFICIENTS]).

    Returns:
        Complex `D`; NaN where the path solver finds no path by that edge alone.
    """
    from rainuav.radio.reference.tracer import isotropic_scenario, load_sionna, tracer_scene
    from rainuav.radio.reference.tracer_wedge import coefficient as using
    from rainuav.radio.scene.area import Area
    from rainuav.radio.scene.scenario import Building, Scenario, Site

    mi, rt = load_sionna()
    phi = np.asarray(phi, dtype=float)
    rho_s, _ = case.source()
    _, _, (sx, sy) = case.grid()
    px, py = case.points(phi)
    z = 20.0
    scn = Scenario(
        freq_hz=case.freq_hz,
        polarization="v" if soft else "h",
        area=Area(x_min_m=-2.0, x_max_m=2.0, y_min_m=-2.0, y_max_m=2.0, altitude_m=z,
                  resolution_m=0.5),
        sites=[Site(x_m=sx, y_m=sy, height_m=z)],
        buildings=[Building(x0_m=-20.0, x1_m=0.0, y0_m=-20.0, y1_m=0.0, height_m=2 * z)],
        ground="none",
    )  # fmt: skip
    with using(coefficient):
        scene = tracer_scene(isotropic_scenario(scn), material=case.material)
        scene.add(rt.Transmitter(name="tx", position=mi.Point3f(sx, sy, z)))
        for i, (a, b) in enumerate(zip(px, py, strict=True)):
            scene.add(rt.Receiver(name=f"rx{i}", position=mi.Point3f(float(a), float(b), z)))
        paths = rt.PathSolver()(
            scene, max_depth=1, los=True, specular_reflection=False, diffuse_reflection=False,
            refraction=False, diffraction=True, edge_diffraction=True, synthetic_array=False,
            samples_per_src=10**6,
        )  # fmt: skip
    re, im = (np.asarray(v, dtype=float).reshape(len(phi), -1) for v in paths.a)
    tau = np.asarray(paths.tau, dtype=float).reshape(len(phi), -1)
    valid = np.asarray(paths.valid.numpy(), dtype=bool).reshape(len(phi), -1)
    s = case.rho_m
    # The edge's path is the one as long as source-edge-point (within a millimetre).
    by_edge = valid & (abs(tau * C - (s + rho_s)) < 1e-3)
    r = np.hypot(px - sx, py - sy)
    free = C / case.freq_hz / (4.0 * math.pi * r)
    a = np.where(by_edge, re + 1j * im, 0.0).sum(axis=1)
    d = a / free * np.sqrt(s * rho_s * (s + rho_s)) / r * (1.0 if soft else -1.0)
    return np.where(by_edge.sum(axis=1) == 1, d, np.nan)


REFERENCE_PHI_DEG = np.arange(2.0, 269.0, 2.0)
"""The field points of the reference corner, degrees from the lit face."""


def reference_corner(material: str) -> WedgeCase:
    """The corner the tests check the coefficient on.

    3.5 GHz, the source 45 degrees from the lit face and 0.3 m from the edge (``k rho = 22``),
    40 cells a wavelength.

    Args:
        material: ``"metal"`` or a P.2040 material.

    Returns:
        The case.
    """
    return WedgeCase(3.5e9, material, 45.0, 0.3, points_per_wavelength=40.0)
