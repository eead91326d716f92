"""Weather in time: moving, growing and decaying rain cells, the frozen
weather at any instant, and the ``storm`` preset's documented distribution."""

from __future__ import annotations

import math

import numpy as np
import pytest
from rainuav import InvalidInputError
from rainuav.radio import Scenario, build_radio_map, presets
from rainuav.radio.scene.scenario import Area
from rainuav.radio.scene.storms import (
    CELL_SPREAD_M_S,
    EVAL_SEEDS_FROM,
    STORM_DURATION_S,
    check_storm_seed,
    draw_storm,
)
from rainuav.radio.scene.weather import Medium, RainCell


def _cell(**kw: float) -> RainCell:
    base = {"x_m": 500.0, "y_m": 800.0, "radius_m": 400.0, "peak_rate_mm_h": 80.0}
    return RainCell(**{**base, **kw})  # type: ignore[arg-type]


def test_a_still_cell_gives_the_same_weather_at_every_instant() -> None:
    w = Medium(kind="cells", rain_rate_mm_h=3.0, cells=[_cell()])
    assert not w.moves
    scn = presets.uma(0.0, 28e9, medium=w)
    for t in (0.0, 5.0, 150.0, 300.0):
        assert w.at(t) == w and scn.replace(medium=w.at(t)).digest() == scn.digest()


def test_a_moving_growing_cell_is_the_first_one_shifted_and_scaled() -> None:
    # Closed form: R_t(x + vx t, y + vy t) = R_0(x, y) exp(t / tau), exactly (to rounding).
    c = _cell(vx_m_s=12.0, vy_m_s=-5.0, growth_s=900.0)
    x, y = np.meshgrid(np.linspace(0, 2000, 41), np.linspace(0, 2000, 41))
    for t in (0.0, 37.5, 300.0):
        moved = c.at(t).rate(x + 12.0 * t, y - 5.0 * t)
        np.testing.assert_allclose(moved, c.rate(x, y) * math.exp(t / 900.0), rtol=1e-12)
    # Time composes: the cell at a then b is the cell at a + b.
    a, b = c.at(40.0).at(70.0), c.at(110.0)
    assert a.x_m == pytest.approx(b.x_m) and a.y_m == pytest.approx(b.y_m)
    assert a.peak_rate_mm_h == pytest.approx(b.peak_rate_mm_h, rel=1e-12)
    # A decaying cell: negative e-folding time; the peak is held within the model's 500 mm/h.
    assert _cell(growth_s=-600.0).at(600.0).peak_rate_mm_h == pytest.approx(80.0 / math.e)
    assert _cell(growth_s=60.0).at(600.0).peak_rate_mm_h == 500.0
    # Far in time (a scenario file may ask for any instant): bounded, no overflow.
    assert _cell(growth_s=60.0).at(1e6).peak_rate_mm_h == 500.0
    assert _cell(growth_s=-60.0).at(1e6).peak_rate_mm_h == 0.0


@pytest.mark.parametrize(
    ("cell", "needle"),
    [
        ({"vx_m_s": 70.0}, "vx_m_s"),
        ({"vx_m_s": 50.0, "vy_m_s": 50.0}, "speed"),
        ({"vy_m_s": float("nan")}, "vy_m_s"),
        ({"growth_s": 5.0}, "growth_s"),
        ({"growth_s": float("inf")}, "growth_s"),
    ],
)
def test_bad_motion_is_refused_naming_the_field(cell: dict, needle: str) -> None:
    w = Medium(kind="cells", cells=[_cell(**cell)])
    with pytest.raises(InvalidInputError, match=needle):
        w.check()
    with pytest.raises(InvalidInputError, match="t_s"):
        Medium(kind="cells", cells=[_cell(vx_m_s=1.0)]).at(float("nan"))


def test_the_storm_distribution_is_the_documented_one() -> None:
    # 400 storms: every draw inside its documented range; the counts' and signs' means within
    # 4 standard errors of the distribution's (1-4 cells uniform: mean 2.5, sd 1.118; growth or
    # decay with equal odds).
    counts, growing, mid = [], [], STORM_DURATION_S / 2
    for seed in range(400):
        w = draw_storm(seed)
        assert w.kind == "cells" and 0.0 <= w.rain_rate_mm_h <= 10.0
        counts.append(len(w.cells))
        v = np.array([[c.vx_m_s, c.vy_m_s] for c in w.cells])
        mean = v.mean(axis=0)
        assert 5.0 - CELL_SPREAD_M_S <= np.hypot(*mean) <= 20.0 + CELL_SPREAD_M_S
        # Each cell within 2 m/s of the storm's velocity: pairwise within 4 m/s.
        assert np.all(np.hypot(*(v[:, None] - v[None]).T) <= 2 * CELL_SPREAD_M_S + 1e-9)
        for c in w.cells:
            at_mid = c.at(mid)
            assert 0.0 <= at_mid.x_m <= 2000.0 and 0.0 <= at_mid.y_m <= 2000.0  # it crosses
            assert 30.0 * (1 - 1e-12) <= at_mid.peak_rate_mm_h <= 150.0 * (1 + 1e-12)
            assert 200.0 <= c.radius_m <= 800.0 and 600.0 <= abs(c.growth_s) <= 1800.0
            growing.append(c.growth_s > 0)
    n = len(counts)
    assert set(counts) == {1, 2, 3, 4}
    assert abs(np.mean(counts) - 2.5) < 4 * 1.118 / math.sqrt(n)
    assert abs(np.mean(growing) - 0.5) < 4 * 0.5 / math.sqrt(len(growing))
    assert draw_storm(7) == draw_storm(7) and draw_storm(7) != draw_storm(8)


def test_the_storm_preset_round_trips_and_keeps_evaluation_seeds_apart() -> None:
    scn = presets.storm(seed=11)
    assert scn.name == "storm" and scn.freq_hz == 28e9 and scn.medium.moves
    back = Scenario.from_toml_string(scn.to_toml_string())
    assert back == scn and back.medium.at(120.0) == scn.medium.at(120.0)
    assert presets.storm(seed=12).digest() != scn.digest()
    assert presets.storm(0.0, seed=11).medium.rain_rate_mm_h == 0.0
    assert check_storm_seed(EVAL_SEEDS_FROM - 1, training=True) == EVAL_SEEDS_FROM - 1
    with pytest.raises(InvalidInputError, match="evaluation storm"):
        check_storm_seed(EVAL_SEEDS_FROM, training=True)
    with pytest.raises(InvalidInputError, match="storm_seed"):
        draw_storm(-1)


def test_a_map_at_an_instant_sees_the_storm_where_it_is() -> None:
    # The frozen weather at t is an ordinary scenario: a static build (ray engine, 50 m
    # pixels) at two instants. Where the strongest cell sits at each instant the SINR of the
    # two maps differs; a still storm would give the same map.
    scn = presets.storm(seed=11, area=Area(resolution_m=50.0), engine="ray")
    maps = [build_radio_map(scn.replace(medium=scn.medium.at(t))) for t in (0.0, 150.0)]
    assert not np.array_equal(maps[0].sinr_db, maps[1].sinr_db)
    still = scn.replace(medium=Medium(kind="cells", rain_rate_mm_h=2.0, cells=[_cell()]))
    a, b = (build_radio_map(still.replace(medium=still.medium.at(t))) for t in (0.0, 150.0))
    assert np.array_equal(a.sinr_db, b.sinr_db)


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["--scenario", "uma", "--storm-seed", "3"], "--storm-seed"),
        (["--scenario", "storm", "--storm-seed", "-3"], "storm_seed"),
        (["--scenario", "storm", "--at-s", "nan"], "t_s"),
    ],
)
def test_radiomap_cli_refuses_bad_storm_flags(tmp_path, capsys, argv, needle) -> None:
    from rainuav import radiomap

    assert radiomap.main([*argv, "--out", str(tmp_path / "m")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("error: ") and needle in err, err


def test_maps_of_varying_rain_outline_it() -> None:
    # The map figure outlines the rain (10/30/100 mm/h) where it varies over the area: here
    # the storm's cells at 150 s; a homogeneous map draws no outline.
    from matplotlib.figure import Figure
    from rainuav.radio.outputs.plot import plot_map

    scn = presets.storm(seed=5, area=Area(resolution_m=50.0), engine="ray")
    for weather, outlined in ((scn.medium.at(150.0), True), (Medium(rain_rate_mm_h=25.0), False)):
        rm = build_radio_map(scn.replace(medium=weather))
        ax = plot_map(rm, "sinr", ax=Figure().subplots())
        assert bool(ax.collections) == outlined
