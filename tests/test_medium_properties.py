"""Invariants of the rain medium (hypothesis) and the wind models."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st
from rainuav import medium as m

freqs = st.floats(1e9, 1e12)
rates = st.floats(0.01, 400.0)
models = st.sampled_from(m.MODELS)
pols = st.sampled_from(m.POLARIZATIONS)
shapes = st.sampled_from(m.SHAPES)
temps = st.floats(0.0, 40.0)
winds = st.floats(0.0, 60.0)


@given(freqs, rates, rates, models, pols, shapes, temps)
def test_attenuation_rises_with_rain_rate(f, r1, r2, model, pol, shape, t) -> None:
    lo, hi = sorted((r1, r2))
    g = m.specific_attenuation(
        f, [lo, hi], model=model, polarization=pol, shape=shape, temperature_c=t
    )
    assert g[0] <= g[1]
    assert g[0] > 0.0


@given(freqs, rates, models, pols, shapes, temps, winds, st.sampled_from(m.WIND_MODELS))
def test_permittivity_is_lossy(f, r, model, pol, shape, t, w, wind_model) -> None:
    eps = m.effective_permittivity(
        f,
        r,
        model=model,
        polarization=pol,
        shape=shape,
        temperature_c=t,
        wind_speed_m_s=w,
        wind_model=wind_model,
    )
    assert eps.imag <= 0.0
    assert np.isfinite(eps)


@given(freqs, rates, models, temps, winds)
def test_spheres_do_not_see_polarisation(f, r, model, t, w) -> None:
    kw = {"model": model, "shape": "sphere", "temperature_c": t, "wind_speed_m_s": w}
    h = m.effective_permittivity(f, r, polarization="h", **kw)
    v = m.effective_permittivity(f, r, polarization="v", **kw)
    avg = m.effective_permittivity(f, r, polarization="average", **kw)
    assert h == v == avg


@given(freqs, rates, models, pols, shapes, st.sampled_from(m.WIND_MODELS))
def test_zero_wind_equals_no_wind(f, r, model, pol, shape, wind_model) -> None:
    kw = {"model": model, "polarization": pol, "shape": shape}
    assert m.effective_permittivity(f, r, wind_speed_m_s=0.0, wind_model=wind_model, **kw) == (
        m.effective_permittivity(f, r, **kw)
    )


@given(freqs, rates, models, shapes, winds)
def test_canting_only_moves_polarisability_between_h_and_v(f, r, model, shape, w) -> None:
    # beta_h' + beta_v' = beta_x + beta_z whatever the canting angle, and both models are
    # linear in beta (n - 1 for forward scattering, eps - 1 for quasi-static): the H + V sum
    # is wind-independent to rounding.
    fn = m.effective_index if model == "forward-scattering" else m.effective_permittivity
    kw = {"model": model, "shape": shape}
    windy = fn(f, r, polarization="h", wind_speed_m_s=w, **kw) + fn(
        f, r, polarization="v", wind_speed_m_s=w, **kw
    )
    still = fn(f, r, polarization="h", **kw) + fn(f, r, polarization="v", **kw)
    # The sums are ~2 (two indices near 1), so rounding alone is a few 1e-16 absolute.
    assert abs(windy - still) <= 1e-9 * abs(still - 2) + 2e-15


def test_wind_cants_drops_towards_the_other_polarisation() -> None:
    # Oblate drops: H attenuates more than V in still air; a light wind tilts drops (by
    # 18-32 degrees at 3 m/s, below the 45 that would swap H and V) so the two approach.
    f, r = 30e9, 50.0
    gh0, gv0 = (m.specific_attenuation(f, r, polarization=p) for p in "hv")
    gh, gv = (m.specific_attenuation(f, r, polarization=p, wind_speed_m_s=3.0) for p in "hv")
    assert gh0 > gv0
    assert gv0 < gv <= gh < gh0


def test_paper_wind_factor_only_adds() -> None:
    # The paper's 1/F factor is >= 1 on every drop and grows with wind.
    g = [
        m.specific_attenuation(10e9, 25.0, wind_model="paper", wind_speed_m_s=w)
        for w in (0.0, 2.0, 5.0)
    ]
    assert g[0] < g[1] < g[2]


def test_broadcasting_and_scalars() -> None:
    f = np.array([5e9, 10e9, 20e9])[:, None]
    r = np.array([0.0, 10.0])
    g = m.specific_attenuation(f, r)
    assert g.shape == (3, 2)
    assert np.all(g[:, 0] == 0.0)
    eps = m.effective_permittivity(f, r)
    assert eps.dtype == np.complex128
    assert np.all(eps[:, 0] == 1.0)
    assert isinstance(m.specific_attenuation(5e9, 10.0), float)
    assert isinstance(m.effective_permittivity(5e9, 10.0), complex)
    # A non-contiguous view is accepted.
    fv = np.linspace(5e9, 50e9, 20)[::2]
    np.testing.assert_array_equal(
        m.specific_attenuation(fv, 10.0), m.specific_attenuation(fv.copy(), 10.0)
    )


def test_other_distributions() -> None:
    # A gamma with the Marshall-Palmer parameters is Marshall-Palmer.
    mp_again = m.gamma_dsd(8000.0, 0.0, 4.1, -0.21)
    assert m.specific_attenuation(20e9, 30.0, dsd=mp_again) == m.specific_attenuation(20e9, 30.0)
    # A table sampled densely from Marshall-Palmer, evaluated at its own rain rate, gives
    # Marshall-Palmer's attenuation at the rate that produced it up to the table's
    # interpolation error and its different rain-rate bookkeeping (Atlas velocity): compare
    # at the table's rate, where N(D) is the table, against MP evaluated on the same N.
    d = np.linspace(0.1, 8.0, 400)
    table = m.tabulated_dsd(d, m.marshall_palmer(d, 25.0))
    g_table = m.specific_attenuation(20e9, table.table_rain_rate_mm_h, dsd=table)
    g_mp = m.specific_attenuation(20e9, 25.0)
    # Linear interpolation of exp(-2.1 D) on a 0.02 mm grid: ~1e-4 relative.
    assert abs(g_table / g_mp - 1) < 1e-3
    # Joss drizzle has many small drops and attenuates less than thunderstorm rain.
    assert m.specific_attenuation(20e9, 10.0, dsd="joss-drizzle") < m.specific_attenuation(
        20e9, 10.0, dsd="joss-thunderstorm"
    )
