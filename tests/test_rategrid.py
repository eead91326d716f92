"""Rain from a NetCDF file as weather in time: read with xarray, exact at
the file's own instants, linear between them, every slice of a map series the static map of its
instant, and a bad file refused in one line naming what is wrong."""

from __future__ import annotations

import re

import numpy as np
import pytest
from rainuav import InvalidInputError
from rainuav.radio import build_radio_map, presets
from rainuav.radio.scene.rategrid import read_rate_grid
from rainuav.radio.scene.scenario import Area

xr = pytest.importorskip("xarray")  # the 'weather' extra; installed with the test extra

AREA = Area(resolution_m=100.0)


def _grid(times=(0.0, 60.0, 120.0), units="mm/h", n=41) -> object:
    """A cell of 30..90 mm/h moving east at 10 m/s over 2 mm/h, on a 50 m grid over 0..2000 m."""
    x = np.linspace(0.0, 2000.0, n)
    y = np.linspace(0.0, 2000.0, n)

    def rate(t: float) -> np.ndarray:
        d2 = (x[None] - 600 - 10 * t) ** 2 + (y[:, None] - 900) ** 2
        return 2.0 + (30.0 + 0.5 * t) * np.exp(-d2 / 300.0**2)

    rates = np.stack([rate(t) for t in times])
    da = xr.DataArray(rates, dims=("time", "y", "x"), coords={"time": list(times), "y": y, "x": x})
    da.attrs["units"] = units
    return xr.Dataset({"rain_rate": da})


def test_a_file_is_the_weather_exactly_at_its_instants_and_linear_between(tmp_path) -> None:
    # Exact (bit for bit) at the file's own instants (the check); halfway, the mean of
    # the two maps around (linear interpolation in time, to rounding 1e-12).
    path = tmp_path / "rain.nc"
    _grid().to_netcdf(path)
    m = read_rate_grid(path, AREA)
    assert m.moves and m.rate_times_s == [0.0, 60.0, 120.0]
    maps = np.asarray(m.rate_map_mm_h)
    for at in (m.at, m.clock()):  # one instant, or many with the maps read once
        for k, t in enumerate(m.rate_times_s):
            assert np.array_equal(np.asarray(at(t).rate_map_mm_h), maps[k])
        half = np.asarray(at(90.0).rate_map_mm_h)
        np.testing.assert_allclose(half, 0.5 * (maps[1] + maps[2]), rtol=1e-12, atol=1e-12)
        assert np.array_equal(np.asarray(at(-10.0).rate_map_mm_h), maps[0])  # held
        assert np.array_equal(np.asarray(at(500.0).rate_map_mm_h), maps[2])
        assert at(90.0).rate_times_s is None and at(90.0).kind == "map"
    # The file's grid is read where its nodes sit: the regridded map against the formula at
    # the area's grid centres, within the bilinear error of a 50 m grid on a 300 m cell.
    xs = np.asarray(np.linspace(0, 2000, maps.shape[2] + 1)[:-1]) + 1000 / maps.shape[2]
    want = 2.0 + 30.0 * np.exp(-((xs[None] - 600) ** 2 + (xs[:, None] - 900) ** 2) / 300.0**2)
    np.testing.assert_allclose(maps[0], want, rtol=0, atol=0.5)


def test_a_series_through_a_file_is_the_static_map_of_each_instant(tmp_path) -> None:
    path = tmp_path / "rain.nc"
    _grid().to_netcdf(path)
    scn = presets.uma(0.0, 28e9, engine="ray", area=AREA, medium=read_rate_grid(path, AREA))
    series = build_radio_map(scn, times_s=[0.0, 30.0, 120.0], cache=False)
    for k, t in enumerate(series.t_s):
        ref = build_radio_map(scn.replace(medium=scn.medium.at(t)), cache=False)
        assert np.percentile(np.abs(series.sinr_db[k] - ref.sinr_db), 99) < 0.05  # the issue's
    assert not np.array_equal(series.sinr_db[0], series.sinr_db[-1])
    # The weather round-trips through the scenario's TOML (the map's file and cache key).
    again = type(scn).from_toml_string(scn.to_toml_string())
    assert again.digest() == scn.digest() and again.medium.rate_times_s == [0.0, 60.0, 120.0]


def test_a_bad_file_is_refused_in_one_line(tmp_path) -> None:
    cases = {
        "units.nc": (_grid(units="dBZ"), "units must be mm/h"),
        "dims.nc": (_grid().rename({"x": "lon"}), "dimensions (time, y, x)"),
        "small.nc": (_grid().isel(x=slice(0, 20)), "x (m) must cover the area"),
        "time.nc": (_grid(times=(0.0, 60.0, 30.0)), "strictly increasing"),
        "nan.nc": (_grid().where(lambda d: d < 50), "finite"),
    }
    for name, (ds, needle) in cases.items():
        ds.to_netcdf(tmp_path / name)
        with pytest.raises(InvalidInputError, match=re.escape(needle)) as err:
            read_rate_grid(tmp_path / name, AREA)
        assert name in str(err.value) and "\n" not in str(err.value)
    (tmp_path / "junk.nc").write_bytes(b"not netcdf")
    with pytest.raises(InvalidInputError, match="not a readable NetCDF"):
        read_rate_grid(tmp_path / "junk.nc", AREA)
    with pytest.raises(InvalidInputError, match="no such file"):
        read_rate_grid(tmp_path / "missing.nc", AREA)


@pytest.mark.slow
def test_the_radiomap_cli_maps_a_rain_file_in_time(tmp_path, monkeypatch, capsys) -> None:
    from rainuav import radiomap

    monkeypatch.setenv("RAINUAV_CACHE_DIR", str(tmp_path / "cache"))
    path = tmp_path / "rain.nc"
    _grid().to_netcdf(path)
    argv = ["--scenario", "uma", "--freq-ghz", "28", "--rain-file", str(path)]
    out = tmp_path / "out"
    assert radiomap.main([*argv, "--duration-s", "120", "--slice-s", "60", "--out", str(out)]) == 0
    assert (out / "storm.gif").exists() and "3 slices" in capsys.readouterr().out
    assert radiomap.main([*argv, "--rain-rate-mm-h", "5", "--out", str(out)]) == 2
    assert "--rain-rate-mm-h" in capsys.readouterr().err


def test_a_file_too_large_for_memory_is_refused_before_it_is_read(tmp_path, monkeypatch) -> None:
    # The sizes are checked on the lazily opened file, before its data are read: a machine
    # with 1 MB free refuses the 41 x 41 x 3 grid (and a file a hostile sender made huge).
    from rainuav import _core

    path = tmp_path / "rain.nc"
    _grid().to_netcdf(path)
    monkeypatch.setattr(_core, "available_memory_bytes", lambda: 10_000)
    with pytest.raises(InvalidInputError, match="GB"):
        read_rate_grid(path, AREA)


def test_a_scenario_as_a_dict_is_the_standard_librarys(tmp_path) -> None:
    # Scenario.to_dict (rainuav._io.plain) copies a list of numbers whole (a radar file's
    # rates: 0.36 -> 0.07 s). The reference is dataclasses.asdict with None dropped, which it
    # must equal exactly (types included: a tuple stays a tuple) for a weather in time, a height
    # map, buildings and the presets. A user's own values keep their types: whole numbers and
    # tuples.
    import dataclasses

    def reference(scn):
        def clean(v):
            if isinstance(v, dict):
                return {k: clean(x) for k, x in v.items() if x is not None}
            return [clean(x) for x in v] if isinstance(v, list) else v

        return clean(dataclasses.asdict(scn))

    path = tmp_path / "rain.nc"
    _grid().to_netcdf(path)
    timed = presets.uma(0.0, 28e9, area=AREA, medium=read_rate_grid(path, AREA))
    heights = presets.paper(height_map_m=((0, 12.5), (30, 0)), area=Area(altitudes_m=[60, 100.5]))
    for scn in (timed, heights, *(make() for make in presets.PRESETS.values())):
        d = scn.to_dict()
        assert d == reference(scn) and repr(d) == repr(reference(scn)), scn.name
