"""Bad input gets a ValueError (rainuav.InvalidInputError) naming the argument and range."""

from __future__ import annotations

import re

import numpy as np
import pytest
import rainuav
from hypothesis import given
from hypothesis import strategies as st
from rainuav import medium as m


def test_hierarchy() -> None:
    assert issubclass(rainuav.InvalidInputError, rainuav.RainuavError)
    assert issubclass(rainuav.InvalidInputError, ValueError)


@pytest.mark.parametrize(
    ("kwargs", "needle"),
    [
        ({"freq_hz": -1.0}, "freq_hz"),
        ({"freq_hz": np.nan}, "freq_hz"),
        ({"freq_hz": np.inf}, "freq_hz"),
        ({"freq_hz": 0.5e9}, "1e9..1e12"),
        ({"freq_hz": 2e12}, "1e9..1e12"),
        ({"rain_rate_mm_h": -1.0}, "rain_rate_mm_h"),
        ({"rain_rate_mm_h": np.nan}, "rain_rate_mm_h"),
        ({"rain_rate_mm_h": np.inf}, "0..500"),
        ({"temperature_c": -5.0}, "temperature_c"),
        ({"temperature_c": 41.0}, "0..40"),
        ({"wind_speed_m_s": -1.0}, "wind_speed_m_s"),
        ({"model": "maxwell"}, "model"),
        ({"polarization": "x"}, "polarization"),
        ({"shape": "cube"}, "shape"),
        ({"dsd": "gauss"}, "dsd"),
        ({"wind_model": "storm"}, "wind_model"),
        ({"freq_hz": "ten"}, "freq_hz"),
        ({"rain_rate_mm_h": 1 + 2j}, "rain_rate_mm_h"),
        ({"freq_hz": np.ones(3) * 1e10, "rain_rate_mm_h": np.ones(2)}, "broadcast"),
    ],
)
@pytest.mark.parametrize(
    "fn", [m.effective_permittivity, m.specific_attenuation, m.effective_index]
)
def test_bad_input(fn, kwargs, needle) -> None:
    args = {"freq_hz": 10e9, "rain_rate_mm_h": 10.0, **kwargs}
    f, r = args.pop("freq_hz"), args.pop("rain_rate_mm_h")
    with pytest.raises(ValueError, match=re.escape(needle)) as info:
        fn(f, r, **args)
    assert isinstance(info.value, rainuav.InvalidInputError)


def test_bad_input_elsewhere() -> None:
    with pytest.raises(rainuav.InvalidInputError, match="temperature_c"):
        m.water_permittivity(10e9, 50.0)
    with pytest.raises(rainuav.InvalidInputError, match="freq_hz"):
        m.water_permittivity(-10e9)
    with pytest.raises(rainuav.InvalidInputError, match="rain_rate_mm_h"):
        m.marshall_palmer(1.0, -2.0)
    with pytest.raises(rainuav.InvalidInputError, match="elevation_deg"):
        m.itu_p838(10e9, 10.0, elevation_deg=100.0)
    with pytest.raises(rainuav.InvalidInputError, match="polarization"):
        m.itu_p838(10e9, 10.0, polarization="q")
    with pytest.raises(rainuav.InvalidInputError, match=r"1e9\.\.1e12"):
        m.itu_p838(1e6, 10.0)
    with pytest.raises(rainuav.InvalidInputError, match="increasing"):
        m.tabulated_dsd([1.0, 0.5], [1.0, 1.0])
    with pytest.raises(rainuav.InvalidInputError, match="density"):
        m.tabulated_dsd([0.5, 1.0], [1.0, -1.0])
    with pytest.raises(rainuav.InvalidInputError, match="mu"):
        m.gamma_dsd(8000.0, np.nan, 4.1, -0.21)
    with pytest.raises(rainuav.InvalidInputError, match="freq_hz"):
        m.RainMedium(0.0)
    with pytest.raises(rainuav.InvalidInputError, match="rain_rate_mm_h"):
        m.RainMedium(10e9).specific_attenuation([1.0, -1.0])
    with pytest.raises(rainuav.InvalidInputError, match="temperature_c"):
        m.effective_permittivity(10e9, 1.0, temperature_c=[10.0, 20.0])  # type: ignore[arg-type]


@given(
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(allow_nan=True, allow_infinity=True),
)
def test_any_number_gives_a_finite_answer_or_a_clear_error(f, r, t, w) -> None:
    # Never a panic, a hang or a silent NaN: either a finite, lossy result or ValueError.
    try:
        eps = m.effective_permittivity(f, r, temperature_c=t, wind_speed_m_s=w)
    except rainuav.InvalidInputError as err:
        assert any(k in str(err) for k in ("freq_hz", "rain_rate_mm_h", "temperature_c", "wind"))
    else:
        assert np.isfinite(eps) and eps.imag <= 0.0


def test_core_rejects_bad_arguments_without_panicking() -> None:
    from rainuav import _core

    with pytest.raises(rainuav.InvalidInputError, match="nodes"):
        _core.gauss_legendre(0)
    with pytest.raises(rainuav.InvalidInputError, match="x"):
        _core.mie_forward(1.5 + 0j, float("nan"))
    with pytest.raises(rainuav.InvalidInputError, match="m must be finite"):
        _core.mie_forward(1.5 - 1j, 1.0)
    with pytest.raises(rainuav.InvalidInputError, match="axial_ratio"):
        _core.depolarisation_factors(1.5)
    with pytest.raises(rainuav.InvalidInputError, match="nodes_per_panel"):
        _core.MediumConfig(
            model="quasi-static",
            polarization="h",
            shape="sphere",
            temperature_c=20.0,
            wind_speed_m_s=0.0,
            wind_model="canting",
            dsd=m.NAMED_DSDS["marshall-palmer"],
            nodes_per_panel=1,
        )
    with pytest.raises(rainuav.InvalidInputError, match="rain_rate_mm_h"):
        _core.effective_medium(
            np.ones(2) * 1e10,
            np.ones(3),
            _core.MediumConfig(
                model="quasi-static",
                polarization="h",
                shape="sphere",
                temperature_c=20.0,
                wind_speed_m_s=0.0,
                wind_model="canting",
                dsd=m.NAMED_DSDS["marshall-palmer"],
            ),
        )
