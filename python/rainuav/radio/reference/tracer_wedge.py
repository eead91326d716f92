"""The wedge diffraction coefficient the tracer
([`rainuav.radio.reference.tracer`][rainuav.radio.reference.tracer]) runs with: ITU-R P.526-15
section 6, the uniform theory of diffraction for a finitely conducting wedge (Kouyoumjian and
Pathak's coefficient with Luebbers' face coefficients), in Sionna RT's place.

Sionna RT 2.2's own coefficient (``RadioMaterial._diffraction_matrix``) groups the four UTD
terms by face, each face's pair times that face's reflection coefficient. For a perfectly
conducting wedge that is Kouyoumjian and Pathak's soft coefficient for both polarisations: the
field across the edge, which must get the hard one, is off by up to 25 dB next to a face (a
conducting block's corner, 1.3 degrees off its wall, 4.9 GHz: -53.4 dB where the hard
coefficient, the exact wedge series and the ray engine give -28.2 dB); and where the second face
is in shadow it sets that face's coefficient to -1 for both polarisations. The standard's text is
the reference for each formula, the tracer for the whole map (which paths exist, their
geometry, spreading and polarisation), so the tracer runs with the standard's coefficient,
written here in the tracer's own terms: its angles, distances, P.2040 slab coefficients and
Jones bases.

In Kouyoumjian and Pathak's edge-fixed bases (``phi`` across the edge, ``beta`` along it) the
diffracted field is ``E_beta = -D_s E'_beta`` and ``E_phi = -D_h E'_phi``, with

``D = pre [d1 + d2 + R_0 d4 + R_n d3]``, ``d1, d2 = cot((pi +- (phi - phi')) / 2n) F(k L
a+-(phi - phi'))``, ``d3, d4 = cot((pi +- (phi + phi')) / 2n) F(k L a+-(phi + phi'))``,

``R_0`` the face-0 coefficient at the incident ray's angle to that face, ``R_n`` the face-n
coefficient at the diffracted ray's (P.526-15 eq. for ``R``: ``phi1`` and ``n pi - phi2``), TE
coefficients for ``D_s`` and TM for ``D_h`` (``-1`` and ``+1`` on a perfect conductor: soft and
hard). [`install()`][rainuav.radio.reference.tracer_wedge.install] puts it in place;
``tests/test_tracer_wedge.py`` checks it against the exact wedge series through the tracer's own
path solver.
"""

from __future__ import annotations

import contextlib
import inspect
from collections.abc import Iterator
from typing import Any

__all__ = ["COEFFICIENTS", "checked", "coefficient", "install", "install_default", "installed"]

_SIGNATURE = ["self", "to_world", "ki_local", "ko_local", "si", "eta", "wavenumber"]


def _p526_diffraction_matrix(
    self: Any, to_world: Any, ki_local: Any, ko_local: Any, si: Any, eta: Any, wavenumber: Any
) -> Any:
    import drjit as dr
    import mitsuba as mi
    from sionna.rt.utils import (
        cot_times_f_utd,
        implicit_basis_vector,
        itu_coefficients_single_layer_slab,
        jones_matrix_from_real_imag,
        jones_matrix_rotator,
        wedge_interior_angle,
    )

    # The wedge in the tracer's local frame: face 0 normal to z, the edge e, the faces' normals
    # outward (as Sionna RT builds them).
    e_hat, nn, n0 = si.dn_du, si.dn_dv, mi.Vector3f(0, 0, 1)
    exterior = dr.two_pi - wedge_interior_angle(n0, nn)
    n = exterior * dr.rcp(dr.pi)
    beta0 = dr.safe_acos(dr.abs(dr.dot(ki_local, e_hat)))
    s, s_prime = si.dp_du.x, si.dp_du.y
    t0 = dr.normalize(dr.cross(n0, e_hat))
    ki_p = dr.normalize(ki_local - dr.dot(ki_local, e_hat) * e_hat)
    ko_p = dr.normalize(ko_local - dr.dot(ko_local, e_hat) * e_hat)
    # The incidence and diffraction angles from face 0, 0 < phi < n pi.
    phi_i = dr.pi - (dr.pi - dr.safe_acos(-dr.dot(ki_p, t0))) * dr.sign(-dr.dot(ki_p, n0))
    phi_d = dr.pi - (dr.pi - dr.safe_acos(dr.dot(ko_p, t0))) * dr.sign(dr.dot(ko_p, n0))
    kl = wavenumber * s * s_prime * dr.rcp(s + s_prime) * dr.sin(beta0) ** 2
    pre = -dr.exp(mi.Complex2f(0, -dr.pi / 4))
    pre *= dr.rcp(2 * n * dr.safe_sqrt(dr.two_pi * wavenumber) * dr.sin(beta0))

    def term(beta: Any, sign: float) -> Any:
        # cot((pi + sign beta) / 2n) F(k L a(beta)), a = 2 cos^2((2 n pi N - beta) / 2) with N
        # the integer nearest (beta + sign pi) / (2 n pi).
        big_n = dr.round((beta + sign * dr.pi) * dr.rcp(2 * exterior))
        a = 2 * dr.cos(exterior * big_n - beta / 2) ** 2
        return pre * cot_times_f_utd((dr.pi + sign * beta) * dr.rcp(2 * n), kl * a, n, kl)

    d1, d2 = term(phi_d - phi_i, 1.0), term(phi_d - phi_i, -1.0)
    d3, d4 = term(phi_d + phi_i, 1.0), term(phi_d + phi_i, -1.0)
    wavelength = dr.two_pi / wavenumber
    r_te_0, r_tm_0, _, _ = itu_coefficients_single_layer_slab(
        dr.abs(dr.dot(ki_local, n0)), eta, self._d, wavelength
    )
    r_te_n, r_tm_n, _, _ = itu_coefficients_single_layer_slab(
        dr.abs(dr.dot(ko_local, nn)), eta, self._d, wavelength
    )
    rough = dr.sqrt(1.0 - dr.square(self._s))  # as the tracer's own reflections
    d_soft = d1 + d2 + rough * (r_te_0 * d4 + r_te_n * d3)
    d_hard = d1 + d2 + rough * (r_tm_0 * d4 + r_tm_n * d3)
    # The tracer orders the edge-fixed bases phi first: diag(-D_h, -D_s).
    real = mi.Matrix2f(-d_hard.real, 0, 0, -d_soft.real)
    imag = mi.Matrix2f(-d_hard.imag, 0, 0, -d_soft.imag)
    phi_in = dr.normalize(dr.cross(ki_local, e_hat))
    phi_out = -dr.normalize(dr.cross(ko_local, e_hat))
    theta_in = to_world.T @ implicit_basis_vector(to_world @ ki_local)
    theta_out = to_world.T @ implicit_basis_vector(to_world @ ko_local)
    w_in = jones_matrix_rotator(ki_local, theta_in, phi_in)
    w_out = jones_matrix_rotator(ko_local, phi_out, theta_out)
    return jones_matrix_from_real_imag(w_out @ real @ w_in, w_out @ imag @ w_in)


COEFFICIENTS = ("p526", "sionna")
"""The wedge coefficients the tracer can run with: ``"p526"``, the one above (the default), and
``"sionna"``, Sionna RT 2.2's own, as released."""


def checked(name: str) -> str:
    """A wedge coefficient's name, checked.

    Args:
        name: The name.

    Returns:
        It, where it is one of [`COEFFICIENTS`][rainuav.radio.reference.tracer_wedge.COEFFICIENTS].

    Raises:
        ValueError: Another name (the allowed ones named).
    """
    if name not in COEFFICIENTS:
        raise ValueError(f"coefficient is one of {', '.join(COEFFICIENTS)} (got {name!r})")
    return name


_RELEASED: dict[str, Any] = {}
"""Sionna RT's own ``_diffraction_matrix``, kept the first time it is replaced."""


def install(coefficient: str = "p526") -> None:
    """Makes Sionna RT diffract at wedges with a coefficient: the standard's or the tracer's own.

    Args:
        coefficient: One of [`COEFFICIENTS`][rainuav.radio.reference.tracer_wedge.COEFFICIENTS]: the
            standard's (the module's docstring) or the tracer's own as released.

    Raises:
        ValueError: Another name.
        ImportError: A tracer version with no such method to replace.
    """
    checked(coefficient)
    from sionna.rt.radio_materials.radio_material import RadioMaterial

    own = getattr(RadioMaterial, "_diffraction_matrix", None)
    if "own" not in _RELEASED:
        if own is None or list(inspect.signature(own).parameters) != _SIGNATURE:
            raise ImportError(
                "this sionna-rt has no RadioMaterial._diffraction_matrix(to_world, ki_local, "
                "ko_local, si, eta, wavenumber) to replace: the tracer needs sionna-rt 2.2"
            )
        _RELEASED["own"] = own
    RadioMaterial._diffraction_matrix = (
        _p526_diffraction_matrix if coefficient == "p526" else _RELEASED["own"]
    )


def install_default() -> None:
    """Installs the standard's coefficient the first time the tracer is loaded; later calls
    leave in place whichever coefficient runs now (a
    [`coefficient()`][rainuav.radio.reference.tracer_wedge.coefficient] block's)."""
    if "own" not in _RELEASED:
        install("p526")


def installed() -> str:
    """The coefficient the tracer diffracts with now.

    Returns:
        Its name ("sionna" before any [`install()`][rainuav.radio.reference.tracer_wedge.install]).
    """
    from sionna.rt.radio_materials.radio_material import RadioMaterial

    own = getattr(RadioMaterial, "_diffraction_matrix", None)
    return "p526" if own is _p526_diffraction_matrix else "sionna"


@contextlib.contextmanager
def coefficient(name: str) -> Iterator[None]:
    """A context in which the tracer diffracts with a coefficient; the one it had is put back after.

    The tracer is loaded first ([`load_sionna()`][rainuav.radio.reference.tracer.load_sionna], which
    installs the default).

    Args:
        name: One of [`COEFFICIENTS`][rainuav.radio.reference.tracer_wedge.COEFFICIENTS].

    Yields:
        Nothing.

    Raises:
        RuntimeError: The tracer not loaded yet (the coefficient it had would not be the default).
    """
    checked(name)
    if "own" not in _RELEASED:
        raise RuntimeError("load the tracer first: rainuav.radio.reference.tracer.load_sionna()")
    before = installed()
    install(name)
    try:
        yield
    finally:
        install(before)
