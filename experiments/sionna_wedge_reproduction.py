"""Sionna RT 2.2's wedge diffraction on a concrete corner against a full-wave solution: a
reproduction that needs only Sionna RT, ceviche, NumPy and SciPy (not rainuav).

    pip install "sionna-rt>=2.2,<3" ceviche scipy
    python experiments/sionna_wedge_reproduction.py

The scene: one block of ITU concrete (x in [-20, 0] m, y in [-20, 0] m, 40 m tall), its vertical
corner at the origin; a transmitter 0.5 m from the corner at 20 m, 45 degrees from the face y =
0 (the lit face); receivers at 20 m on the circle of 0.5 m round the corner, in the shadow of the
face x = 0 (235-265 degrees from the lit face). Every ray meets the edge at right angles, so the
problem is two-dimensional and a 2-D full-wave solution holds: ceviche's finite-difference
frequency-domain solver (40 cells a wavelength, a line source at the transmitter's place). In the
shadow only the edge's diffracted field is there, so each method gives the diffraction
coefficient's magnitude |D| (m^1/2):

- the full wave: ``|u(P) / u_free(P)| |H0(k r)| sqrt(s) / |H0(k s')|`` (``r`` source to
  receiver, ``s`` and ``s'`` edge to receiver and to source, ``H0`` the Hankel function of the
  second kind);
- Sionna RT's path solver: ``|a / a_free| sqrt(s s' (s + s')) / r`` of the path by the edge;
- ITU-R P.526-15 section 6 (Kouyoumjian and Pathak's coefficient with Luebbers' face
  coefficients: ``D = d1 + d2 + R0 d4 + Rn d3`` times the prefactor, ``R0`` the lit face's
  Fresnel coefficient at the source's grazing angle, ``Rn`` the shadowed face's at the diffracted
  ray's), written out below.

What it shows (3.5 GHz; vertical polarisation is the field along the edge, horizontal across it):
P.526's coefficient is within a few tenths of a dB of the full wave for both polarisations; the
tracer's, which weights each face's pair of terms by that face's Fresnel coefficient at the
incident ray's angle (``R0 (d1 - d4) + Rn (d2 - d3)``, ``Rn = -1`` where the far face is not
lit), is several dB off for the field across the edge. About two minutes on 2 cores.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.interpolate import RegularGridInterpolator
from scipy.special import fresnel, hankel2

C = 299_792_458.0
FREQ = 3.5e9
K = 2 * math.pi * FREQ / C
EPS0 = 8.854187817e-12
# ITU-R P.2040 concrete: eps_r 5.24, sigma = 0.0462 f_GHz^0.7822 S/m.
EPS = 5.24 - 1j * 0.0462 * (FREQ / 1e9) ** 0.7822 / (2 * math.pi * FREQ * EPS0)
RHO, PHI1 = 0.5, math.radians(45.0)
PHI = np.radians(np.arange(235.0, 266.0, 5.0))
N = 1.5  # the exterior angle over pi: a right-angled corner


def place(phi: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """(x, y) at ``RHO`` from the corner, ``phi`` from the lit face (the face y = 0, x < 0)."""
    a = math.pi - np.asarray(phi)
    return RHO * np.cos(a), RHO * np.sin(a)


def fresnel_face(graze: np.ndarray | float, vertical: bool) -> np.ndarray:
    """A concrete half-space's coefficient at grazing angle ``graze``: TE for the field along
    the (vertical) edge, TM across it."""
    s, c = np.sin(graze), np.cos(graze)
    root = np.sqrt(EPS - c * c + 0j)
    return (s - root) / (s + root) if vertical else (EPS * s - root) / (EPS * s + root)


def transition(x: np.ndarray) -> np.ndarray:
    """Kouyoumjian and Pathak's ``F(X) = 2 j sqrt(X) exp(jX) int_sqrt(X)^inf exp(-j t^2) dt``."""
    v = np.sqrt(2 * x / math.pi)
    s, c = fresnel(v)
    tail = math.sqrt(math.pi / 2) * ((0.5 - c) - 1j * (0.5 - s))
    return 2j * np.sqrt(x) * np.exp(1j * x) * tail


def p526(phi: np.ndarray, vertical: bool, s: float, s_prime: float) -> np.ndarray:
    """ITU-R P.526-15 section 6's coefficient at normal incidence (module docstring)."""
    big_l = s * s_prime / (s + s_prime)

    def term(beta: np.ndarray, sign: float) -> np.ndarray:
        big_n = np.round((beta + sign * math.pi) / (2 * N * math.pi))
        a = 2 * np.cos((2 * N * math.pi * big_n - beta) / 2) ** 2
        return transition(K * big_l * a) / np.tan((math.pi + sign * beta) / (2 * N))

    r0 = fresnel_face(PHI1, vertical)
    rn = fresnel_face(N * math.pi - phi, vertical)
    pre = -np.exp(-1j * math.pi / 4) / (2 * N * math.sqrt(2 * math.pi * K))
    d = term(phi - PHI1, 1) + term(phi - PHI1, -1) + r0 * term(phi + PHI1, -1)
    return pre * (d + rn * term(phi + PHI1, 1))


def full_wave(vertical: bool) -> tuple[np.ndarray, float, float]:
    """|D| by ceviche's FDFD (module docstring), and the source's snapped distance and the
    grid's cell size."""
    from ceviche import fdfd_ez, fdfd_hz

    dl, pml = C / FREQ / 40, 30
    cells = round(2.3 * RHO / dl) + 2 * pml
    x = (np.arange(cells) - cells / 2 + 0.5) * dl  # the faces fall on cell boundaries
    xx, yy = np.meshgrid(x, x, indexing="ij")
    sx, sy = place(PHI1)
    i, j = np.argmin(abs(x - sx)), np.argmin(abs(x - sy))
    sx, sy = x[i], x[j]
    src = np.zeros(xx.shape)
    src[i, j] = 1.0
    px, py = place(PHI)
    solver = fdfd_ez if vertical else fdfd_hz

    def field(eps: np.ndarray) -> np.ndarray:
        u = solver(2 * math.pi * FREQ, dl, eps, [pml, pml]).solve(src)[2]
        return RegularGridInterpolator((x, x), u)(np.c_[px, py])

    ratio = field(np.where((xx < 0) & (yy < 0), EPS, 1.0 + 0j)) / field(np.ones(xx.shape) + 0j)
    s_prime = math.hypot(sx, sy)
    r = np.hypot(px - sx, py - sy)
    d = np.abs(ratio) * np.abs(hankel2(0, K * r)) * math.sqrt(RHO) / abs(hankel2(0, K * s_prime))
    return d, s_prime, (sx, sy)


def tracer(vertical: bool, source: tuple[float, float]) -> np.ndarray:
    """|D| by Sionna RT's path solver (module docstring)."""
    import os

    for lib in (
        "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so",
        "/usr/lib/aarch64-linux-gnu/libLLVM.so.19.1", "/usr/lib/llvm-19/lib/libLLVM.so.1",
    ):  # fmt: skip
        if os.path.exists(lib):  # Debian's libllvm19: Dr.Jit's CPU backend
            os.environ.setdefault("DRJIT_LIBLLVM_PATH", lib)
    import mitsuba as mi

    for variant in ("cuda_ad_mono_polarized", "llvm_ad_mono_polarized"):
        try:  # a GPU where there is one, else the CPU
            mi.set_variant(variant)
            break
        except (ImportError, AttributeError, RuntimeError):
            continue
    import sionna.rt as rt

    scene = rt.load_scene()
    scene.frequency = FREQ
    # A closed box, each corner one vertex shared by its faces (the tracer diffracts where two
    # faces share an edge), faces outward.
    v = np.array([[x, y, z] for z in (0.0, 40.0) for x, y in
                  ((-20, -20), (0, -20), (0, 0), (-20, 0))], dtype=np.float32)  # fmt: skip
    f = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7]]
                 + [[a, b, b + 4] for a, b in ((0, 1), (1, 2), (2, 3), (3, 0))]
                 + [[a, b + 4, a + 4] for a, b in ((0, 1), (1, 2), (2, 3), (3, 0))],
                 dtype=np.uint32)  # fmt: skip
    mesh = mi.Mesh("box", 8, 12)
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float(v.ravel())
    params["faces"] = mi.UInt32(f.ravel())
    params.update()
    concrete = rt.ITURadioMaterial(name="concrete", itu_type="concrete", thickness=0.3)
    scene.edit(add=[rt.SceneObject(mi_mesh=mesh, name="box", radio_material=concrete)])
    pol = "V" if vertical else "H"
    scene.tx_array = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization=pol)
    scene.rx_array = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization=pol)
    sx, sy = (float(v) for v in source)
    scene.add(rt.Transmitter(name="tx", position=mi.Point3f(sx, sy, 20.0)))
    px, py = place(PHI)
    for n, (a, b) in enumerate(zip(px, py, strict=True)):
        scene.add(rt.Receiver(name=f"rx{n}", position=mi.Point3f(float(a), float(b), 20.0)))
    paths = rt.PathSolver()(scene, max_depth=1, los=True, specular_reflection=False,
                            diffuse_reflection=False, refraction=False, diffraction=True,
                            edge_diffraction=True, synthetic_array=False)  # fmt: skip
    re, im = (np.asarray(x, dtype=float).reshape(len(PHI), -1) for x in paths.a)
    tau = np.asarray(paths.tau, dtype=float).reshape(len(PHI), -1)
    valid = np.asarray(paths.valid.numpy(), dtype=bool).reshape(len(PHI), -1)
    s_prime = math.hypot(sx, sy)
    by_edge = valid & (abs(tau * C - (RHO + s_prime)) < 1e-3)
    a = np.abs(np.where(by_edge, re + 1j * im, 0).sum(axis=1))
    r = np.hypot(px - sx, py - sy)
    return a * (4 * math.pi * r * FREQ / C) * math.sqrt(RHO * s_prime * (RHO + s_prime)) / r


def main() -> None:
    print("|D| in dB (m^1/2), concrete corner, 3.5 GHz, source 0.5 m from the edge at 45 deg")
    print("pol  phi   full wave   P.526   Sionna RT 2.2   (P.526 - full, Sionna - full)")
    for vertical in (True, False):
        full, s_prime, source = full_wave(vertical)
        ours = np.abs(p526(PHI, vertical, RHO, s_prime))
        theirs = tracer(vertical, source)
        for k, phi in enumerate(PHI):
            f, p, t = (20 * math.log10(x[k]) for x in (full, ours, theirs))
            print(f" {'V' if vertical else 'H'}  {math.degrees(phi):5.0f}  {f:9.2f} {p:8.2f} "
                  f"{t:10.2f}      ({p - f:+.2f}, {t - f:+.2f})")  # fmt: skip


if __name__ == "__main__":
    main()
