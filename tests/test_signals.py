"""One signal with named axes (``rainuav.signals``): every kind of saved map loads as one
signal with the source's values bit for bit, one file format round-trips exactly, the field a
signal gives reads as the field built from the source directly, and bad signals or files are
refused in one line. The references are the existing loaders and fields, whose own tests
check them against the physics and the planner."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from rainuav.errors import InvalidInputError
from rainuav.nav.field import SignalField
from rainuav.nav.levelfield import field_of
from rainuav.radio.outputs.levelmaps import LevelStack
from rainuav.radio.outputs.signals import load_signal, signal_of
from rainuav.radio.outputs.timemap import build_radio_map_series
from rainuav.radio.scene import presets
from rainuav.radio.scene.scenario import Area, Scenario, Site
from rainuav.signals import AXES, Signal

pytestmark = pytest.mark.timeout(120)


@pytest.fixture(scope="module")
def series():
    """A storm's maps at two instants, ray engine, 100 m pixels (20 x 20): half a second."""
    scn = presets.storm(seed=11, area=Area(resolution_m=100.0), engine="ray")
    return build_radio_map_series(scn, [0.0, 60.0])


def stack(moving: bool = False) -> LevelStack:
    """Three levels over 400 m (40 x 40), a closed block at the lowest; in time: 3 slices."""
    alts = [30.0, 45.0, 100.0]
    area = Area(x_min_m=0, x_max_m=400, y_min_m=0, y_max_m=400, resolution_m=10, altitudes_m=alts)
    scn = Scenario(name="synthetic", area=area, sites=[Site(x_m=200.0, y_m=200.0)])
    rng = np.random.default_rng(0)
    lead = (3,) if moving else ()
    sinr = rng.normal(10.0, 8.0, (*lead, 3, 40, 40)).astype(np.float32)
    serving = rng.integers(-1, 3, sinr.shape).astype(np.int16)
    mask = np.zeros((3, 40, 40), bool)
    mask[0, 10:14, 20:30] = True
    t = np.array([0.0, 40.0, 80.0]) if moving else None
    return LevelStack(scn, np.asarray(alts), sinr, serving, mask, (0.0, 400.0, 0.0, 400.0), t)


def points(n: int = 300, seed: int = 1):
    u = np.random.default_rng(seed).random((4, n))
    return u[0] * 2000.0, u[1] * 2000.0, u[2] * 80.0


def test_every_saved_kind_loads_as_one_signal_bit_for_bit(series, tmp_path: Path) -> None:
    """A map, maps in time and the maps of every level (static and in time), each saved by its
    own code and read by load_signal: the axes' sizes are the kind's, the values, serving cells
    and mask the source's exactly; saved as a signal file, read back identical."""
    one = series.at(0.0)
    cases = [
        ("radiomap.npz", one, (1, 1, 1, 20, 20)),
        ("radiomap_series.npz", series, (1, 2, 1, 20, 20)),
        ("radiolevels.npz", stack(), (1, 1, 3, 40, 40)),
        ("moving_levels.npz", stack(moving=True), (1, 3, 3, 40, 40)),
    ]
    for name, source, shape in cases:
        source.save(tmp_path / name)
        sig = load_signal(tmp_path / name)
        assert sig.values.shape == shape, name
        flat = sig.values.reshape(-1, *shape[-2:])
        want = np.asarray(source.sinr_db).reshape(-1, *shape[-2:])
        assert np.array_equal(flat, want), name
        serving = np.asarray(source.serving_cell).reshape(flat.shape)
        assert np.array_equal(sig.serving_cell.reshape(flat.shape), serving), name
        assert sig.scenario_toml, name
        sig.save(tmp_path / f"signal_{name}")
        back = load_signal(tmp_path / f"signal_{name}")
        for f in ("values", "t_s", "altitudes_m", "serving_cell", "not_flyable"):
            a, b = getattr(sig, f), getattr(back, f)
            assert (a is None and b is None) or (a.dtype == b.dtype and np.array_equal(a, b))
        assert back.extent_m == sig.extent_m and back.scenario_toml == sig.scenario_toml
    mask = load_signal(tmp_path / "radiolevels.npz").not_flyable
    assert np.array_equal(mask, stack().not_flyable)
    # SIR where the file holds it; the series' instants are its own.
    sir = load_signal(tmp_path / "radiomap_series.npz", "sir")
    assert sir.name == "sir_db" and np.array_equal(sir.values[0, :, 0], series.sir_db)
    assert np.array_equal(sir.t_s, series.t_s)


def test_the_field_of_a_signal_reads_as_the_field_of_its_source(series) -> None:
    """field_of gives the kind the axes ask for, and it reads as the field built from the
    source's arrays directly (exactly, at 300 random points, instants and levels)."""
    x, y, t = points()
    one = series.at(0.0)
    a = field_of(signal_of(one))
    b = SignalField(one.sinr_db, one.extent_m, "sinr_db", one.serving_cell, one.not_flyable)
    assert type(a) is SignalField and not a.varies and a.values.shape == (1, 1, 1, 20, 20)
    assert np.array_equal(a(x, y), b(x, y))
    assert np.array_equal(a.serving_cell(x, y), b.serving_cell(x, y))
    a = field_of(signal_of(series))
    b = SignalField.series(series.sinr_db, series.t_s, one.extent_m, "sinr_db", series.serving_cell)
    assert type(a) is SignalField and a.varies and not a.banked
    assert np.array_equal(a(x, y, t), b(x, y, t))
    for moving in (False, True):
        s = stack(moving)
        a = field_of(signal_of(s))
        b = SignalField.from_stack(
            s.sinr_db, s.altitudes_m, s.extent, t_s=s.t_s, not_flyable=s.not_flyable,
            serving_cell=s.serving_cell,
        )  # fmt: skip
        lv = np.arange(len(x)) % 3
        xs, ys = x / 5.0, y / 5.0
        assert type(a) is SignalField and a.altitudes_m is not None and a.levels == 3
        assert np.array_equal(a(xs, ys, t, level=lv), b(xs, ys, t, level=lv))
        assert np.array_equal(a.serving_cell(xs, ys, t, lv), b.serving_cell(xs, ys, t, lv))
        assert np.array_equal(a.blocked(xs, ys, lv), b.blocked(xs, ys, lv))
    # A bank: four worlds' maps in time, each point reading its own world.
    rng = np.random.default_rng(2)
    v = rng.normal(0.0, 10.0, (4, 2, 20, 20))
    w = np.arange(len(x)) % 4
    sig = Signal.from_axes(v, ("world", "time", "north", "east"), one.extent_m, t_s=series.t_s)
    a, b = field_of(sig), SignalField.bank(v, series.t_s, one.extent_m)
    assert type(a) is SignalField and a.banked and a.worlds == 4
    assert np.array_equal(a(x, y, t, w), b(x, y, t, w))
    lv5 = rng.normal(0.0, 10.0, (4, 2, 3, 20, 20))
    sig = Signal(lv5, one.extent_m, series.t_s, np.array([30.0, 45.0, 100.0]))
    a, b = field_of(sig), SignalField.bank(lv5, series.t_s, one.extent_m, [30.0, 45.0, 100.0])
    lv = np.arange(len(x)) % 3
    assert a.banked and np.array_equal(a(x, y, t, w, level=lv), b(x, y, t, w, level=lv))


def test_named_axes_are_put_in_the_signals_order() -> None:
    """from_axes moves named axes into (world, time, level, north, east) and adds the missing
    ones; take keeps an axis of size 1; to_xarray names them with their coordinates."""
    rng = np.random.default_rng(3)
    arr = rng.normal(size=(5, 4, 3))  # east, north, time
    sig = Signal.from_axes(arr, ("east", "north", "time"), (0, 50, 0, 40), t_s=[0.0, 5.0, 9.0])
    assert sig.sizes == dict(zip(AXES, (1, 3, 1, 4, 5), strict=True))
    assert all(sig.values[0, k, 0, i, j] == arr[j, i, k]
               for j in range(5) for i in range(4) for k in range(3))  # fmt: skip
    one = sig.take(time=-1)
    assert one.sizes["time"] == 1 and one.t_s.tolist() == [9.0]
    assert np.array_equal(one.values[0, 0, 0], arr[:, :, 2].T)
    xr = pytest.importorskip("xarray")
    da = sig.to_xarray()
    assert isinstance(da, xr.DataArray) and da.dims == AXES
    assert da.coords["east"].values.tolist() == [5.0, 15.0, 25.0, 35.0, 45.0]
    assert float(da.sel(time=5.0, north=25.0, east=45.0).squeeze()) == arr[4, 2, 1]


def test_bad_signals_and_files_are_refused_in_one_line(tmp_path: Path) -> None:
    ext = (0.0, 100.0, 0.0, 100.0)
    good = np.zeros((1, 1, 1, 4, 4))
    bad = [
        (lambda: Signal(good[0], ext, [0.0], [50.0]), "values must be a floating 5-D"),
        (lambda: Signal(good * np.nan, ext, [0.0], [50.0]), "values must be finite"),
        (lambda: Signal(good, (0, 0, 0, 1), [0.0], [50.0]), "extent_m must be"),
        (lambda: Signal(good, ext, [0.0, 1.0], [50.0]), "t_s must be 1 finite"),
        (lambda: Signal(good, ext, [0.0], [50.0], name="rss"), "name must be"),
        (lambda: Signal(good, ext, [0.0], [50.0], serving_cell=np.zeros(3, int)), "serving_cell"),
        (lambda: Signal(good, ext, [0.0], [50.0], not_flyable=np.zeros((4, 4))), "not_flyable"),
        (lambda: Signal.from_axes(good[0, 0, 0], ("north", "up"), ext), "dims must name"),
        (lambda: Signal.from_axes(good, ("north", "east"), ext), "values must have one axis"),
        (lambda: Signal(good, ext, [0.0], [50.0]).take(level=1), "level must be an index"),
        (lambda: field_of(np.zeros((4, 4))), "signal must be a rainuav.signals.Signal"),
    ]
    for make, needle in bad:
        with pytest.raises(InvalidInputError, match=needle) as err:
            make()
        assert "\n" not in str(err.value)
    closed = Signal(np.zeros((2, 1, 1, 4, 4)), ext, [0.0], [50.0],
                    not_flyable=np.ones((1, 4, 4), bool))  # fmt: skip
    with pytest.raises(InvalidInputError, match="open ground"):
        field_of(closed)
    # Files: not an .npz, a pickled array, another npz, another version, bad values inside.
    sig = Signal(good, ext, [0.0], [50.0])
    sig.save(tmp_path / "ok.npz")
    (tmp_path / "text.npz").write_text("not a zip")
    np.savez(tmp_path / "pickled.npz", values=np.array([{"a": 1}], dtype=object))
    np.savez(tmp_path / "other.npz", a=np.zeros(3))
    with np.load(tmp_path / "ok.npz") as z:
        d = {k: z[k] for k in z.files}
    meta = json.loads(str(d["meta_json"]))
    np.savez(tmp_path / "v2.npz", **{**d, "meta_json": np.asarray(json.dumps(
        {**meta, "format_version": 2}))})  # fmt: skip
    np.savez(tmp_path / "nan.npz", **{**d, "values": d["values"] * np.nan})
    files = [
        ("text.npz", "not a readable"),
        ("pickled.npz", "not a readable"),
        ("other.npz", "neither a signal file nor a radio map"),
        ("v2.npz", "format version 2"),
        ("nan.npz", "values must be finite"),
        ("missing.npz", "not a readable"),
    ]
    for name, needle in files:
        with pytest.raises(InvalidInputError, match=needle) as err:
            load_signal(tmp_path / name)
        assert "\n" not in str(err.value) and name in str(err.value)
    assert dataclasses.is_dataclass(load_signal(tmp_path / "ok.npz"))


def test_a_world_of_a_signal_flies_as_the_world_of_its_source(series, tmp_path: Path) -> None:
    """world_from reads every kind as one signal: a world made of the signal of a series flies
    exactly as the world of the series (the planner's return to 1e-9, the same threshold from
    the scenario's name), and is saved and read back with a run as signal.npz."""
    from rainuav.nav import planner
    from rainuav.nav.task import NavConfig
    from rainuav.world import load_world, world_from

    task = NavConfig(goal_m=(1800.0, 1800.0), max_steps=60)
    a, b = world_from(series, task), world_from(signal_of(series), task)
    assert a.task.min_db == b.task.min_db == -2.0  # the storm preset's documented threshold
    starts = [(150.0, 250.0), (900.0, 150.0), (250.0, 1100.0)]
    ra = [planner.optimal(a.env(), s).return_ for s in starts]
    rb = [planner.optimal(b.env(), s).return_ for s in starts]
    assert np.allclose(ra, rb, rtol=0, atol=1e-9)
    assert b.save(tmp_path).name == "signal.npz"
    c = load_world(tmp_path, dataclasses.replace(spec_for(task)))
    assert isinstance(c.source, Signal)
    assert np.allclose([planner.optimal(c.env(), s).return_ for s in starts], ra, atol=1e-9)
    with pytest.raises(InvalidInputError, match=r"task\.signal is 'sir'"):
        world_from(signal_of(series), dataclasses.replace(task, signal="sir"))


def test_the_environment_takes_every_kind_as_its_signal(series) -> None:
    """UAVNavEnv(radio_map=...) reads any map kind or a signal through its as_signal(): one map
    and its signal fly the same (the planner's return bit for bit, as the map's own arrays gave
    before), maps in time fly as their world does (to 1e-9), the maps of every level give an
    environment among levels, and an object that is no map is one line."""
    from rainuav.nav import planner
    from rainuav.nav.env import UAVNavEnv
    from rainuav.nav.task import NavConfig
    from rainuav.world import world_from

    task = NavConfig(goal_m=(1800.0, 1800.0), max_steps=60, min_db=-2.0)
    starts = [(150.0, 250.0), (900.0, 150.0)]
    one = series.at(0.0)
    pairs = [(UAVNavEnv(one, config=task), UAVNavEnv(signal_of(one), config=task)),
             (UAVNavEnv(series, config=task), world_from(series, task).env())]  # fmt: skip
    for env_a, env_b in pairs:
        ra = [planner.optimal(env_a, s).return_ for s in starts]
        rb = [planner.optimal(env_b, s).return_ for s in starts]
        assert np.allclose(ra, rb, rtol=0, atol=1e-9), (ra, rb)
    assert env_a.field.varies  # the series flew as maps in time
    levels = UAVNavEnv(stack(), config=NavConfig(goal_m=(350.0, 350.0), max_steps=40))
    assert levels.field.altitudes_m is not None and levels.action_space.n == 6
    # What the learner reads of them (rainuav.nav.batched.FlightTerms), and the digest a run
    # records: the same for a map and its signal, another for another map.
    plane, moving, among = pairs[0][0].terms(), env_a.terms(), levels.terms()
    assert (plane.signal, plane.min_db, plane.altitudes_m, plane.varies) == ("sinr", -2.0, None,
                                                                           False)  # fmt: skip
    assert moving.varies and moving.altitudes_m is None
    assert among.altitudes_m == (30.0, 45.0, 100.0) and not among.varies
    assert pairs[0][0].digest() == pairs[0][1].digest() != env_a.digest()
    raw = UAVNavEnv(sinr_db=one.sinr_db, extent_m=one.extent_m, config=task)
    assert [planner.optimal(raw, s).return_ for s in starts] == [
        planner.optimal(UAVNavEnv(one, config=task), s).return_ for s in starts
    ]
    with pytest.raises(InvalidInputError, match="signal is sinr_db, not sir_db"):
        UAVNavEnv(signal_of(one), config=task, signal="sir")
    with pytest.raises(InvalidInputError, match="radio_map must be a built map"):
        UAVNavEnv(radio_map=np.zeros((4, 4)), config=task)


def spec_for(task):
    from rainuav.world import WorldSpec

    return WorldSpec(task=task)


def test_a_band_of_one_level_stays_a_level_field() -> None:
    """levels=True gives a field of one level (a band of one flight level, six moves),
    reading as the plain map does."""
    s = stack()
    one = Signal.from_axes(s.sinr_db[:1], ("level", "north", "east"), s.extent, altitudes_m=[30.0])
    a, b = field_of(one, levels=True), field_of(one)
    assert a.altitudes_m is not None and a.levels == 1 and b.altitudes_m is None
    x, y, t = points()
    assert np.array_equal(a(x / 5, y / 5, t, level=0), b(x / 5, y / 5))


def _powers(shape: tuple[int, ...], cells: int = 3, seed: int = 0):
    from rainuav.cellpowers import CellPowers

    rng = np.random.default_rng(seed)
    full = (cells, *shape)
    return CellPowers(rng.normal(-80.0, 10.0, full), rng.uniform(0.5, 3.0, full),
                      rng.uniform(0.0, 2.0, full), 1.5, -97.0)  # fmt: skip


def test_a_signal_carries_its_cells_powers_through_its_file_and_its_takes(tmp_path: Path) -> None:
    """Every cell's power and its two spreads ride with the signal: saved and read back bit for
    bit, cut with it by ``take``; powers over other axes, a negative spread, a file holding some
    of their arrays and not the others are each refused in one line naming the field."""
    from rainuav.cellpowers import ARRAY_NAMES, CellPowers

    v = np.random.default_rng(1).normal(5.0, 4.0, (2, 3, 1, 4, 5))
    pw = _powers(v.shape)
    sig = Signal(v, (0.0, 50.0, 0.0, 40.0), [0.0, 5.0, 10.0], [30.0], powers=pw)
    back = Signal.load(sig.save(tmp_path / "signal.npz"))
    for name in ("dbm", "local_std_db", "sample_std_db"):
        np.testing.assert_array_equal(getattr(back.powers, name), getattr(pw, name))
    assert (back.powers.common_std_db, back.powers.noise_power_dbm) == (1.5, -97.0)
    cut = sig.take(world=1, time=2)
    assert cut.powers.dbm.shape == (3, 1, 1, 1, 4, 5)
    np.testing.assert_array_equal(cut.powers.dbm[:, 0, 0], pw.dbm[:, 1, 2])
    with pytest.raises(InvalidInputError, match="powers must be"):
        Signal(v, (0.0, 50.0, 0.0, 40.0), [0.0, 5.0, 10.0], [30.0], powers=_powers((1, 1, 1, 4, 5)))
    with pytest.raises(InvalidInputError, match="sample_std_db must be finite and >= 0"):
        CellPowers(pw.dbm, pw.local_std_db, -pw.sample_std_db)
    with pytest.raises(InvalidInputError, match="dbm must be a 6-D array"):
        CellPowers(pw.dbm[0], pw.local_std_db[0], pw.sample_std_db[0])
    arrays = dict(np.load(tmp_path / "signal.npz", allow_pickle=False))
    del arrays[ARRAY_NAMES[1]]
    np.savez(tmp_path / "part.npz", **arrays)
    with pytest.raises(InvalidInputError, match=r"part\.npz: the cells' powers need"):
        Signal.load(tmp_path / "part.npz")


def test_the_outage_of_a_signal_draws_every_cell_as_the_outage_of_a_map_does() -> None:
    """On a synthetic signal of two worlds whose powers are known: one cell far above the noise
    with no spread is never in outage, a value whose every cell is below the floor always is,
    and the probability of a lone cell with a local spread s at the threshold's edge is the
    Gaussian's (within 4 standard errors of 4096 draws)."""
    from math import erf, sqrt

    from rainuav.cellpowers import CellPowers
    from rainuav.radio.measured.signalrisk import signal_outage_probability
    from rainuav.radio.outputs.sinr import RSS_FLOOR_DBM

    shape = (2, 1, 1, 1, 3)
    dbm = np.full((1, *shape), -60.0)
    dbm[0, 1, 0, 0, 0, 1] = RSS_FLOOR_DBM  # nothing reaches
    dbm[0, 1, 0, 0, 0, 2] = -90.0 + 1.0  # 1 dB above the threshold of -90 + 0 dB SINR
    local = np.zeros_like(dbm)
    local[0, 1, 0, 0, 0, 2] = 2.0
    pw = CellPowers(dbm, local, np.zeros_like(dbm), 0.0, -90.0)
    sig = Signal(np.zeros(shape), (0.0, 30.0, 0.0, 10.0), [0.0], [0.0], powers=pw)
    p = signal_outage_probability(sig, 0.0, draws=4096, seed=3)
    assert p.shape == shape
    assert p[0].max() == 0.0 and p[1, 0, 0, 0, 1] == 1.0
    want = 0.5 * (1 + erf(-1.0 / 2.0 / sqrt(2)))  # P(N(1, 2) < 0)
    assert abs(p[1, 0, 0, 0, 2] - want) < 4 * sqrt(want * (1 - want) / 4096)
    with pytest.raises(InvalidInputError, match="carries no cells' powers"):
        signal_outage_probability(dataclasses.replace(sig, powers=None), 0.0)
