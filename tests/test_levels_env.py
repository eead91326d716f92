"""The navigation task in three dimensions (rainuav.nav.levels): the environment against the
exact planner among levels (its plans replayed earn its returns, on maps and in time), and
against the plane's environment on one level."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from rainuav.errors import InvalidInputError
from rainuav.nav import planner
from rainuav.nav.env import UAVNavEnv
from rainuav.nav.field import SignalField
from rainuav.nav.levels import UAVLevelsEnv
from rainuav.nav.task import NavConfig

EXTENT = (0.0, 120.0, 0.0, 80.0)
ALTS = [30.0, 45.0, 60.0]


def cfg(**kw) -> NavConfig:
    base = {"goal_m": (105.0, 65.0), "max_steps": 40, "min_db": 0.0, "goal_reward": 100.0,
            "out_of_bounds_penalty": 500.0, "tol_m": 1.0, "mu": 0.5}  # fmt: skip
    return NavConfig(**{**base, **kw})


def stack(seed: int, slices: int | None = None) -> np.ndarray:
    rng = np.random.default_rng(seed)
    shape = (len(ALTS), 8, 12) if slices is None else (slices, len(ALTS), 8, 12)
    return rng.uniform(-12.0, 6.0, size=shape)


def replay(env: UAVLevelsEnv, plan: planner.LevelPlan) -> tuple[float, list, list]:
    _, info = env.reset(options={"start_m": plan.path_m[0], "start_level": int(plan.levels[0])})
    ret, path, ticks = 0.0, [info["position_m"]], [0]
    for a in plan.actions:
        _, r, term, trunc, info = env.step(int(a))
        ret += r
        path.append(info["position_m"])
        ticks.append(round(info["t_s"] / env.cfg.move_s))
        if term or trunc:
            break
    return ret, path, ticks


@pytest.mark.parametrize("moving", [False, True])
def test_exact_plans_replayed_in_the_environment_earn_their_returns(moving) -> None:
    # Random maps (a third of the lowest level not flyable), on maps and in time (four
    # slices 13 s apart, so moves land between slices and on them): every plan's actions
    # replayed in the environment give its return (1e-9: the same rewards summed in the same
    # order), its path and its clock.
    c = cfg()
    sig = stack(1, 4 if moving else None)
    t_s = np.array([0.0, 13.0, 26.0, 39.0]) if moving else None
    mask = np.zeros((3, 8, 12), bool)
    mask[0, 2:5, 3:9] = True
    field = SignalField.from_stack(sig, ALTS, EXTENT, t_s=t_s, not_flyable=mask)
    env = UAVLevelsEnv(field, c)
    rng = np.random.default_rng(7)
    starts = rng.uniform([0, 0], [120, 80], size=(12, 2))
    levels = rng.integers(1, 3, size=12)
    plans = planner.optimal_levels(sig, ALTS, EXTENT, c, starts, levels, t_s=t_s,
                                   not_flyable=mask)  # fmt: skip
    vertical = 0
    for p in plans:
        ret, path, ticks = replay(env, p)
        assert ret == pytest.approx(p.return_, abs=1e-9)
        assert np.allclose(path, p.path_m) and ticks == list(p.ticks)
        vertical += int(np.sum(p.actions >= 4))
    assert vertical > 0  # the replays cover climbs and descents


def test_one_level_is_the_plane_s_environment() -> None:
    # On one level the six-move task is the plane's: the same rewards, ends and positions for
    # the same moves (here random sequences of the four), and a vertical move leaves the band.
    sig = stack(2)[:1]
    c = cfg(max_steps=25)
    lv = UAVLevelsEnv(SignalField.from_stack(sig, [100.0], EXTENT), c)
    flat = UAVNavEnv(sinr_db=sig[0], extent_m=EXTENT, config=c)
    rng = np.random.default_rng(3)
    for _ in range(20):
        start = rng.uniform([0, 0], [120, 80])
        lv.reset(options={"start_m": start})
        flat.reset(options={"start_m": start})
        for a in rng.integers(0, 4, size=30):
            o1, r1, t1, u1, i1 = lv.step(int(a))
            o2, r2, t2, u2, i2 = flat.step(int(a))
            assert (r1, t1, u1) == (r2, t2, u2)
            assert np.array_equal(i1["position_m"], i2["position_m"]) and i1["altitude_m"] == 100.0
            assert np.array_equal(o1[:2], o2)
            if t1 or u1:
                break
    lv.reset(options={"start_m": (55.0, 35.0)})
    _, r, term, _, info = lv.step(4)
    assert term and r < -c.out_of_bounds_penalty and info["level"] == 0


def test_climbs_last_their_duration_and_land_in_their_slice() -> None:
    # 15 m gaps at 5 m/s climb and 3 m/s descent, 1 s moves: 3 and 5 ticks; each earns its
    # duration times the base reward where and when it lands.
    c = cfg(mu=1.0)
    sig = np.full((2, 3, 8, 12), -10.0)
    sig[1, 1] = 4.0  # level 1 clear from t = 3 s on
    field = SignalField.from_stack(sig, ALTS, EXTENT, t_s=np.array([0.0, 3.0]))
    env = UAVLevelsEnv(field, c)
    obs, info = env.reset(options={"start_m": (55.0, 35.0)})
    assert info["level"] == 0 and info["altitude_m"] == 30.0 and obs.shape == (4,)
    _, r, *_, info = env.step(4)
    assert info["t_s"] == 3.0 and info["level"] == 1 and r == pytest.approx(3 * -1.0)
    _, r, *_, info = env.step(5)
    assert info["t_s"] == 8.0 and info["level"] == 0 and r == pytest.approx(5 * (-1.0 - 10.0))
    assert env.observation_space.contains(env.observe_batch(info["position_m"], 0, 8))
    assert env.action_space == gym.spaces.Discrete(6)


def test_bad_input_is_refused_in_one_line() -> None:
    sig = stack(3)
    field = SignalField.from_stack(sig, ALTS, EXTENT)
    env = UAVLevelsEnv(field, cfg())
    env.reset(options={"start_m": (5.0, 5.0)})
    for bad in (6, -1, 1.5, "up", True):
        with pytest.raises(InvalidInputError, match=r"0\.\.5"):
            env.step(bad)
    with pytest.raises(InvalidInputError, match="start_level"):
        env.reset(options={"start_m": (5.0, 5.0), "start_level": 3})
    with pytest.raises(InvalidInputError, match="increase"):
        SignalField.from_stack(sig, [60.0, 45.0, 30.0], EXTENT)
    with pytest.raises(InvalidInputError, match="one altitude a level"):
        SignalField.from_stack(sig, [30.0, 45.0], EXTENT)
    mask = np.zeros((3, 8, 12), bool)
    mask[:2, 0, 0] = True
    env = UAVLevelsEnv(SignalField.from_stack(sig, ALTS, EXTENT, not_flyable=mask), cfg())
    _, info = env.reset(options={"start_m": (5.0, 5.0)})
    assert info["level"] == 2  # the lowest level flyable there
    with pytest.raises(InvalidInputError, match="not flyable at level 0"):
        env.reset(options={"start_m": (5.0, 5.0), "start_level": 0})
    series = SignalField.series(stack(4, 2)[:, 0], [0.0, 5.0], EXTENT)
    with pytest.raises(InvalidInputError, match="all maps, all maps in time"):
        SignalField.of_levels([series, field.level(1), field.level(2)], ALTS)


def test_a_plan_too_big_for_memory_is_refused_before_allocating() -> None:
    # 64 levels of 200 x 200 points over a horizon of 100 000 ticks would need about 2.6e11
    # bytes of policy: refused in one line naming max_steps, in time and on maps.
    sig = np.zeros((64, 200, 200))
    c = cfg(max_steps=100_000, goal_m=(1900.0, 1900.0))
    alts = np.arange(64) * 10.0 + 20.0
    for t_s in (None, [0.0]):
        s = sig if t_s is None else sig[None]
        with pytest.raises(InvalidInputError, match="max_steps"):
            planner.optimal_levels(s, alts, (0.0, 2000.0, 0.0, 2000.0), c, [[10.0, 10.0]], [0],
                                   t_s=t_s)  # fmt: skip


def test_gym_make_builds_the_levels_of_a_scenario() -> None:
    # `gym.make("rainuav/UAVLevels-v0")`: the scenario mapped at each level, the preset's
    # SINR threshold, a climb of 30 m lasting 6 moves; the weather observation shows both
    # levels; the signal is the SINR (another is refused in one line).
    import rainuav  # noqa: F401 - registers the environments
    from rainuav.radio.scene.presets import SINR_THRESHOLDS_DB, uma
    from rainuav.radio.scene.scenario import Area

    scn = uma(0.0, 28e9, engine="ray").replace(area=Area(resolution_m=50.0))
    env = gym.make("rainuav/UAVLevels-v0", scenario=scn, altitudes_m=[30.0, 60.0])
    base = env.unwrapped
    assert base.cfg.min_db == SINR_THRESHOLDS_DB["uma"] and base.climb == [6]
    obs, info = env.reset(seed=0, options={"start_m": (500.0, 500.0)})
    assert info["altitude_m"] == 30.0 and obs[2] == 0.0
    obs, _, *_, info = env.step(4)
    assert info["altitude_m"] == 60.0 and info["t_s"] == 6.0 and obs[2] == 1.0
    env = gym.make("rainuav/UAVLevels-v0", scenario=scn, altitudes_m=[30.0, 60.0],
                   observation="weather", random_goal=True)  # fmt: skip
    obs, info = env.reset(seed=0)
    assert obs["local"].shape == (2, 11, 11) and obs["level"][0] == 0.0 and "goal_m" in info
    with pytest.raises(InvalidInputError, match="signal: the environment among levels"):
        gym.make("rainuav/UAVLevels-v0", scenario=scn, signal="sir")


def test_a_field_of_levels_is_its_levels_read_one_by_one() -> None:
    """One field over (time, level, north, east) reads, level by level, bit for bit what each
    level's own field reads (maps and maps in time, with closed pixels and serving cells); its
    levels taken apart and put together again give the same field."""
    rng = np.random.default_rng(5)
    x, y = rng.uniform(-10, 130, 300), rng.uniform(-10, 90, 300)
    t, lv = rng.uniform(-2, 12, 300), rng.integers(0, 3, 300)
    mask = rng.random((3, 8, 12)) < 0.2
    for sig, t_s in ((stack(6), None), (stack(7, 4), [0.0, 3.0, 5.0, 10.0])):
        serving = rng.integers(0, 5, sig.shape)
        field = SignalField.from_stack(sig, ALTS, EXTENT, t_s=t_s, not_flyable=mask,
                                      serving_cell=serving)  # fmt: skip
        assert field.levels == 3 and field.values.shape[2] == 3
        again = SignalField.of_levels([field.level(k) for k in range(3)], ALTS)
        for k in range(3):
            one = field.level(k)
            assert one.altitudes_m is None and one.levels == 1
            on = lv == k
            got = field(x[on], y[on], t[on], level=k)
            np.testing.assert_array_equal(got, one(x[on], y[on], t[on]))
            np.testing.assert_array_equal(got, again(x[on], y[on], t[on], level=k))
            np.testing.assert_array_equal(
                field.serving_cell(x[on], y[on], t[on], k), one.serving_cell(x[on], y[on], t[on])
            )
            np.testing.assert_array_equal(field.blocked(x[on], y[on], k), one.blocked(x[on], y[on]))
        np.testing.assert_array_equal(field.blocked(x, y, lv), again.blocked(x, y, lv))
        assert np.array_equal(field.flyable(5.0, 5.0), ~mask[:, 0, 0])
