"""The UTD coefficient of a wedge (ITU-R P.526-15 section 6,
`rainuav_core::propagation::diffraction::utd_wedge`) against the exact solution of a plane wave on a
perfectly conducting wedge: the eigenfunction series (Bowman, Senior and Uslenghi, Electromagnetic
and Acoustic Scattering by Simple Shapes, chapter 6), summed with SciPy's Bessel functions of
fractional order.

For a wedge of exterior angle ``n pi`` (free space for ``0 < phi < n pi``) and a plane wave from
``phi1`` (``exp(+j w t)``: ``u_i = exp(j k rho cos(phi - phi1))``), the total field is
``(4 / n) sum_{m >= 1} j^(m/n) J_(m/n)(k rho) sin(m phi1 / n) sin(m phi / n)`` for a soft wedge
(the field along the edge: vertical polarisation at a building's corner) and
``(2 / n) sum_{m >= 0} eps_m j^(m/n) J_(m/n)(k rho) cos(m phi1 / n) cos(m phi / n)`` for a hard one.
The UTD field is the geometrical optics (incident and reflected waves where they exist) plus
``D exp(-j k rho) / sqrt(rho)`` with ``L = rho``.

Tolerance 0.1 dB (1.15% of the field; in the pattern's nulls below -30 dB, 1.15% of -30 dB) at
``k rho = 60`` (a building corner 2 m away at 4.9 GHz; the UTD is asymptotic
in ``k rho``: its error falls as ``1 / (k rho)``) over every direction round the wedge, including
the shadow, both boundaries and grazing along either face, where the field vanishes on a soft
face."""

import math

import numpy as np
import pytest
from rainuav import _core
from scipy.special import jv

pytestmark = pytest.mark.timeout(60)


def _exact(n: float, phi1: float, phi: np.ndarray, krho: float, soft: bool) -> np.ndarray:
    m = np.arange(0, int(n * (krho + 60)) + 1)
    nu = (m / n)[:, None]
    terms = (1j**nu) * jv(nu, krho)
    if soft:
        return (4 / n) * (terms * np.sin(nu * phi1) * np.sin(nu * phi[None]))[1:].sum(0)
    eps = np.where(m == 0, 1.0, 2.0)[:, None]
    return (2 / n) * (eps * terms * np.cos(nu * phi1) * np.cos(nu * phi[None])).sum(0)


def _utd(n: float, phi1: float, phi: np.ndarray, krho: float, soft: bool) -> np.ndarray:
    r = -1.0 if soft else 1.0
    d = _core.utd_wedge(n, phi1, phi, l_m=krho, sin_beta0=1.0, k=1.0, r0=complex(r), rn=complex(r))
    pi = math.pi
    incident = np.exp(1j * krho * np.cos(phi - phi1)) * (phi < pi + phi1)
    from_0 = r * np.exp(1j * krho * np.cos(phi + phi1)) * (phi < pi - phi1)
    from_n = (
        r * np.exp(1j * krho * np.cos(phi - (2 * n * pi - phi1))) * (phi > (2 * n - 1) * pi - phi1)
    )
    return incident + from_0 + from_n + d * np.exp(-1j * krho) / np.sqrt(krho)


@pytest.mark.parametrize("soft", [True, False], ids=["soft", "hard"])
@pytest.mark.parametrize(("n", "phi1_deg"), [(1.5, 30.0), (1.5, 100.0), (1.75, 60.0), (2.0, 45.0)])
def test_utd_is_the_exact_wedge_solution_all_round(n: float, phi1_deg: float, soft: bool) -> None:
    krho = 60.0
    phi1 = math.radians(phi1_deg)
    # Every direction in the free space round the wedge, 0.5 degree apart, ends included
    # within a degree (grazing along both faces), boundaries moved off by a hair.
    phi = np.radians(np.arange(1.0, n * 180.0 - 0.99, 0.5)) + 1e-7
    exact, utd = _exact(n, phi1, phi, krho, soft), _utd(n, phi1, phi, krho, soft)
    # |UTD - exact| within 1.15% of the exact field (0.1 dB) wherever the field is above -30 dB
    # of the incident wave, and within 1.15% of -30 dB (3.5e-4) in the nulls of the pattern.
    scale = np.maximum(np.abs(exact), 10 ** (-30 / 20))
    ratio = np.abs(utd - exact) / scale
    worst = int(np.argmax(ratio))
    assert ratio.max() < 0.0116, (
        f"UTD {20 * np.log10(abs(utd[worst])):.2f} dB vs exact "
        f"{20 * np.log10(abs(exact[worst])):.2f} dB at {math.degrees(phi[worst]):.1f} deg"
    )


def test_a_soft_face_at_grazing_is_dark_and_the_utd_says_so() -> None:
    # 1 degree off face n of a 90 degree corner, soft: the exact field is tens of dB down.
    n, phi1, krho = 1.5, math.radians(30.0), 60.0
    phi = np.array([n * math.pi - math.radians(1.0)])
    exact = 20 * np.log10(abs(_exact(n, phi1, phi, krho, True)[0]))
    utd = 20 * np.log10(abs(_utd(n, phi1, phi, krho, True)[0]))
    assert exact < -30.0
    assert abs(utd - exact) < 0.1
