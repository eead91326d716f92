"""The tracer as a reference at building corners
([`rainuav.radio.reference.tracer`][rainuav.radio.reference.tracer],
[`rainuav.radio.reference.tracer_wedge`][rainuav.radio.reference.tracer_wedge]).

- Its buildings are closed meshes whose faces share their edges: the tracer diffracts at a
  wedge only where two faces share an edge (an edge of one face alone is a half-plane). Checked
  exactly on the arrays: every edge in two faces, once each way; the volume is the footprint's
  area times the height (faces outward).
- One diffraction at a block's corner, through the tracer's own path solver, equals the UTD
  coefficient of ITU-R P.526-15 section 6 as the ray engine computes it
  (``rainuav_core::propagation::diffraction::utd_wedge``, itself within 0.1 dB of the exact wedge
  series: ``tests/test_wedge_exact.py``), for the field along the edge (soft) and across it (hard),
  on a conducting block and on a concrete one. Tolerance 0.2 dB on the conducting block (the tracer
  computes in single precision; its "metal" conducts 1e7 S/m, not infinitely) and 0.5 dB on the
  concrete one (the tracer's walls are 0.3 m slabs, the engine's half-spaces: at 4.9 GHz the slab's
  far face returns less than -50 dB). Sionna RT 2.2's own coefficient gives the soft value for both
  polarisations: 25 dB off at the first point for the hard one.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from rainuav import _core
from rainuav.radio.reference.tracer import prism_arrays

pytestmark = pytest.mark.timeout(300)

L_SHAPE = shapely.Polygon([(0, 0), (40, 0), (40, 10), (10, 10), (10, 30), (0, 30)])
COURTYARD = shapely.Polygon(
    [(0, 0), (50, 0), (50, 40), (0, 40)], holes=[[(10, 10), (10, 30), (40, 30), (40, 10)]]
)


@pytest.mark.parametrize("polygon", [L_SHAPE, COURTYARD], ids=["L", "courtyard"])
def test_the_tracer_meshes_are_closed_and_share_their_edges(polygon: shapely.Polygon) -> None:
    v, f = prism_arrays(polygon, 2.0, 17.0)
    directed = [(int(a), int(b)) for tri in f for a, b in zip(tri, np.roll(tri, -1), strict=True)]
    assert len(set(directed)) == len(directed)  # each directed edge once: orientation agrees
    assert all((b, a) in set(directed) for a, b in directed)  # and shared by two faces
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    volume = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0
    assert volume == pytest.approx(polygon.area * 15.0, rel=1e-9)


SITE = (10.0, 0.0, 25.0)
CORNER = (60.0, 20.0)  # the box's corner on the site's left, 30 m tall
FREQ = 4.9e9
# Pixels (x, y, 20 m) behind the box that only this corner reaches: 2 m off the side wall's
# plane (1.3 degrees), 20 m off it, and 4 m inside the shadow boundary.
POINTS = [(146.0, 22.0, 20.0), (146.0, 40.0, 20.0), (130.0, 44.0, 20.0)]


def _angle_from_front_face(p: tuple[float, ...]) -> float:
    # The front face runs from the corner towards -y; angles grow through the site's side.
    return (math.atan2(-1.0, 0.0) - math.atan2(p[1] - CORNER[1], p[0] - CORNER[0])) % (2 * math.pi)


def _utd_gain_db(q: tuple[float, ...], soft: bool, eps: complex | None) -> float:
    """The gain of the corner's diffracted ray re free space, as the ray engine's UTD gives it."""
    r1 = math.hypot(SITE[0] - CORNER[0], SITE[1] - CORNER[1])
    r2 = math.hypot(q[0] - CORNER[0], q[1] - CORNER[1])
    zv = SITE[2] + (q[2] - SITE[2]) * r1 / (r1 + r2)
    s1, s2 = math.hypot(r1, zv - SITE[2]), math.hypot(r2, q[2] - zv)
    sin_b = r1 / s1
    phi1, phi2 = _angle_from_front_face(SITE), _angle_from_front_face(q)

    def face(graze: float) -> complex:
        if eps is None:
            return -1.0 if soft else 1.0
        s, c = math.sin(graze), math.cos(graze)
        root = complex(eps - c * c) ** 0.5
        # Along the edge the field is across the plane of incidence (TE), else in it (TM).
        return (s - root) / (s + root) if soft else (eps * s - root) / (eps * s + root)

    # Each face's grazing angle: the incident ray's on face 0, the diffracted ray's on face n.
    g0 = math.asin(abs(math.sin(phi1)) * sin_b)
    gn = math.asin(abs(math.sin(1.5 * math.pi - phi2)) * sin_b)
    k = 2 * math.pi * FREQ / 299792458.0
    d = _core.utd_wedge(1.5, phi1, np.array([phi2]), l_m=s1 * s2 * sin_b**2 / (s1 + s2),
                        sin_beta0=sin_b, k=k, r0=face(g0), rn=face(gn))[0]  # fmt: skip
    dist = math.dist(SITE, q)
    return 10 * math.log10(abs(d) ** 2 * dist**2 / (s1 * s2 * (s1 + s2)))


def _tracer_gain_db(q: tuple[float, ...], pol: str, material: str) -> list[float]:
    """Each path the tracer finds from the site to ``q`` (the box scene), dB re free space."""
    from rainuav.radio.reference.tracer import isotropic_scenario, load_sionna, tracer_scene
    from rainuav.radio.reference.tracer_scenes import scene

    mi, rt = load_sionna()
    sc = tracer_scene(isotropic_scenario(scene("box", FREQ, 20.0, pol)), material=material)
    sc.add(rt.Transmitter(name="tx", position=mi.Point3f(*SITE)))
    sc.add(rt.Receiver(name="rx", position=mi.Point3f(*q)))
    paths = rt.PathSolver()(sc, max_depth=2, los=True, specular_reflection=True,
                            diffuse_reflection=False, refraction=False, diffraction=True,
                            edge_diffraction=True, synthetic_array=False)  # fmt: skip
    re, im = paths.a
    a = (np.asarray(re) + 1j * np.asarray(im)).ravel()[np.asarray(paths.valid.numpy()).ravel()]
    free = (299792458.0 / FREQ / (4 * math.pi * math.dist(SITE, q))) ** 2
    return [10 * math.log10(abs(x) ** 2 / free) for x in a]


@pytest.mark.slow
@pytest.mark.parametrize(("material", "tol"), [("metal", 0.2), ("concrete", 0.5)])
@pytest.mark.parametrize("pol", ["v", "h"])
def test_one_corner_diffraction_in_the_tracer_is_the_p526_wedge(pol, material, tol) -> None:
    pytest.importorskip("sionna.rt")
    f_ghz = FREQ / 1e9
    eps = None if material == "metal" else 5.24 - 1j * 0.0462 * f_ghz**0.7822 / (
        2 * math.pi * FREQ * 8.854187817e-12)  # fmt: skip
    for q in POINTS:
        got = _tracer_gain_db(q, pol, material)
        assert len(got) == 1, (q, got)  # the corner's ray alone
        assert got[0] == pytest.approx(_utd_gain_db(q, pol == "v", eps), abs=tol), q
