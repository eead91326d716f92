"""One network for every storm: the weather observation against the map it claims
to show, the destination distribution, a bank of worlds against its members, per-UAV
destinations in the batched stepper against the scalar env, the storm pool's seeds, and a
seeded run over the storm distribution reproduced."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from rainuav.errors import InvalidInputError
from rainuav.nav.env import UAVNavEnv
from rainuav.nav.field import SignalField
from rainuav.nav.task import MOVES, NavConfig
from rainuav.nav.views import GOAL_MARGIN_M, REACH, WeatherView, sample_goal, sample_start_for

EXTENT = (0.0, 1000.0, 0.0, 800.0)
H, W = 40, 50  # 20 m pixels over 1000 x 800 m
T_S = np.array([0.0, 10.0, 20.0])


def plane(a: float, b: float, c: float, d: float) -> np.ndarray:
    """A signal linear in x, y and t, dB, sampled at the pixel centres of (K, H, W): bilinear
    in space and linear in time reproduce it exactly between the outermost centres."""
    x = EXTENT[0] + (np.arange(W) + 0.5) * (EXTENT[1] - EXTENT[0]) / W
    y = EXTENT[2] + (np.arange(H) + 0.5) * (EXTENT[3] - EXTENT[2]) / H
    return a * x[None, None, :] + b * y[None, :, None] + c * T_S[:, None, None] + d


def exact(x: np.ndarray, y: np.ndarray, t: float, coef: tuple[float, ...]) -> np.ndarray:
    """The analytic plane at (x, y, t), with the edge values beyond the outermost centres."""
    a, b, c, d = coef
    x = np.clip(x, EXTENT[0] + 10.0, EXTENT[1] - 10.0)
    y = np.clip(y, EXTENT[2] + 10.0, EXTENT[3] - 10.0)
    return a * x + b * y + c * np.clip(t, T_S[0], T_S[-1]) + d


COEF = (0.02, -0.015, 0.3, -4.0)


def weather_env(**kw: object) -> UAVNavEnv:
    field = SignalField.series(plane(*COEF), T_S, EXTENT)
    task = NavConfig(goal_m=(700.0, 500.0), max_steps=50, speed_m_s=5.0, min_db=-2.0)
    return UAVNavEnv(field=field, config=task, observation="weather", **kw)


def test_weather_observation_shows_the_map_it_claims() -> None:
    """Every sample of the local window and of the whole-area grid equals the analytic signal
    at its documented point and instant, through tanh((S - min_db) / scale_db), to float32
    rounding (the field is linear, so the map's interpolation is exact: 1e-5)."""
    env = weather_env()
    v = env.view
    assert v is not None
    pos = np.array([[330.0, 410.0], [20.0, 780.0]])  # the second: the window leaves the area
    t = np.array([3, 7])
    goal = np.array([[700.0, 500.0], [100.0, 100.0]])
    obs = env.observe(pos, t, goal)
    assert env.observation_space.contains({k: val[0] for k, val in obs.items()})
    for n in range(2):
        t_s = t[n] * env.cfg.move_s
        h = v.window // 2
        for i in range(v.window):
            for j in range(v.window):
                x = pos[n, 0] + (j - h) * v.window_step_m
                y = pos[n, 1] + (i - h) * v.window_step_m
                want = np.tanh((exact(x, y, t_s, COEF) + 2.0) / v.scale_db)
                assert obs["local"][n, 0, i, j] == pytest.approx(want, abs=1e-5)
        for i in range(v.area):
            for j in range(v.area):
                x = (j + 0.5) * 1000.0 / v.area
                y = (i + 0.5) * 800.0 / v.area
                want = np.tanh((exact(x, y, t_s, COEF) + 2.0) / v.scale_db)
                assert obs["area"][n, 0, i, j] == pytest.approx(want, abs=1e-5)
        assert obs["time"][n, 0] == pytest.approx(t[n] / 50)
    np.testing.assert_allclose(obs["position"], pos / [1000.0, 800.0], atol=1e-6)
    np.testing.assert_allclose(obs["goal"], goal / [1000.0, 800.0], atol=1e-6)
    flat = v.flat(obs)
    assert flat.shape == (2, sum(v.sizes.values()))
    np.testing.assert_array_equal(flat[:, 5 : 5 + v.window**2], obs["local"].reshape(2, -1))


def test_weather_env_passes_gymnasiums_checker() -> None:
    from gymnasium.utils.env_checker import check_env

    check_env(weather_env(random_goal=True), skip_render_check=True)


def test_destination_distribution() -> None:
    """Destinations are uniform in the area shrunk by the margin (20 000 draws: the range
    within 1%, the mean within 3 standard errors, each quartile within 1% of the side);
    starts lie within reach of theirs and outside the arrival disc."""
    rng = np.random.default_rng(0)
    g = np.array([sample_goal(rng, EXTENT) for _ in range(20_000)])
    for axis, (lo, hi) in enumerate([(EXTENT[0], EXTENT[1]), (EXTENT[2], EXTENT[3])]):
        a, b = lo + GOAL_MARGIN_M, hi - GOAL_MARGIN_M
        assert g[:, axis].min() >= a and g[:, axis].max() <= b
        assert g[:, axis].min() < a + 0.01 * (b - a) and g[:, axis].max() > b - 0.01 * (b - a)
        se = (b - a) / np.sqrt(12 * len(g))
        assert abs(g[:, axis].mean() - (a + b) / 2) < 3 * se
        q = np.quantile(g[:, axis], [0.25, 0.5, 0.75])
        np.testing.assert_allclose(
            q, a + (b - a) * np.array([0.25, 0.5, 0.75]), atol=0.01 * (b - a)
        )
    cfg = NavConfig(max_steps=40)
    for goal in g[:500]:
        s = sample_start_for(rng, EXTENT, goal, cfg)
        assert np.abs(s - goal).sum() <= REACH * 40 * cfg.step_m
        assert np.hypot(*(s - goal)) > cfg.tol_m
    env = weather_env(random_goal=True)
    goals = []
    for k in range(50):
        obs, info = env.reset(seed=k)
        goals.append(info["goal_m"])
        np.testing.assert_allclose(obs["goal"], info["goal_m"] / [1000.0, 800.0], atol=1e-6)
    assert len({tuple(x) for x in goals}) == 50  # drawn per episode


def test_fixed_destination_stays_the_tasks() -> None:
    env = weather_env()
    for k in range(5):
        _, info = env.reset(seed=k)
        assert tuple(info["goal_m"]) == (700.0, 500.0)


def test_bank_reads_each_world_as_its_series() -> None:
    """A bank of three worlds gives, point by point, what each world's own series gives
    (bit for bit: the same operations); put() replaces one world."""
    worlds = [plane(0.01 * k, -0.02, 0.1 * k, k) for k in range(3)]
    bank = SignalField.bank(worlds, T_S, EXTENT)
    rng = np.random.default_rng(1)
    x, y = rng.uniform(-50, 1050, 300), rng.uniform(-50, 850, 300)
    t = rng.uniform(-5, 25, 300)
    w = rng.integers(0, 3, 300)
    got = bank(x, y, t, w)
    for k in range(3):
        own = SignalField.series(worlds[k], T_S, EXTENT)
        np.testing.assert_array_equal(got[w == k], own(x[w == k], y[w == k], t[w == k]))
    pts = np.stack([x[:40], y[:40]], axis=1)  # fixed points (an area grid) at many instants
    np.testing.assert_allclose(
        bank.at_points(pts, t, w), bank(pts[None, :, 0], pts[None, :, 1], t[:, None], w[:, None]),
        rtol=0, atol=1e-12,
    )  # fmt: skip
    bank.put(1, worlds[2])
    np.testing.assert_allclose(bank.at_points(pts, t, 1)[:, :3], bank(x[:3], y[:3], t[:, None], 1))
    np.testing.assert_array_equal(
        bank(x, y, t, 1), SignalField.series(worlds[2], T_S, EXTENT)(x, y, t)
    )
    with pytest.raises(InvalidInputError, match="sinr_db must be finite"):
        bank.put(0, np.full_like(worlds[0], np.nan))


def test_batched_destinations_match_scalar_envs() -> None:
    """UAVs with their own destinations stepped at once (the batched stepper, as training
    steps them) get exactly the transitions of scalar envs built with those destinations."""
    env = weather_env()
    rng = np.random.default_rng(2)
    n = 12
    goals = np.array([sample_goal(rng, EXTENT) for _ in range(n)])
    starts = np.array([sample_start_for(rng, EXTENT, g, env.cfg) for g in goals])
    off, t = np.zeros((n, 2), dtype=np.int64), np.zeros(n, dtype=np.int64)
    singles = []
    for s, g in zip(starts, goals, strict=True):
        e = UAVNavEnv(
            field=env.field,
            config=dataclasses.replace(env.cfg, goal_m=tuple(g)),
            observation="weather",
        )
        e.reset(options={"start_m": s})
        singles.append(e)
    live = np.ones(n, dtype=bool)
    for _ in range(60):
        idx = np.flatnonzero(live)
        if not len(idx):
            break
        a = rng.integers(0, 4, len(idx))
        r = env.step_batch(starts[idx], off[idx], np.zeros_like(idx), t[idx], a, goals[idx])
        off[idx], t[idx] = r["offset"], r["t"]
        for j, k in enumerate(idx):
            _, rew, term, trunc, _ = singles[k].step(int(a[j]))
            assert rew == r["reward"][j]
            assert (term, trunc) == (r["terminated"][j], r["truncated"][j])
            if term or trunc:
                live[k] = False
    assert not live.any() or t.max() == 60


def test_bad_weather_options_are_refused() -> None:
    with pytest.raises(
        InvalidInputError, match="random_goal and a bank of worlds need observation='weather'"
    ):
        UAVNavEnv(field=weather_env().field, goal_m=(500.0, 500.0), random_goal=True)
    with pytest.raises(InvalidInputError, match="observation must be one of"):
        UAVNavEnv(field=weather_env().field, goal_m=(500.0, 500.0), observation="radar")
    with pytest.raises(InvalidInputError, match="window must be an odd integer"):
        WeatherView(window=4)
    with pytest.raises(InvalidInputError, match=r"options\['goal_m'\] must be"):
        weather_env().reset(options={"goal_m": (5000.0, 0.0)})


def pool_cfg(out: object, **kw: object) -> object:
    """A tiny run over the storm distribution (2 storms renewed every 3 episodes; the ray
    engine: what is checked is the pool, not the propagation)."""
    from rainuav.rl.config import DQNConfig, TrainConfig

    fields = {
        "scenario": "storm", "observation": "weather", "random_goal": True, "storm_pool": 2,
        "storm_episodes": 3, "task": NavConfig(max_steps=40), "out": str(out),
        "eval_starts": 3, "validate_every": 0, "stages": 1, "checkpoint_every": 1000,
        "engine": "ray",
        "dqn": DQNConfig(episodes=16, lanes=4, learning_starts=50, replay_capacity=2000,
                         hidden=16),
    }  # fmt: skip
    return TrainConfig(**{**fields, **kw})


@pytest.mark.slow
@pytest.mark.timeout(240)
def test_storm_pool_run_is_seeded_resumes_exactly_and_never_flies_reserved_storms(
    tmp_path,
) -> None:
    """A second run over the storm distribution with the same seed, interrupted at a
    checkpoint with UAVs in flight and storms renewed and then resumed, gives the first run's
    log and metrics (CPU; the pool's storms, its seed stream and its episode counts are in the
    checkpoint); every storm the pool mapped is a training storm (below the validation seeds,
    so also below the evaluation seeds); its storms are renewed as asked."""
    from rainuav.rl.loop import train
    from rainuav.world.pool import TRAINING_SEEDS, StormPool

    def log(out: str) -> str:
        rows = (tmp_path / out / "log.csv").read_text().splitlines()
        return "\n".join(",".join(r.split(",")[:-1]) for r in rows)  # without the seconds

    cfg = pool_cfg(tmp_path / "a", checkpoint_every=6)
    pool = StormPool(cfg, cfg.seed)
    m_a = train(cfg, pool.world(), progress=False)
    cfg = pool_cfg(tmp_path / "b", checkpoint_every=6)
    assert train(cfg, StormPool(cfg, cfg.seed).world(), progress=False, stop_after=6) == {}
    m_b = train(cfg, StormPool(cfg, cfg.seed).world(), progress=False, resume=True)
    assert log("a") == log("b")
    keep = [k for k in m_a if "seconds" not in k]
    assert json.dumps({k: m_a[k] for k in keep}) == json.dumps({k: m_b[k] for k in keep})
    # 16 episodes over 2 storms renewed every 3 (each drained of its UAVs first): at least 3
    # renewals, all training seeds.
    assert m_a["storms_flown"] >= 5 and m_a["storms_flown"] == len(pool.flown)
    assert all(TRAINING_SEEDS[0] <= k < TRAINING_SEEDS[1] for k in pool.flown)
    assert m_a["evaluated_on_storm_seed"] == 900_000
    # The run flown through a held-out storm it never saw (the figures' plumbing; the
    # numbers of a real run are in the README), and refused where it has no world of its own.
    from rainuav.evaluate import main as evaluate_main
    from rainuav.rl.storm_eval import evaluate_storms

    result, first = evaluate_storms(tmp_path / "a", [1_000_000], starts=2, progress=False)
    row = result["worlds"][0]
    assert result["mean"]["held_out"] and row["storm_seed"] == 1_000_000
    assert row["eval_starts"] == 2 and 0.0 <= row["success_rate"] <= 1.0
    assert "frozen_plan_mean_excess_cost" in row and "replan_success_rate" in row
    assert first is not None
    on, _ = evaluate_storms(tmp_path / "a", [1_000_000], starts=2, progress=False, online=True)
    assert on["mean"]["online"] is True and result["mean"]["online"] is False
    assert evaluate_main([str(tmp_path / "a")]) == 2


@pytest.mark.parametrize(
    ("text", "match"),
    [("5-3", "must be A-B"), ("x", "must be A-B"), ("1-2-3", "must be A-B"), ("0-5000", "at most")],
)
def test_storm_seed_ranges_are_checked(text: str, match: str) -> None:
    from rainuav.rl.storm_eval import parse_seeds

    with pytest.raises(InvalidInputError, match=match):
        parse_seeds(text)
    assert parse_seeds("7-9") == [7, 8, 9] and parse_seeds("4") == [4]


def test_gym_make_gives_the_weather_observation() -> None:
    """``gym.make`` passes observation and random_goal through (a Dict space; SB3's
    MultiInputPolicy reads it); the vector env keeps one destination and says so."""
    import gymnasium as gym
    import rainuav  # noqa: F401 - registers the env

    kw = {"sinr_db": plane(*COEF)[0], "extent_m": EXTENT, "goal_m": (500.0, 400.0)}
    env = gym.make("rainuav/UAVNav-v0", observation="weather", random_goal=True, **kw)
    assert isinstance(env.observation_space, gym.spaces.Dict)
    obs, info = env.reset(seed=3)
    assert env.observation_space.contains(obs) and "goal_m" in info
    vec = gym.make_vec(
        "rainuav/UAVNav-v0", num_envs=3, vectorization_mode="vector_entry_point",
        observation="weather", **kw,
    )  # fmt: skip
    obs, _ = vec.reset(seed=0)
    assert obs["local"].shape == (3, 1, 11, 11)
    with pytest.raises(InvalidInputError, match="random_goal: the vector env"):
        gym.make_vec(
            "rainuav/UAVNav-v0", num_envs=3, vectorization_mode="vector_entry_point",
            observation="weather", random_goal=True, **kw,
        )  # fmt: skip


@pytest.mark.slow
def test_move_features_tell_what_each_move_does() -> None:
    """The weather network's move features (``move_features``) against the env itself: for
    300 (start, destination) pairs, a third of them a few moves from the destination, the
    arrival feature of each move that stays in the area is the env's ``arrived`` after that
    move, and the progress
    feature is the drop of the straight distance to the destination in moves (1e-3: float32
    positions of a 1000 m area, 1e-4 m, over 10 m moves)."""
    from dataclasses import replace

    import torch
    from rainuav.nav.training import network_inputs
    from rainuav.rl.config import DQNConfig
    from rainuav.rl.setup import make_encoder

    env = weather_env(random_goal=True)
    d = DQNConfig(move_features=True, conv=4, hidden=16)
    enc = make_encoder(d, replace(network_inputs(env), step=(0.01, 0.0125)))
    net = enc.make_net()
    rng = np.random.default_rng(3)
    arrivals = 0
    for n in range(300):
        goal = sample_goal(rng, EXTENT)
        near = goal + rng.uniform(-25.0, 25.0, 2)
        start = near if n % 3 == 0 and np.hypot(*(near - goal)) > 10.0 else None
        start = sample_start_for(rng, EXTENT, goal, env.cfg) if start is None else start
        obs, _ = env.reset(options={"start_m": start, "goal_m": goal})
        x = torch.as_tensor(enc({k: v[None] for k, v in obs.items()}, 0))
        feats = net.move_features(x[:, :5])[0].numpy()
        for a in range(4):
            env.reset(options={"start_m": start, "goal_m": goal})
            _, _, _, _, info = env.step(a)
            after = start + env.cfg.step_m * MOVES[a]
            if not (0 <= after[0] <= 1000 and 0 <= after[1] <= 800):
                continue  # a move out of the area ends the flight there: no geometry to check
            np.testing.assert_allclose(info["position_m"], after)
            assert feats[a, 0] == float(info["arrived"]), (start, goal, a)
            want = (np.hypot(*(start - goal)) - np.hypot(*(after - goal))) / env.cfg.step_m
            assert feats[a, 1] == pytest.approx(want, abs=1e-3)
            arrivals += info["arrived"]
    assert arrivals > 20  # the near starts do test the arrival disc


def test_goal_maps_draw_the_destination_on_the_grids() -> None:
    """``goal_maps``: the extra channels against the env's own grids (their points from
    ``WeatherView.local_offsets`` and ``area_points``), for 50 random (position, destination)
    pairs: each area cell's distance to the destination and to the UAV over the area's
    diagonal, and each window point's approach to the destination over the window's
    half-width (1e-5: float32 positions of a 1000 m area); the network takes them as extra
    input channels; without the flag the network is unchanged."""
    from dataclasses import replace

    import torch
    from rainuav.nav.training import network_inputs
    from rainuav.rl.config import DQNConfig
    from rainuav.rl.setup import make_encoder

    env = weather_env(random_goal=True)
    enc = make_encoder(
        DQNConfig(goal_maps=True, conv=4, hidden=16),
        replace(network_inputs(env), step=(0.01, 0.0125)),
    )
    net = enc.make_net()
    assert net.local[0].in_channels == 2 and net.whole[0].in_channels == 3
    plain = make_encoder(
        DQNConfig(conv=4, hidden=16), replace(network_inputs(env), step=(0.01, 0.0125))
    ).make_net()
    assert plain.goal_maps is None and plain.whole[0].in_channels == 1
    rng = np.random.default_rng(4)
    cells, off = env.view.area_points(EXTENT), env.view.local_offsets()
    diag, reach = np.hypot(1000.0, 800.0), (env.view.window // 2) * env.view.window_step_m
    for _ in range(50):
        goal = sample_goal(rng, EXTENT)
        start = sample_start_for(rng, EXTENT, goal, env.cfg)
        obs, _ = env.reset(options={"start_m": start, "goal_m": goal})
        x = torch.as_tensor(enc({k: v[None] for k, v in obs.items()}, 0))
        near, area = (a[0].numpy() for a in net.goal_channels(x[:, :5]))
        np.testing.assert_allclose(area[0].ravel(), np.hypot(*(cells - goal).T) / diag, atol=1e-5)
        np.testing.assert_allclose(area[1].ravel(), np.hypot(*(cells - start).T) / diag, atol=1e-5)
        approach = np.hypot(*(goal - start)) - np.hypot(*(goal - start - off).T)
        np.testing.assert_allclose(near.ravel(), np.clip(approach / reach, -1, 1), atol=1e-5)
        assert net(x).shape == (1, 4)


def test_runs_without_move_features_keep_their_network() -> None:
    """A run saved before the move features (its config has neither ``conv`` nor
    ``move_features``) builds the network it was trained with: 16/32 channels, no move
    features; with them the per-move gain is the only new weight shared by the moves."""
    from dataclasses import replace

    from rainuav.nav.training import network_inputs
    from rainuav.rl.config import DQNConfig
    from rainuav.rl.setup import make_encoder

    env = weather_env()
    old = make_encoder(DQNConfig(), replace(network_inputs(env), step=(0.01, 0.0125))).make_net()
    assert old.moves is None and old.local[0].out_channels == 16
    new = make_encoder(
        DQNConfig(move_features=True, conv=8), replace(network_inputs(env), step=(0.01, 0.0125))
    ).make_net()
    assert new.local[2].out_channels == 16 and new.move_gain.weight.shape == (1, 2)


def test_task_goals_mix_the_tasks_destination_into_training() -> None:
    """With ``task_goals = 0.3`` a drawn-destination env's training flights go to the task's
    own destination 30% of the time (4000 draws: within 3 standard errors), the rest to drawn
    ones; with 0 the draws are exactly the env's own (the random stream untouched); an env
    with the fixed destination is not affected."""
    from rainuav.rl.config import DQNConfig
    from rainuav.rl.learner import training_task

    env = weather_env(random_goal=True)
    task = np.asarray(env.cfg.goal_m)
    rng = np.random.default_rng(3)
    d = DQNConfig(task_goals=0.3, goal_starts=0.0)
    own = [np.array_equal(training_task(env, d, rng)[1], task) for _ in range(4000)]
    se = np.sqrt(0.3 * 0.7 / len(own))
    assert abs(np.mean(own) - 0.3) < 3 * se
    a, b = np.random.default_rng(5), np.random.default_rng(5)
    plain = DQNConfig(task_goals=0.0, goal_starts=0.0)
    for _ in range(50):
        got, want = training_task(env, plain, a), env.draw_task(b)
        np.testing.assert_array_equal(got[0], want[0])
        np.testing.assert_array_equal(got[1], want[1])
    fixed = weather_env()
    goals = {tuple(training_task(fixed, d, rng)[1]) for _ in range(50)}
    assert goals == {(700.0, 500.0)}
    from rainuav.rl.config import TrainConfig, check_config

    with pytest.raises(InvalidInputError, match="task_goals must be in"):
        check_config(TrainConfig(dqn=DQNConfig(task_goals=1.5)))


@pytest.mark.slow
@pytest.mark.timeout(240)
def test_calm_pool_storms_are_the_background_alone() -> None:
    """``calm_share`` picks calm storms by their seed alone (20 000 seeds: the share within 3
    standard errors; 0 never); a calm storm's maps do not change in time and equal the map
    series of the same storm with its cells taken out by hand (the uniform background alone,
    through the preset's homogeneous-rain path), to float32 rounding."""
    from rainuav.radio.outputs.timemap import build_radio_map_series
    from rainuav.radio.scene import presets
    from rainuav.world import series_instants
    from rainuav.world.pool import StormPool, is_calm

    flags = [is_calm(k, 0.15) for k in range(20_000)]
    assert abs(np.mean(flags) - 0.15) < 3 * np.sqrt(0.15 * 0.85 / 20_000)
    assert not any(is_calm(k, 0.0) for k in range(1000))
    assert flags[:50] == [is_calm(k, 0.15) for k in range(50)]  # the seed alone decides
    cfg = pool_cfg("unused", storm_pool=1, calm_share=1.0)
    pool = StormPool(cfg, 0)
    try:
        (seed,) = pool.seeds
        slices = pool.bank.db[0]
        assert np.all(slices == slices[:1])
        storm = presets.storm(seed=seed)
        bg = storm.medium.rain_rate_mm_h
        by_hand = presets.with_rain(presets.uma(0.0, 28e9), bg)
        ref = build_radio_map_series(by_hand, series_instants(cfg), cache=False)
        np.testing.assert_allclose(slices, ref.sinr_db, atol=1e-4)
    finally:
        pool.close()
