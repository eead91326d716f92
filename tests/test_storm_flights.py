"""Flights through weather that moves: time in the task, the exact space-time
optimum against an independent brute force, the environment's return along the planner's
path, the baselines, the world built from a spec, and static maps unchanged."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from rainuav.errors import InvalidInputError
from rainuav.nav import UAVNavEnv, planner
from rainuav.nav.baselines import fly_actions, frozen_plans, replans
from rainuav.nav.field import SignalField
from rainuav.nav.task import NavConfig
from rainuav.nav.vector import UAVNavVectorEnv
from rainuav.world import WorldSpec, build_world

EXT = (0.0, 60.0, 0.0, 50.0)


def series(k: int = 4, seed: int = 0) -> SignalField:
    """A small signal in time whose slices differ strongly (so timing matters)."""
    rng = np.random.default_rng(seed)
    return SignalField.series(rng.normal(0.0, 12.0, (k, 5, 6)), np.arange(k) * 3.0, EXT)


def storm_env(**kw) -> UAVNavEnv:
    task = {"goal_m": (45.0, 35.0), "step_m": 10.0, "tol_m": 1.0, "max_steps": 7, "mu": 0.5}
    return UAVNavEnv(field=series(), min_db=0.0, speed_m_s=5.0, **{**task, **kw})


def test_space_time_optimum_equals_brute_force_through_the_env(
    best_return_of_every_sequence,
) -> None:
    # Tolerance 1e-9: the planner reads the signal operation for operation as the env does.
    # Five moves of 2 s cross the slices at 3, 6 and 9 s: the best path depends on timing.
    env = storm_env(max_steps=5)
    starts = np.array([[0.0, 0.0], [15.0, 25.0], [55.0, 5.0]])
    for s in starts:
        best = best_return_of_every_sequence(env, s, env.cfg.max_steps)
        assert planner.optimal(env, s).return_ == pytest.approx(best, abs=1e-9)
    # Timing matters here: planning on the take-off weather alone loses from two starts.
    frozen = [p.return_ for p in frozen_plans(env, starts)]
    best = [p.return_ for p in planner.optimal_many(env, starts)]
    assert sum(f < b - 1e-6 for f, b in zip(frozen, best, strict=True)) == 2


def test_planner_value_is_the_env_return_along_its_path() -> None:
    env = storm_env(max_steps=40, goal_m=(45.0, 35.0))
    rng = np.random.default_rng(1)
    starts = np.array([env.sample_start(rng) for _ in range(12)])
    plans = planner.optimal_many(env, starts)
    flown = fly_actions(env, starts, [p.actions for p in plans])
    for p, f in zip(plans, flown, strict=True):
        assert f.return_ == pytest.approx(p.return_, abs=1e-9)
        np.testing.assert_allclose(f.path_m, p.path_m, atol=1e-12)
    # and the planner's exact optimum beats (or ties) every baseline from every start
    for base in (frozen_plans(env, starts), replans(env, starts, 2)):
        assert all(b.return_ <= p.return_ + 1e-9 for b, p in zip(base, plans, strict=True))
    lines = [planner.straight_line(env, s) for s in starts]
    assert all(b.return_ <= p.return_ + 1e-9 for b, p in zip(lines, plans, strict=True))


def test_on_a_single_map_the_baselines_are_the_optimum_and_nothing_changed() -> None:
    rng = np.random.default_rng(2)
    values = rng.normal(5.0, 8.0, (5, 6))
    env = UAVNavEnv(sinr_db=values, extent_m=EXT, goal_m=(45.0, 35.0), max_steps=30, tol_m=1.0)
    starts = np.array([env.sample_start(rng) for _ in range(10)])
    opt = [p.return_ for p in planner.optimal_many(env, starts)]
    # Exactly (to rounding) the optimum: a single map does not change while the UAV flies.
    np.testing.assert_allclose([p.return_ for p in frozen_plans(env, starts)], opt, atol=1e-9)
    np.testing.assert_allclose([p.return_ for p in replans(env, starts, 3)], opt, atol=1e-9)
    # A series of one repeated slice is that map: same plans, same returns, bit for bit.
    same = UAVNavEnv(
        field=SignalField.series(np.stack([values, values]), [0.0, 1.0], EXT),
        goal_m=(45.0, 35.0), max_steps=30, tol_m=1.0, min_db=env.cfg.min_db,
    )  # fmt: skip
    assert [p.return_ for p in planner.optimal_many(same, starts)] == opt
    # The static env's observation is the position alone, as before; info carries the time.
    obs, info = env.reset(seed=0)
    assert obs.shape == (2,) and info["t_s"] == 0.0
    _, _, _, _, info = env.step(0)
    assert info["t_s"] == pytest.approx(env.cfg.step_m / env.cfg.speed_m_s)


def test_time_is_in_the_observation_and_the_signal_is_read_at_the_move_instant() -> None:
    env = storm_env(max_steps=20)
    obs, info = env.reset(options={"start_m": [5.0, 5.0]})
    assert env.observation_space.shape == (3,) and obs[2] == 0.0
    obs, _, _, _, info = env.step(0)  # 10 m at 5 m/s: 2 s
    assert info["t_s"] == pytest.approx(2.0)
    assert obs[2] == pytest.approx(1 / 20)
    f = env.field
    # Linear in time between the slices at 0 s and 3 s, bilinear in space.
    s0, s1 = (SignalField(f.db[k], EXT)(15.0, 5.0) for k in (0, 1))
    expected = (1 / 3) * s0 + (2 / 3) * s1
    assert info["signal_db"] == pytest.approx(expected, abs=1e-12)
    assert env.observation_space.contains(obs)


def test_vector_env_in_time_matches_the_scalar_env() -> None:
    env = storm_env(max_steps=15)
    n = 6
    vec = UAVNavVectorEnv(env, n)
    scalars = [storm_env(max_steps=15) for _ in range(n)]
    starts = np.array([[5.0 + 8 * k, 5.0 + 6 * k] for k in range(n)])
    obs, _ = vec.reset(options={"start_m": starts})
    for k, e in enumerate(scalars):
        o, _ = e.reset(options={"start_m": starts[k]})
        np.testing.assert_array_equal(obs[k], o)
    rng = np.random.default_rng(3)
    ended = np.zeros(n, dtype=bool)
    for _ in range(10):
        a = rng.integers(0, 4, n)
        obs, r, _, _, info = vec.step(a)
        for k, e in enumerate(scalars):
            if ended[k]:
                continue
            o, rk, tk, uk, ik = e.step(int(a[k]))
            assert r[k] == rk and info["t_s"][k] == ik["t_s"]
            np.testing.assert_array_equal(obs[k], o)
            ended[k] = tk or uk
        if ended.all():
            break


def test_frozen_field_and_bad_series_are_refused_cleanly() -> None:
    f = series()
    assert isinstance(f.frozen(0.0), SignalField)
    np.testing.assert_array_equal(f.frozen(3.0).db, f.db[1])
    with pytest.raises(InvalidInputError, match="t_s"):
        SignalField.series(np.zeros((2, 3, 3)), [1.0, 1.0], EXT)
    with pytest.raises(InvalidInputError, match="speed_m_s"):
        UAVNavEnv(field=f, goal_m=(45.0, 35.0), speed_m_s=0.0)
    with pytest.raises(InvalidInputError, match="replan_every"):
        replans(storm_env(), np.array([[5.0, 5.0]]), 0)


@pytest.mark.timeout(240)
def test_a_storm_world_from_a_spec_for_gym_make_train_and_evaluate() -> None:
    spec = WorldSpec(
        scenario="storm", storm_seed=2, engine="ray", slice_s=10.0, task=NavConfig(max_steps=60)
    )
    world = build_world(spec)
    assert world.varies and world.field.db.shape[0] == 7  # 60 moves of 1 s: 0..60 s
    env = world.env()
    assert env.observation_space.shape == (3,) and env.cfg.min_db == -2.0
    made = gym.make(
        "rainuav/UAVNav-v0", scenario="storm", storm_seed=2, engine="ray", slice_s=10.0,
        max_steps=60, goal_m=(1400.0, 1600.0),
    )  # fmt: skip
    np.testing.assert_array_equal(made.unwrapped.field.db, world.field.db)
    # A storm seed reserved for evaluation is refused for training, naming it.
    from rainuav.rl.config import TrainConfig
    from rainuav.rl.loop import train

    cfg = TrainConfig(
        scenario="storm", storm_seed=1_000_001, slice_s=10.0, task=NavConfig(max_steps=60)
    )
    with pytest.raises(InvalidInputError, match="evaluation storm"):
        train(cfg, world)


def test_flights_in_time_are_drawn_over_the_signal_at_take_off(tmp_path) -> None:
    from rainuav.nav.figures import plot_trajectories

    env = storm_env(max_steps=20)
    starts = np.array([[5.0, 5.0], [55.0, 5.0]])
    paths = [p.path_m for p in planner.optimal_many(env, starts)]
    plot_trajectories(env, [], tmp_path / "f.png", "storm", paths)
    assert (tmp_path / "f.png").stat().st_size > 1000


@pytest.mark.slow
@pytest.mark.timeout(240)
def test_train_on_one_storm_and_evaluate_on_another_from_the_cli(tmp_path, capsys) -> None:
    import json

    from rainuav import evaluate, train

    run = tmp_path / "run"
    argv = [
        "--scenario", "storm", "--storm-seed", "0", "--engine", "ray", "--slice-s", "30",
        "--task.max-steps", "40", "--task.goal-m", "300,300", "--dqn.episodes", "4",
        "--dqn.lanes", "2", "--eval-starts", "4", "--validate-every", "0", "--out", str(run),
    ]  # fmt: skip
    assert train.main(argv) == 0
    for name in ("radiomap_series.npz", "trajectories.png", "storm_flights.png"):
        assert (run / name).exists(), name
    metrics = json.loads((run / "metrics.json").read_text())
    assert {"frozen_plan_success_rate", "replan_success_rate"} <= set(metrics)
    out = tmp_path / "ev"
    rc = evaluate.main([str(run), "--scenario", "storm", "--storm-seed", "1", "--out", str(out)])
    assert rc == 0
    flown = json.loads((out / "evaluation.json").read_text())
    assert flown["trained_on"] == {"scenario": "storm", "rain_rate_mm_h": None, "storm_seed": 0}
    assert "replan_mean_return" in flown and flown["eval_starts"] == 4
    assert (out / "evaluation_storm_flights.png").stat().st_size > 1000
    capsys.readouterr()


def test_the_train_cli_refuses_an_evaluation_storm_before_building_anything(tmp_path, capsys):
    from rainuav import train

    rc = train.main(
        ["--scenario", "storm", "--storm-seed", "1000000", "--out", str(tmp_path / "r")]
    )
    err = capsys.readouterr().err
    assert rc == 2 and "evaluation storm" in err and "Traceback" not in err
    assert not (tmp_path / "r").exists()


@pytest.mark.parametrize(
    ("kw", "field"),
    [({"slice_s": 0.0}, "slice_s"), ({"freq_hz": "abc"}, "freq_hz"),
     ({"rain_rate_mm_h": "abc"}, "rain_rate"), ({"storm_seed": 1.5}, "storm_seed")],
)  # fmt: skip
def test_gym_make_refuses_a_bad_weather_keyword_in_one_line(kw, field) -> None:
    # Not silently replaced by a default (slice_s = 0 once became 5 s), never a TypeError.
    with pytest.raises(InvalidInputError, match=field):
        gym.make("rainuav/UAVNav-v0", scenario="storm", engine="ray", **kw)
