"""Stochastic rain fields: the noise's spectrum slope, the wet fraction and
the mean rate asked for (within sampling error, stated), an exact shift with the storm velocity,
a continuous evolution, slices of a series against static builds, and bad input."""

from __future__ import annotations

import contextlib
import io

import numpy as np
import pytest
from rainuav import InvalidInputError
from rainuav.radio import build_radio_map, presets
from rainuav.radio.scene.scenario import Area, Scenario
from rainuav.radio.scene.stochastic import StochasticRain, field_rates, nodes, noise_field
from rainuav.radio.scene.weather import Medium


def test_the_noise_has_the_spectrum_slope_asked_for() -> None:
    # The radially averaged power spectrum (pysteps' own rapsd) of one 512 x 512 noise field,
    # fitted in log-log over wavenumbers 4-128: -beta within 0.1 (one field has ~ 2 pi k modes
    # per shell, so the fitted slope of one realisation scatters by a few hundredths; measured
    # -2.514, -3.013, -3.513).
    with contextlib.redirect_stdout(io.StringIO()):
        from pysteps.utils.spectral import rapsd
    for beta in (2.5, 3.0, 3.5):
        noise = noise_field(7, 0, 512, beta)
        assert abs(noise.mean()) < 1e-9 and abs(noise.std() - 1.0) < 1e-9
        psd = rapsd(noise, fft_method=np.fft)
        k = np.arange(4, 129)
        slope = np.polyfit(np.log(k), np.log(psd[k]), 1)[0]
        assert abs(slope + beta) < 0.1, (beta, slope)


def test_wet_fraction_and_mean_rate_are_what_was_asked() -> None:
    # Over the whole periodic square (each noise field has mean 0 and variance 1 exactly),
    # averaged over 20 fields: within 3 standard errors of the 20 (the sampling error of the
    # large scales that a beta = 3 field puts most of its variance in). Measured: wet fraction
    # 0.310 +- 0.004 for 0.3, mean 11.81 +- 0.14 mm/h for 12.
    f = StochasticRain(mean_rate_mm_h=12.0, wet_fraction=0.3)
    n = nodes(f.side_m)
    xy = np.arange(n) * f.side_m / n  # the nodes themselves: no interpolation
    wet, mean = [], []
    for seed in range(20):
        r = field_rates(StochasticRain(**{**vars(f), "seed": seed}), xy[None, :], xy[:, None])
        wet.append(float((r > 0).mean()))
        mean.append(float(r.mean()))
    for got, want in ((wet, 0.3), (mean, 12.0)):
        se = np.std(got, ddof=1) / np.sqrt(len(got))
        assert abs(np.mean(got) - want) < 3 * se + 1e-3 * want, (np.mean(got), want, se)


def test_the_field_moves_exactly_with_the_storm_and_evolves_continuously() -> None:
    f = StochasticRain(seed=3, vx_m_s=12.0, vy_m_s=-5.0)
    x, y = np.meshgrid(np.linspace(0, 2000, 81), np.linspace(0, 2000, 81))
    now, later = field_rates(f, x, y), field_rates(f.at(40.0), x + 480.0, y - 200.0)
    np.testing.assert_allclose(later, now, rtol=1e-9, atol=1e-9)  # a shift, to rounding
    g = StochasticRain(seed=3, lifetime_s=600.0)
    np.testing.assert_array_equal(field_rates(g.at(600.0), x, y), field_rates(
        StochasticRain(seed=3, lifetime_s=600.0, t_s=600.0), x, y))  # fmt: skip
    a, b = field_rates(g, x, y), field_rates(g.at(1.0), x, y)
    assert np.mean(np.abs(b - a)) < 0.01 * max(np.mean(a), 1e-3)  # 1 s of 600: barely moved
    assert not np.array_equal(field_rates(g.at(300.0), x, y), a)  # but it does evolve


def test_a_series_through_a_field_is_the_static_map_of_each_instant() -> None:
    weather = Medium(kind="field", field=StochasticRain(seed=5, mean_rate_mm_h=15.0, vx_m_s=10.0,
                                                        lifetime_s=900.0))  # fmt: skip
    scn = presets.uma(0.0, 28e9, engine="ray", area=Area(resolution_m=50.0), medium=weather)
    series = build_radio_map(scn, times_s=[0.0, 60.0, 120.0], cache=False)
    for k, t in enumerate(series.t_s):
        ref = build_radio_map(scn.replace(medium=scn.medium.at(t)), cache=False)
        assert np.percentile(np.abs(series.sinr_db[k] - ref.sinr_db), 99) < 0.05  # the issue's
    assert not np.array_equal(series.sinr_db[0], series.sinr_db[-1])
    again = Scenario.from_toml_string(scn.to_toml_string())
    assert again.digest() == scn.digest() and again.medium.field == weather.field


@pytest.mark.parametrize(
    ("field", "needle"),
    [
        ({"wet_fraction": 0.0}, "wet_fraction"),
        ({"lifetime_s": 10.0}, "lifetime_s"),
        ({"beta": float("nan")}, "beta"),
        ({"vx_m_s": 50.0, "vy_m_s": 50.0}, "speed"),
        ({"seed": -1}, "seed"),
    ],
)
def test_bad_fields_are_named(field, needle) -> None:
    with pytest.raises(InvalidInputError, match=needle):
        Medium(kind="field", field=StochasticRain(**field)).check()
    with pytest.raises(InvalidInputError, match="field is required"):
        Medium(kind="field").check()
