"""One network for every storm among flight levels: the weather view of every level against
the signal it claims to show, a bank of storms' levels against each storm's own levels, UAVs
with their own destinations and storms stepped at once against the scalar environment, the
network's inputs and moves, and a tiny run over the storm distribution among levels (seeded,
resumed, evaluated on a held-out storm)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import torch
from gymnasium.utils.env_checker import check_env
from rainuav.errors import InvalidInputError
from rainuav.nav.field import SignalField
from rainuav.nav.levels import UAVLevelsEnv
from rainuav.nav.task import NavConfig
from rainuav.nav.views import WeatherView
from rainuav.rl.config import DQNConfig
from rainuav.rl.dqn import memory_needed
from rainuav.rl.networks import MoveGeometry, WeatherEncoder
from test_one_network import EXTENT, T_S, exact, plane  # the analytic signal and its grid

ALTS = [30.0, 60.0, 90.0]


def coef(world: int, level: int) -> tuple[float, float, float, float]:
    """A plane in x, y and t per world and level (every level and world reads differently)."""
    return (0.02 - 0.01 * level, -0.015 + 0.005 * world, 0.3 * (level - 1), -4.0 + 3.0 * level)


def stacks(worlds: int = 2) -> np.ndarray:
    """(P, T, L, H, W): every world's levels in time."""
    return np.stack(
        [np.stack([plane(*coef(p, k)) for k in range(len(ALTS))], axis=1) for p in range(worlds)]
    )


def bank_env(**kw: object) -> UAVLevelsEnv:
    field = SignalField.bank(stacks(), T_S, EXTENT, ALTS)
    task = NavConfig(goal_m=(700.0, 500.0), max_steps=60, speed_m_s=5.0, min_db=-2.0)
    return UAVLevelsEnv(field, task, observation="weather", **kw)


def test_weather_view_among_levels_shows_every_level() -> None:
    """Every sample of the local window and of the whole-area grid, on every layer, equals the
    analytic signal of that level and world at the UAV's instant (1e-5 dB after tanh's
    inverse: float32); the level part is the level over the highest index."""
    env = bank_env()
    v = env.view
    assert v is not None and v.layers == 3
    pos = np.array([[330.0, 410.0], [20.0, 780.0]])  # the second: the window leaves the area
    tick, level, world = np.array([4, 9]), np.array([2, 0]), np.array([1, 0])
    obs = env.observe_batch(pos, level, tick, np.array([[700.0, 500.0]] * 2), world)
    assert obs["local"].shape == (2, 3, 11, 11) and obs["area"].shape == (2, 3, 16, 16)
    np.testing.assert_array_equal(obs["level"][:, 0], level / 2)
    off = v.local_offsets()
    pts = v.area_points(EXTENT)
    for n in range(2):
        t = float(env.stepper.time_s(tick[n]))
        for k in range(3):
            c = coef(int(world[n]), k)
            want = np.tanh((exact(pos[n, 0] + off[:, 0], pos[n, 1] + off[:, 1], t, c) + 2.0) / 10)
            np.testing.assert_allclose(obs["local"][n, k].ravel(), want, atol=1e-5)
            want = np.tanh((exact(pts[:, 0], pts[:, 1], t, c) + 2.0) / 10)
            np.testing.assert_allclose(obs["area"][n, k].ravel(), want, atol=1e-5)


def test_one_level_view_is_the_planes() -> None:
    """On one level the view has no level part and one layer: the flat encoding the storm
    network on one level was trained on (5 + 11^2 + 16^2 floats)."""
    v = WeatherView()
    assert "level" not in v.space().spaces and sum(v.sizes.values()) == 382 and v.vector == 5
    assert sum(WeatherView(layers=7).sizes.values()) == 6 + 7 * (121 + 256)


def test_level_bank_reads_each_world_as_its_own_levels() -> None:
    """A field of banks gives, point by point, what each world's own levels give (bit for
    bit); put() renews one world on every level."""
    s = stacks(3)
    bank = SignalField.bank(s, T_S, EXTENT, ALTS)
    rng = np.random.default_rng(3)
    x, y = rng.uniform(-50, 1050, 400), rng.uniform(-50, 850, 400)
    t, lv, w = rng.uniform(-5, 25, 400), rng.integers(0, 3, 400), rng.integers(0, 3, 400)
    got = bank(x, y, t, w, level=lv)
    for p in range(3):
        own = SignalField.from_stack(s[p], ALTS, EXTENT, t_s=T_S)
        on = w == p
        np.testing.assert_array_equal(got[on], own(x[on], y[on], t[on], level=lv[on]))
    bank.put(0, s[2])
    np.testing.assert_array_equal(bank(x, y, t, 0, level=lv), bank(x, y, t, 2, level=lv))
    assert bank.worlds == 3 and bank.banked
    with pytest.raises(InvalidInputError, match=r"must be finite, of shape \(3, 3, 40, 50\)"):
        bank.put(0, s[2][:, :2])
    with pytest.raises(InvalidInputError, match="put renews a world of a bank"):
        SignalField.from_stack(s[0], ALTS, EXTENT, t_s=T_S).put(0, s[1])


def test_batched_steps_with_destinations_and_storms_match_the_env() -> None:
    """UAVs among levels with their own destinations and storms, stepped at once (as
    training steps them: env.step_batch and observe_batch), get exactly the rewards, levels,
    clocks and observations of scalar environments reset to those tasks, over random
    sequences of the six moves."""
    env = bank_env(random_goal=True)
    rng = np.random.default_rng(4)
    n = 10
    singles, starts, goals, worlds = [], [], [], []
    for k in range(n):
        e = bank_env(random_goal=True)
        _, info = e.reset(seed=k)
        singles.append(e)
        starts.append(info["position_m"])
        goals.append(info["goal_m"])
        worlds.append(info["world"])
    starts, goals, worlds = np.array(starts), np.array(goals), np.array(worlds)
    off = np.zeros((n, 2), dtype=np.int64)
    lv, t = np.array([e._level[0] for e in singles]), np.zeros(n, dtype=np.int64)
    live = np.ones(n, dtype=bool)
    climbed = 0
    for _ in range(40):
        idx = np.flatnonzero(live)
        if not len(idx):
            break
        a = rng.integers(0, 6, len(idx))
        a[lv[idx] == 0] = rng.choice([0, 1, 2, 3, 4], (lv[idx] == 0).sum())  # few at once out
        r = env.step_batch(starts[idx], off[idx], lv[idx], t[idx], a, goals[idx], worlds[idx])
        climbed += int((r["level"] > 0).sum())
        off[idx], lv[idx], t[idx] = r["offset"], r["level"], r["t"]
        batch = env.observe_batch(r["position"], r["level"], r["t"], goals[idx], worlds[idx])
        for j, k in enumerate(idx):
            o, rew, term, trunc, info = singles[k].step(int(a[j]))
            assert rew == r["reward"][j] and info["level"] == r["level"][j]
            assert (term, trunc) == (r["terminated"][j], r["truncated"][j])
            np.testing.assert_array_equal(
                env.view.flat(o)[0], env.view.flat({q: v[j] for q, v in batch.items()})[0]
            )
            if term or trunc:
                live[k] = False
    assert climbed > 0 and len(set(worlds.tolist())) == 2  # both storms, above the lowest level


def test_weather_levels_env_passes_gymnasiums_checker() -> None:
    env = bank_env(random_goal=True)
    check_env(env, skip_render_check=True)
    obs, info = env.reset(seed=0, options={"goal_m": (500.0, 400.0), "world": 1})
    assert info["world"] == 1 and tuple(info["goal_m"]) == (500.0, 400.0)
    assert env.observation_space.contains(obs)
    assert isinstance(env.action_space, gym.spaces.Discrete) and env.action_space.n == 6


def test_the_network_among_levels_reads_every_layer_and_six_moves() -> None:
    """The weather network among levels takes the flat view of seven layers and gives six
    Q-values; a climb's and a descent's move features are zero (no arrival, no progress: they
    stay over the point); the memory check counts its weights as built."""
    cfg = DQNConfig(hidden=32, conv=4, move_features=True, goal_maps=True)
    view = WeatherView(layers=7)
    geometry = MoveGeometry((1000.0, 800.0), 10.0, 10.0)
    enc = WeatherEncoder(cfg, view, (0.01, 0.0125), geometry, n_actions=6)
    net = enc.make_net()
    x = torch.rand(5, enc.dim)
    assert net(x).shape == (5, 6)
    mf = net.move_features(x[:, : view.vector])
    assert mf.shape == (5, 6, 2) and torch.all(mf[:, 4:] == 0)
    params = sum(p.numel() for p in net.parameters())
    need = memory_needed(cfg, view, levels=True)
    assert need["dqn.hidden"] == 7 * 4 * params
    assert need["dqn.replay_capacity"] == cfg.replay_capacity * (2 * 4 * enc.dim + 20)


def test_bad_weather_options_among_levels_are_refused() -> None:
    field = SignalField.bank(stacks(), T_S, EXTENT, ALTS)
    task = NavConfig(goal_m=(700.0, 500.0), max_steps=60, min_db=-2.0)
    with pytest.raises(InvalidInputError, match="need observation='weather'"):
        UAVLevelsEnv(field, task)
    one = SignalField.from_stack(stacks()[0], ALTS, EXTENT, t_s=T_S)
    with pytest.raises(InvalidInputError, match="need observation='weather'"):
        UAVLevelsEnv(one, task, random_goal=True)
    with pytest.raises(InvalidInputError, match="observation must be one of"):
        UAVLevelsEnv(one, task, observation="radar")
    with pytest.raises(InvalidInputError, match=r"options\['world'\] must be an integer in 0..1"):
        bank_env().reset(options={"world": 2})
    with pytest.raises(InvalidInputError, match=r"options\['goal_m'\] needs observation"):
        UAVLevelsEnv(one, task).reset(options={"goal_m": (1.0, 1.0)})
    with pytest.raises(InvalidInputError, match=r"options\['goal_m'\] must be \(x, y\) inside"):
        bank_env().reset(options={"goal_m": (5000.0, 1.0)})
    with pytest.raises(InvalidInputError, match=r"layers must be an integer in 1\.\.64"):
        WeatherView(layers=0)
    with pytest.raises(InvalidInputError, match="as many worlds and instants"):
        two, three = (SignalField.bank(stacks(p), T_S, EXTENT, ALTS) for p in (2, 3))
        SignalField.of_levels([two.level(0), three.level(1)], ALTS[:2])


def pool_cfg(out: Path, **kw: object) -> object:
    """A tiny run over the storm distribution among two levels (2 storms renewed every 3
    episodes, 40 moves; half of them calm, whose weather does not move)."""
    from rainuav.rl.config import TrainConfig

    fields = {
        "scenario": "storm", "observation": "weather", "random_goal": True, "storm_pool": 2,
        "storm_episodes": 3, "task": NavConfig(max_steps=40), "out": str(out),
        "eval_starts": 3, "validate_every": 0, "stages": 1, "checkpoint_every": 1000,
        "engine": "ray", "altitudes_m": "50:110:60", "calm_share": 0.5,
        "dqn": DQNConfig(episodes=12, lanes=4, learning_starts=50, replay_capacity=1000,
                         hidden=16, conv=4),
    }  # fmt: skip
    return TrainConfig(**{**fields, **kw})


@pytest.mark.slow
@pytest.mark.timeout(240)
def test_storm_pool_among_levels_is_seeded_resumes_exactly_and_is_evaluated(
    tmp_path: Path,
) -> None:
    """A run over the storm distribution among levels, run twice with one seed (the second
    interrupted at a checkpoint and resumed), gives one log and one set of metrics; its
    storms are training storms; it is evaluated on a held-out storm against the exact plan
    among levels and the plans held at one altitude."""
    from rainuav.rl.loop import train
    from rainuav.world.pool import TRAINING_SEEDS, StormPool, is_calm

    def log(out: str) -> str:
        rows = (tmp_path / out / "log.csv").read_text().splitlines()
        return "\n".join(",".join(r.split(",")[:-1]) for r in rows)  # without the seconds

    cfg = pool_cfg(tmp_path / "a", checkpoint_every=6)
    pool = StormPool(cfg, cfg.seed)
    assert isinstance(pool.bank, SignalField) and pool.bank.levels == 2
    m_a = train(cfg, pool.world(), progress=False)
    cfg = pool_cfg(tmp_path / "b", checkpoint_every=6)
    assert train(cfg, StormPool(cfg, cfg.seed).world(), progress=False, stop_after=6) == {}
    m_b = train(cfg, StormPool(cfg, cfg.seed).world(), progress=False, resume=True)
    assert log("a") == log("b")
    keep = [k for k in m_a if "seconds" not in k]
    assert json.dumps({k: m_a[k] for k in keep}) == json.dumps({k: m_b[k] for k in keep})
    assert m_a["storms_flown"] == len(pool.flown) >= 3  # renewed at least once
    assert any(is_calm(k, 0.5) for k in pool.flown)
    assert all(TRAINING_SEEDS[0] <= k < TRAINING_SEEDS[1] for k in pool.flown)
    assert m_a["altitudes_m"] == [50.0, 110.0] and "fixed_altitude_success_rate" in m_a
    from rainuav.evaluate import main as evaluate_main  # the CLI: figures, flights, heights

    ev = tmp_path / "ev"
    argv = [str(tmp_path / "a"), "--storm-seeds", "1000000-1000000", "--starts", "2"]
    assert evaluate_main([*argv, "--out", str(ev)]) == 0
    result = json.loads((ev / "evaluation.json").read_text())
    row = result["worlds"][0]
    assert result["mean"]["held_out"] and row["storm_seed"] == 1_000_000
    for key in ("fixed_altitude_mean_excess_cost", "best_single_altitude_success_rate",
                "mean_altitude_m", "vertical_moves"):  # fmt: skip
        assert key in result["mean"]
    assert "frozen_plan_success_rate" not in result["mean"]
    assert (ev / "evaluation_trajectories.png").stat().st_size > 0


@pytest.mark.slow
def test_a_pool_that_cannot_fit_is_refused(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """The pool's memory is checked once its first storm is mapped, naming storm_pool (here
    one storm's levels need 0.04 GB to map and 1 MB to keep: 64 of them do not fit in 0.1
    GB, one does); its storms are flown once and never kept in the map cache."""
    from rainuav import _core
    from rainuav.world.pool import StormPool

    monkeypatch.setattr(_core, "available_memory_bytes", lambda: 10**8)
    monkeypatch.setenv("RAINUAV_CACHE_DIR", str(tmp_path / "cache"))
    cfg = pool_cfg(tmp_path)
    cfg = dataclasses.replace(cfg, task=dataclasses.replace(cfg.task, max_steps=10))
    with pytest.raises(InvalidInputError, match="storm_pool = 64 needs"):
        StormPool(dataclasses.replace(cfg, storm_pool=64), 0)
    pool = StormPool(dataclasses.replace(cfg, storm_pool=1), 0)
    pool.renew(0)
    pool.close()
    cached = tmp_path / "cache"
    assert len(pool.flown) == 2 and not (cached.exists() and any(cached.rglob("*.npz")))
