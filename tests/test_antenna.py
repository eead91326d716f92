"""Antenna patterns against the standard's defining values, the uniform array's closed form,
and an integration over the sphere that does not share the library's quadrature."""

from __future__ import annotations

import math

import numpy as np
import pytest
import rainuav
from rainuav import antenna


def riemann_mean(pattern, d_el: float = 0.1, d_az: float = 0.25, focus=None) -> float:
    """(1 / 4 pi) integral G dOmega by the midpoint rule in (elevation, azimuth) angle with
    the cos(elevation) weight: a different rule from antenna.sphere_mean (Gauss-Legendre in
    sin(elevation)), so agreement checks the normalisation, not the rule against itself.
    ``focus = (az0, az1, el0, el1, step)``: that window (edges on the coarse grid) is summed
    on a finer grid instead, for narrow beams."""

    def cells(lo: float, hi: float, d: float) -> np.ndarray:
        return np.arange(lo + d / 2, hi, d)

    def riemann(az: np.ndarray, el: np.ndarray, d_az: float, d_el: float, skip=None) -> float:
        total = 0.0
        for chunk in np.array_split(el, max(1, len(el) // 100)):
            g = 10 ** (pattern.gain_dbi(az[None, :], chunk[:, None]) / 10)
            w = np.cos(np.radians(chunk))[:, None] * np.ones_like(az)[None, :]
            if skip is not None:
                a0, a1, e0, e1 = skip
                inside = (az[None, :] > a0) & (az[None, :] < a1)
                inside = inside & (chunk[:, None] > e0) & (chunk[:, None] < e1)
                w = np.where(inside, 0.0, w)
            total += float((g * w).sum())
        return total * math.radians(d_el) * math.radians(d_az)

    az, el = cells(-180, 180, d_az), cells(-90, 90, d_el)
    if focus is None:
        return riemann(az, el, d_az, d_el) / (4 * math.pi)
    a0, a1, e0, e1, step = focus
    coarse = riemann(az, el, d_az, d_el, skip=(a0, a1, e0, e1))
    fine = riemann(cells(a0, a1, step), cells(e0, e1, step), step, step)
    return (coarse + fine) / (4 * math.pi)


def test_tr38901_element_defining_values() -> None:
    # TR 38.901 Table 7.3-1: 8 dBi peak, 3 dB down at half of the 65 degree widths in both
    # planes, 30 dB front-to-back, SLA_V 30 dB. The formula is exact: 1e-12.
    e = antenna.tr38901_element()
    az = np.array([0.0, 32.5, -32.5, 0.0, 0.0, 180.0, 180.0, 0.0])
    el = np.array([0.0, 0.0, 0.0, 32.5, -32.5, 0.0, 60.0, 90.0])
    want = [8.0, 5.0, 5.0, 5.0, 5.0, -22.0, -22.0, 8.0 - 12 * (90 / 65) ** 2]
    np.testing.assert_allclose(e.gain_dbi(az, el), want, rtol=0, atol=1e-12)
    # Azimuth wraps: 190 degrees is -170.
    assert e.gain_dbi(190.0, 0.0) == pytest.approx(float(e.gain_dbi(-170.0, 0.0)), abs=1e-12)


def test_tr38901_element_radiates_two_thirds_of_an_isotrope() -> None:
    # With its 8 dBi peak and 65 degree widths the standard's element integrates to 0.657 of
    # 4 pi (directivity of a 65 x 65 degree beam ~9.8 dBi): two rules agree within 0.5%.
    e = antenna.tr38901_element()
    gl, mid = antenna.sphere_mean(e), riemann_mean(e, d_el=0.05, d_az=0.1)
    assert gl == pytest.approx(mid, rel=5e-3)
    assert 0.64 < gl < 0.67


def _first_sidelobe_db(n: int, d: float) -> float:
    """Closed form of a uniform array: |sin(n psi/2) / (n sin(psi/2))|^2 between its first
    and second nulls (psi = 2 pi / n .. 4 pi / n)."""
    psi = np.linspace(2 * np.pi / n, 4 * np.pi / n, 20001)[1:-1]
    return float(10 * np.log10((np.sin(n * psi / 2) / (n * np.sin(psi / 2))) ** 2).max())


def test_uniform_array_steering_nulls_sidelobes_and_width() -> None:
    arr = antenna.uniform_array(rows=8, spacing=0.5, electrical_tilt_deg=-10.0)
    # The array factor peaks at the steering elevation at 10 log10(rows), exactly.
    assert float(arr.array_gain_db(0.0, -10.0)) == pytest.approx(10 * math.log10(8), abs=1e-9)
    # Nulls where psi = 2 pi k / N: sin e = sin e0 + k / (N d).
    s0 = math.sin(math.radians(-10.0))
    ks = [k for k in range(-7, 8) if k and abs(s0 + k / 4) <= 1]
    nulls = np.degrees(np.arcsin([s0 + k / 4 for k in ks]))
    assert np.all(arr.array_gain_db(0.0, nulls) < -100.0)
    # First sidelobe against the closed form (-12.8 dB for 8 elements), on a 0.01 degree cut.
    el = np.arange(-90, 90, 0.01)
    af = arr.array_gain_db(0.0, el) - 10 * math.log10(8)
    side = af[(el > nulls[ks.index(1)] + 0.1) & (el < nulls[ks.index(2)] - 0.1)].max()
    assert side == pytest.approx(_first_sidelobe_db(8, 0.5), abs=0.05)
    # Half-power width of the whole pattern: 0.886 / (N d) rad at broadside, widened by
    # 1 / cos(e0) when steered (12.9 degrees); the element's slope near -10 degrees shifts the
    # edges by a little, so 0.4 degrees.
    g = arr.gain_dbi(0.0, el)
    hp = el[g >= g.max() - 3.0]
    want = math.degrees(0.886 / 4) / math.cos(math.radians(10))
    assert hp.max() - hp.min() == pytest.approx(want, abs=0.4)


@pytest.mark.slow
@pytest.mark.parametrize(
    "kwargs",
    [
        {"rows": 8, "spacing": 0.5, "electrical_tilt_deg": -10.0},
        {"rows": 4, "spacing": 0.8, "electrical_tilt_deg": 0.0},
        {"rows": 8, "spacing": 0.5, "electrical_tilt_deg": -6.0, "columns": 4},
    ],
)
def test_uniform_array_integrates_to_4_pi(kwargs) -> None:
    # The bar: the normalised pattern integrates to 4 pi within 1%, checked with the
    # independent midpoint rule.
    arr = antenna.uniform_array(**kwargs)
    assert riemann_mean(arr) == pytest.approx(1.0, rel=0.01)


def test_gaussian_beam_half_power_floor_and_normalisation() -> None:
    pure = antenna.gaussian(4.333, tilt_deg=5.0)
    # Half power at +-bw/2 from boresight in each plane: exp(-ln 2) = 1/2, exactly.
    peak = float(pure.gain_dbi(0.0, 5.0))
    assert peak == pytest.approx(pure.peak_dbi, abs=1e-12)
    for az, el in ((4.333 / 2, 5.0), (-4.333 / 2, 5.0), (0.0, 5.0 + 4.333 / 2)):
        assert float(pure.gain_dbi(az, el)) == pytest.approx(peak - 10 * math.log10(2), abs=1e-9)
    # The PE source's directivity 4 ln2 / sin^2(bw / 2) integrates to 4 pi within 1% for a
    # narrow beam (the small-angle forms of the two agree).
    beam = (-15.0, 15.0, -10.0, 20.0, 0.02)  # the main beam on a 0.02 degree grid
    assert riemann_mean(pure, focus=beam) == pytest.approx(1.0, rel=0.01)
    # A 40 dB floor: the far sidelobe region sits 40 dB under the (renormalised) peak, and the
    # renormalised pattern integrates to 4 pi.
    floor = antenna.gaussian(4.333, tilt_deg=5.0, floor_db=40.0)
    assert floor.norm_db < 0
    assert float(floor.gain_dbi(90.0, 0.0)) == pytest.approx(
        float(floor.gain_dbi(0.0, 5.0)) - 40.0, abs=1e-9
    )
    assert riemann_mean(floor, focus=beam) == pytest.approx(1.0, rel=0.01)


def test_tabulated_pattern_interpolates_and_normalises() -> None:
    az = np.linspace(-180, 180, 37)
    el = np.linspace(-90, 90, 19)
    table = -0.1 * np.abs(az)[:, None] - 0.2 * np.abs(el)[None, :]
    raw = antenna.tabulated(az, el, table, normalise=False)
    # Bilinear is exact on a function linear within each cell.
    q_az, q_el = np.array([12.5, -47.0, 3.0]), np.array([33.0, -5.5, 81.0])
    np.testing.assert_allclose(
        raw.gain_dbi(q_az, q_el), -0.1 * np.abs(q_az) - 0.2 * np.abs(q_el), atol=1e-12
    )
    # Normalised: a constant shift that makes it integrate to 4 pi (1%, the midpoint rule).
    norm = antenna.tabulated(az, el, table)
    assert float(norm.gain_dbi(0, 0) - raw.gain_dbi(0, 0)) == pytest.approx(norm.norm_db)
    assert riemann_mean(norm) == pytest.approx(1.0, rel=0.01)
    # Outside a partial table: its lowest value.
    part = antenna.tabulated([-30, 30], [-10, 10], [[0.0, -3.0], [-6.0, -9.0]], normalise=False)
    assert float(part.gain_dbi(90.0, 0.0)) == -9.0


@pytest.mark.parametrize(
    ("make", "needle"),
    [
        (lambda: antenna.uniform_array(rows=-2), "rows must be an integer within 1..64"),
        (lambda: antenna.uniform_array(spacing=0.0), "spacing must be within"),
        (lambda: antenna.uniform_array(electrical_tilt_deg=float("nan")), "electrical_tilt"),
        (lambda: antenna.gaussian(0.1), "beamwidth_h_deg must be within"),
        (lambda: antenna.gaussian(floor_db=-3.0), "floor_db must be within"),
        (lambda: antenna.tabulated([0, 1], [0, 1], [[0, np.nan], [0, 0]]), "finite"),
        (lambda: antenna.tabulated([1, 0], [0, 1], [[0, 0], [0, 0]]), "increase strictly"),
        (lambda: antenna.tabulated([0, 1], [0, 1], [[0, 0, 0]]), "gain_db must"),
        (lambda: antenna.tr38901_element().gain_dbi(0.0, 95.0), "elevation_deg"),
        (lambda: antenna.tr38901_element().gain_dbi([np.inf], 0.0), "finite"),
    ],
)
def test_bad_antennas_name_the_field(make, needle) -> None:
    with pytest.raises(rainuav.InvalidInputError, match=needle):
        make()
