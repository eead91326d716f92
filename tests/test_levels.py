"""Altitude as a decision: maps at several flight altitudes and the exact planner among them
(rainuav_core::planning::planlevels), against the planner in the plane and against a brute force."""

from __future__ import annotations

import numpy as np
import pytest
from rainuav.errors import InvalidInputError
from rainuav.nav import planner
from rainuav.nav.field import SignalField
from rainuav.nav.task import NavConfig
from rainuav.radio.outputs.levelmaps import build_radio_levels
from rainuav.radio.scene.presets import uma
from rainuav.radio.scene.scenario import Area

EXTENT = (0.0, 60.0, 0.0, 40.0)


def cfg(**kw) -> NavConfig:
    base = {"goal_m": (55.0, 35.0), "max_steps": 12, "min_db": 0.0, "goal_reward": 100.0,
            "out_of_bounds_penalty": 500.0, "tol_m": 1.0}  # fmt: skip
    return NavConfig(**{**base, **kw})


def maps(levels: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.uniform(-8.0, 6.0, size=(levels, 4, 6))


def test_one_level_is_the_plane() -> None:
    # The same return and actions as the planner in the plane, from several starts.
    sig = maps(1)
    c = cfg()
    starts = np.array([[5.0, 5.0], [25.0, 15.0], [45.0, 5.0]])
    flat = planner.plan_on(SignalField(sig[0], EXTENT), c, starts)
    lv = planner.optimal_levels(sig, [100.0], EXTENT, c, starts, np.zeros(3))
    for a, b in zip(flat, lv, strict=True):
        assert a.return_ == pytest.approx(b.return_, abs=1e-9)
        assert np.array_equal(a.actions, b.actions) and np.all(b.levels == 0)


@pytest.mark.slow
def test_against_a_brute_force_over_every_move_sequence() -> None:
    # Three levels 15 m apart (climb 5 m/s: 3 moves' time; descent 3 m/s: 5), a horizon of 6
    # ticks of the flight's clock: the best of every move sequence until the clock reaches
    # it, replayed move by move with the rule written here (duration x base reward; leaving
    # the area or the band ends the flight with the penalty; arrival at any level), equals
    # the planner's return. Tolerance 1e-9.
    from rainuav._sampling import bilinear

    sig = maps(3, seed=4)
    c = cfg(max_steps=6, goal_m=(35.0, 25.0), mu=0.4, goal_reward=10.0)
    alts = [30.0, 45.0, 60.0]
    climb, descend = planner.level_durations(alts, c)
    assert climb == [3, 3] and descend == [5, 5]

    def base(level: int, x: float, y: float) -> float:
        s = float(bilinear(sig[level], EXTENT, np.array([x]), np.array([y]))[0])
        return -1.0 - c.mu * max(0.0, c.min_db - s)

    def best(x: float, y: float, lv: int, clock: int) -> float:
        if clock >= c.max_steps:
            return 0.0
        out = -np.inf
        for a in range(6):
            if a < 4:
                dx, dy = [(10, 0), (0, 10), (-10, 0), (0, -10)][a]
                nx, ny = x + dx, y + dy
                left = not (EXTENT[0] <= nx <= EXTENT[1] and EXTENT[2] <= ny <= EXTENT[3])
                r = base(lv, np.clip(nx, *EXTENT[:2]), np.clip(ny, *EXTENT[2:]))
                if left:
                    v = r - c.out_of_bounds_penalty
                elif np.hypot(nx - c.goal_m[0], ny - c.goal_m[1]) <= c.tol_m:
                    v = r + c.goal_reward
                else:
                    v = r + best(nx, ny, lv, clock + 1)
            else:
                to = lv + 1 if a == 4 else lv - 1
                dur = climb[min(lv, 1)] if a == 4 else descend[max(lv - 1, 0)]
                if not 0 <= to < 3:
                    v = dur * base(lv, x, y) - c.out_of_bounds_penalty
                else:
                    v = dur * base(to, x, y) + best(x, y, to, clock + dur)
            out = max(out, v)
        return out

    vertical = 0
    for deep in (0.0, 30.0):  # the lowest level in deep outage: climbing pays
        sig[0] -= deep
        for start, level in (((5.0, 5.0), 0), ((15.0, 25.0), 1), ((35.0, 5.0), 2)):
            want = best(start[0], start[1], level, 0)
            got = planner.optimal_levels(sig, alts, EXTENT, c, [start], [level])[0]
            assert got.return_ == pytest.approx(want, abs=1e-9), (start, level)
            assert got.ticks[-2] < c.max_steps and np.all(np.diff(got.ticks) >= 1)
            vertical += int(np.sum(got.actions >= 4))
    assert vertical > 0  # the comparison covers climbs, not only the plane's moves


def test_bad_altitude_sets_are_refused_in_one_line() -> None:
    for bad, word in (([], "non-empty"), ([60.0, 30.0], "increase"), ([0.1], "altitudes_m[0]"),
                      ([30.0, 4000.0], "altitudes_m[1]")):  # fmt: skip
        with pytest.raises(InvalidInputError, match=word.replace("[", r"\[").replace("]", r"\]")):
            Area(altitudes_m=bad).check()


def test_maps_at_several_heights_are_each_level_s_map() -> None:
    # The stack holds, at each level, the map of the scenario flying at that altitude.
    from rainuav.radio.outputs.levelmaps import level_scenario
    from rainuav.radio.outputs.maps import build_radio_map

    area = Area(resolution_m=50.0, altitudes_m=[40.0, 100.0])
    scn = uma(engine="ray").replace(area=area)
    stack = build_radio_levels(scn, cache=False)
    assert stack.sinr_db.shape == (2, 40, 40)
    for k, a in enumerate(stack.altitudes_m):
        one = build_radio_map(level_scenario(scn, a), cache=False)
        assert np.array_equal(one.sinr_db, stack.sinr_db[k])
    assert not np.allclose(stack.sinr_db[0], stack.sinr_db[1])


@pytest.mark.slow
def test_fly_a_band_of_heights_climbs_a_wall_and_writes_each_height(tmp_path) -> None:
    # A 40 m wall across the whole place between the start and the destination: at 30 m it
    # is not flyable (its 10 m clearance), at 60 m it is. `fly --altitudes-m 30:60:30` started
    # at 30 m climbs to cross, and every file carries the heights: pymavlink reads the
    # waypoints at the path's levels (relative to home), the GeoJSON's vertices too, and the
    # plan costs no more than the flight held at its start level (which cannot cross).
    # Without a start height the exact planner chooses the take-off level and says so.
    import json
    from pathlib import Path

    from pymavlink import mavwp
    from rainuav.fly import main

    examples = Path(__file__).resolve().parents[1] / "examples"
    wall = [[8.40, 47.3729], [8.70, 47.3729], [8.70, 47.3731], [8.40, 47.3731], [8.40, 47.3729]]
    fc = {"type": "FeatureCollection", "features": [{"type": "Feature", "properties":
          {"height": 40}, "geometry": {"type": "Polygon", "coordinates": [wall]}}]}  # fmt: skip
    (tmp_path / "wall.geojson").write_text(json.dumps(fc))
    out = tmp_path / "flight"
    argv = ["--sites", str(examples / "sites.csv"), "--start", "47.3660,8.5380,30", "--goal",
            "47.3800,8.5560", "--footprints", str(tmp_path / "wall.geojson"), "--altitudes-m",
            "30:60:30", "--engine", "ray", "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    s = json.loads((out / "summary.json").read_text())
    from test_docs import documented_summary_fields

    assert set(s) <= documented_summary_fields(), set(s) - documented_summary_fields()
    assert s["start_altitude_m"] == 30.0 and s["climbs"] >= 1
    assert s["start_altitude_chosen_by"] == "--start"
    line = json.loads((out / "flight.geojson").read_text())["features"][0]
    z = np.array(line["geometry"]["coordinates"])[:, 2]
    assert set(np.unique(z)) == {30.0, 60.0}
    loader = mavwp.MAVWPLoader()
    n = loader.load(str(out / "mission.waypoints"))
    alts = [loader.wp(k).z for k in range(2, n - 1)]  # the waypoints after the take-off
    assert set(alts) == {30.0, 60.0} and len(alts) == s["waypoints"]
    # Held at 30 m the flight cannot cross: the best single level is 60 m. The band's plan
    # costs at most a climb at the start (30 m at 5 m/s: 6 moves' time, each at most
    # 1 + mu x 38 dB of shortfall, SINR being clipped at -40 dB) plus the 60 m plan.
    assert s["best_single_altitude_m"] == 60.0
    assert s["cost"] <= s["best_single_altitude_cost"] + 6 * (1 + 10 / 43 * 38)
    # No start height (the same maps): the planner takes off at 60 m, the best level here,
    # needs no climb, and costs what the plan held at 60 m costs (the same flight).
    out2 = tmp_path / "chosen"
    assert main([*argv[:2], "--start", "47.3660,8.5380", *argv[4:-1], str(out2)]) == 0
    s2 = json.loads((out2 / "summary.json").read_text())
    assert s2["start_altitude_m"] == 60.0 and s2["climbs"] == 0
    assert s2["start_altitude_chosen_by"] == "planner"
    assert s2["cost"] == pytest.approx(s["best_single_altitude_cost"], abs=1e-9)


def test_the_altitude_study_and_its_figures() -> None:
    # The built-in study: 2 networks x 2 frequencies x 4 rain rates, six levels, `--quick`
    # with 10 starts. One case's figures on a coarse map: the plan among levels costs no more
    # than the best fixed level where every flight arrives at both, and the plan held at
    # 100 m costs at least as much.
    from rainuav.nav.task import NavConfig
    from rainuav.studies.altitude import ALTITUDE_COLUMNS, altitude_row
    from rainuav.studies.spec import load_study

    study = load_study("altitude")
    assert len(study.cases()) == 16 and study.compute == ["altitudes"]
    assert study.with_quick().eval_starts == 10
    scn = uma(engine="ray").replace(
        area=Area(resolution_m=40.0, altitudes_m=[25.0, 50.0, 100.0, 150.0])
    )
    rng = np.random.default_rng(1)
    starts = rng.uniform(0.0, 2000.0, size=(4, 2))
    row = altitude_row(scn, NavConfig(min_db=-2.0, step_m=40.0, tol_m=40.0), starts)
    assert set(row) == set(ALTITUDE_COLUMNS) and row["straight_line_100m_arrives"] is None
    assert row["levels_optimal_mean_cost"] <= row["best_fixed_mean_cost"] + 1e-9
    assert row["fixed_100m_excess_cost"] >= -1e-9 and row["best_single_excess_cost"] >= -1e-9
    # With the case's environment at 100 m, the straight line there beside them.
    from rainuav.radio.outputs.levelmaps import level_scenario
    from rainuav.radio.outputs.maps import build_radio_map
    from rainuav.world import world_from

    cfg = NavConfig(min_db=-2.0, step_m=40.0, tol_m=40.0)
    env = world_from(build_radio_map(level_scenario(scn, 100.0)), cfg).env()
    row = altitude_row(scn, cfg, starts, env)
    assert row["straight_line_100m_arrives"] == 1.0
    assert row["straight_line_100m_excess_cost"] >= row["fixed_100m_excess_cost"] - 1e-9


def test_bad_altitude_bands_are_refused_in_one_line(tmp_path, capsys) -> None:
    from pathlib import Path

    from rainuav.fly import main

    examples = Path(__file__).resolve().parents[1] / "examples"
    base = ["--sites", str(examples / "sites.csv"), "--start", "47.3660,8.5380", "--goal",
            "47.3800,8.5560", "--engine", "ray"]  # fmt: skip
    for band, word in (("60:30:15", "LOW <= HIGH"), ("30:120", "LOW:HIGH:STEP"),
                       ("0.1:10:5", "altitudes_m[0]"), ("30:3000:10", "at most 64")):  # fmt: skip
        out = tmp_path / band.replace(":", "_")
        capsys.readouterr()
        rc = main([*base, "--altitudes-m", band, "--out", str(out)])
        err = capsys.readouterr().err.strip().splitlines()
        assert rc == 2 and len(err) == 1 and word in err[0], (band, err)
        assert not (out / "summary.json").exists()


@pytest.mark.slow
def test_one_level_band_flies_todays_plan_and_a_start_altitude_is_a_level(tmp_path, capsys) -> None:
    # `--altitudes-m 100:100:1` is today's flight at 100 m: the same cost, moves and outage
    # chance (the same map, from the cache). A start altitude must be one of the levels (one
    # line, exit 2).
    import json
    from pathlib import Path

    from rainuav.fly import main

    examples = Path(__file__).resolve().parents[1] / "examples"
    base = ["--sites", str(examples / "sites.csv"), "--goal", "47.3800,8.5560", "--engine", "ray"]
    assert main([*base, "--start", "47.3660,8.5380", "--out", str(tmp_path / "a")]) == 0
    assert main([*base, "--start", "47.3660,8.5380", "--altitudes-m", "100:100:1",
                 "--out", str(tmp_path / "b")]) == 0  # fmt: skip
    a = json.loads((tmp_path / "a" / "summary.json").read_text())
    b = json.loads((tmp_path / "b" / "summary.json").read_text())
    assert b["cost"] == pytest.approx(a["cost"], abs=1e-9) and b["moves"] == a["moves"]
    # Its outage with its spread, each move on its level's map, is today's on the one map.
    ca, cb = a["outage_chance"], b["outage_chance"]
    for k in ("expected_outage_share", "spread_independent", "spread_correlated"):
        assert cb[k] == pytest.approx(ca[k], abs=1e-12), k
    capsys.readouterr()
    rc = main([*base, "--start", "47.3660,8.5380,45", "--altitudes-m", "30:60:30",
               "--out", str(tmp_path / "c")])  # fmt: skip
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "one of --altitudes-m" in err[0], err


@pytest.mark.slow
def test_fly_a_band_of_heights_over_terrain_writes_heights_above_sea_level(tmp_path) -> None:
    # Over the ridge DEM of the terrain tests, `--altitudes-m 60:120:60` above the ground: the
    # mission's waypoints (pymavlink) are MAV_FRAME_GLOBAL heights, each the terrain under it
    # plus one of the levels (1.5 m: the file's int16 heights, bilinear).
    import json

    from pymavlink import mavwp
    from rainuav.fly import main
    from rainuav.missions import MAV_FRAME_GLOBAL
    from test_terrain import EXAMPLE_SITES, _ground, _zurich_hill_dem

    dem = _zurich_hill_dem(tmp_path / "ridge.tif", ridge=True)
    out = tmp_path / "flight"
    argv = ["--sites", str(EXAMPLE_SITES), "--start", "47.3660,8.5380", "--goal",
            "47.3800,8.5560", "--terrain", str(dem), "--altitudes-m", "60:120:60",
            "--engine", "ray", "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    s = json.loads((out / "summary.json").read_text())
    loader = mavwp.MAVWPLoader()
    n = loader.load(str(out / "mission.waypoints"))
    items = [loader.wp(k) for k in range(2, n - 1)]
    assert len(items) == s["waypoints"] and all(it.frame == MAV_FRAME_GLOBAL for it in items)
    lat, lon = np.array([it.x for it in items]), np.array([it.y for it in items])
    above = np.array([it.z for it in items]) - _ground(lat, lon, ridge=True)
    assert np.all(np.min(np.abs(above[:, None] - np.array([60.0, 120.0])), axis=1) < 1.5)


def test_maps_in_time_at_several_heights() -> None:
    # (time, altitude, H, W): each level's slice is that level's own series.
    from rainuav.radio.outputs.levelmaps import build_radio_level_series, level_scenario
    from rainuav.radio.outputs.timemap import build_radio_map_series
    from rainuav.radio.scene.presets import storm

    scn = storm(seed=0, engine="ray")
    scn = scn.replace(area=Area(resolution_m=50.0, altitudes_m=[50.0, 100.0]))
    series = build_radio_level_series(scn, [0.0, 60.0, 120.0], cache=False)
    sinr, t = series.sinr_db, series.t_s
    assert sinr.shape == (3, 2, 40, 40) and list(series.altitudes_m) == [50.0, 100.0]
    one = build_radio_map_series(level_scenario(scn, 50.0), t, cache=False)
    assert np.array_equal(sinr[:, 0], one.sinr_db.astype(np.float32))
    assert np.array_equal(series.serving_cell[:, 0], one.serving_cell)
    assert not np.array_equal(sinr[1, 0], sinr[1, 1])
    assert series.not_flyable.shape == (2, 40, 40) and not series.not_flyable.any()


@pytest.mark.slow
def test_one_march_reads_every_level() -> None:
    # The hybrid engine marches each cell once for every level. One height recorded by the
    # levels' march is the single-height march bit for bit; the maps of the one march agree
    # with each level's own build (its own grid and cone) within 0.5 dB of SINR everywhere
    # (the cone of the highest level's grid is narrower; the rays carry the rest: measured
    # 0.14 dB at 60 m here, 0.44 dB on `uma` at 28 GHz, 20 m pixels, 30 m), and within
    # 0.05 dB at the highest level, whose grid it is (PE budget cut to 0.02 for speed).
    from rainuav.radio.engines.grid import march_grid
    from rainuav.radio.engines.pe_engine import march_cell, march_cell_levels
    from rainuav.radio.outputs.levelmaps import level_scenario, shares_a_march
    from rainuav.radio.scene.presets import paper
    from rainuav.radio.scene.scenario import PESettings

    scn = paper().replace(area=Area(resolution_m=50.0, altitudes_m=[60.0, 100.0]),
                          pe=PESettings(budget_gpoints=0.02), engine="hybrid")  # fmt: skip
    assert shares_a_march(scn) and not shares_a_march(scn.replace(engine="pe"))
    top = level_scenario(scn, 100.0)
    site = top.sites[0]
    grid = march_grid(top, site, site.cells[0])
    one = march_cell(top, site, site.cells[0], grid)
    assert np.array_equal(march_cell_levels(top, site, site.cells[0], grid, [100.0])[0], one)
    shared = build_radio_levels(scn, cache=False)
    apart = build_radio_levels(scn, cache=False, one_march=False)
    assert (apart.maps[0].pe_share > 0.5).sum() > 50  # the PE carries part of the map
    for k, tol in ((0, 0.5), (1, 0.05)):
        assert np.abs(shared.maps[k].sinr_db - apart.maps[k].sinr_db).max() < tol


def test_more_levels_than_fit_in_memory_are_refused_before_building() -> None:
    # 64 levels of `uma`'s 21 cells at 0.5 m pixels (16 million a level) need about 100 GB:
    # refused in one line naming area.altitudes_m, before the first level is built (as are
    # the maps in time).
    from rainuav.radio.outputs.levelmaps import build_radio_level_series

    scn = uma(0.0, 28e9, engine="ray").replace(
        area=Area(resolution_m=0.5, altitudes_m=[20.0 + 10.0 * k for k in range(64)])
    )
    with pytest.raises(InvalidInputError, match=r"area\.altitudes_m \(64 levels"):
        build_radio_levels(scn, cache=False)
    with pytest.raises(InvalidInputError, match=r"area\.altitudes_m \(64 levels"):
        build_radio_level_series(scn, [0.0, 5.0], cache=False)


def test_radiomap_writes_a_map_at_each_level(tmp_path, capsys) -> None:
    # `radiomap --altitudes-m 30:60:30` on a georeferenced scenario: per level a PNG, an .npz
    # (the level's own map: its altitude, the same SINR as built alone) and a GeoTIFF tagged
    # with its altitude; radiomap_levels.json last with the outage shares. A bad band or a
    # band with maps in time: one line, exit 2, nothing written.
    import json

    import rasterio
    from rainuav.radio.outputs.levelmaps import level_scenario
    from rainuav.radio.outputs.mapdata import RadioMap
    from rainuav.radio.outputs.maps import build_radio_map
    from rainuav.radio.scene.scenario import Origin
    from rainuav.radiomap import main

    # A scenario of its own name (a place's): the outage counted at the uma preset's -2 dB,
    # the threshold fly uses, not left out.
    scn = uma(0.0, 28e9, engine="ray").replace(
        name="my_place", area=Area(resolution_m=50.0), origin=Origin(47.37, 8.54)
    )
    cfg_file = tmp_path / "uma.toml"
    cfg_file.write_text(scn.to_toml_string())
    out = tmp_path / "maps"
    assert main(["--config", str(cfg_file), "--altitudes-m", "30:60:30", "--out", str(out)]) == 0
    summary = json.loads((out / "radiomap_levels.json").read_text())
    assert [lv["altitude_m"] for lv in summary["levels"]] == [30.0, 60.0]
    assert summary["min_db"] == -2.0
    for lv in summary["levels"]:
        a = lv["altitude_m"]
        rm = RadioMap.load(out / lv["map"])
        alone = build_radio_map(level_scenario(scn, a), cache=False)
        assert rm.altitude_m == a and np.array_equal(rm.sinr_db, alone.sinr_db)
        assert lv["outage_share"] == pytest.approx(float(np.mean(alone.sinr_db < -2.0)))
        with rasterio.open(out / f"radiomap_{a:g}m.tif") as src:
            assert src.count == 4 and float(src.tags()["altitude_m"]) == a
        assert (out / f"sinr_{a:g}m.png").stat().st_size > 0
    wrong = (["--altitudes-m", "60:30:15"], ["--altitudes-m", "30:60:30", "--duration-s", "10"])
    for extra in wrong:
        bad = tmp_path / "bad"
        capsys.readouterr()
        rc = main(["--config", str(cfg_file), *extra, "--out", str(bad)])
        err = capsys.readouterr().err.strip().splitlines()
        assert rc == 2 and len(err) == 1 and "--altitudes-m" in err[0], err
        assert not (bad / "radiomap_levels.json").exists()


@pytest.mark.slow
def test_maps_in_time_read_every_level_from_one_clear_air_march(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # The hybrid series in time at two levels through moving rain cells: the PE's clear-air
    # march once a cell for both levels, against each level's own series: SINR within 0.5 dB
    # at the lower level and 0.05 dB at the highest (as the static maps), at every instant.
    from rainuav.radio.outputs.levelmaps import build_radio_level_series
    from rainuav.radio.scene.presets import paper
    from rainuav.radio.scene.scenario import PESettings
    from rainuav.radio.scene.weather import Medium, RainCell

    cells = [RainCell(700.0, 900.0, 500.0, 150.0, vx_m_s=12.0)]
    scn = paper().replace(
        area=Area(resolution_m=50.0, altitudes_m=[60.0, 100.0]),
        pe=PESettings(budget_gpoints=0.02), engine="hybrid",
        medium=Medium(kind="cells", rain_rate_mm_h=5.0, cells=cells),
    )  # fmt: skip
    shared = build_radio_level_series(scn, [0.0, 60.0], cache=False)
    apart = build_radio_level_series(scn, [0.0, 60.0], cache=False, one_march=False)
    d = np.abs(shared.sinr_db - apart.sinr_db)
    assert d[:, 0].max() < 0.5 and d[:, 1].max() < 0.05
    assert not np.array_equal(shared.sinr_db[0, 0], shared.sinr_db[1, 0])  # the rain moves
    # Another weather over the same network (a storm pool's next storm) marches nothing: the
    # clear-air march is the last one's, and the series is the one a fresh march gives.
    from rainuav.radio.engines import hybrid
    from rainuav.radio.outputs import levelmaps

    other = scn.replace(medium=Medium(kind="cells", rain_rate_mm_h=20.0, cells=cells))
    marches = []
    real = hybrid.engine_parts_levels

    def counted(*a: object, **k: object) -> object:
        marches.append(1)
        return real(*a, **k)

    monkeypatch.setattr(hybrid, "engine_parts_levels", counted)
    again = build_radio_level_series(other, [0.0, 60.0], cache=False)
    assert marches == []
    levelmaps._CLEAR_PARTS.clear()
    fresh = build_radio_level_series(other, [0.0, 60.0], cache=False)
    assert marches == [1]
    np.testing.assert_array_equal(again.sinr_db, fresh.sinr_db)
    assert not np.array_equal(again.sinr_db, shared.sinr_db)  # its own rain
