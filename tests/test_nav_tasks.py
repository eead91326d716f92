"""The navigation task on physical maps: which signal it flies, its default threshold, the
registered environment (``gym.make`` / ``gym.make_vec``), the vector environment against
Gymnasium's own ``SyncVectorEnv`` of scalar envs, the cost metrics and the learner preset."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import rainuav  # noqa: F401 - registers rainuav/UAVNav-v0
from gymnasium.utils.env_checker import check_env
from gymnasium.vector import AutoresetMode, SyncVectorEnv
from rainuav.errors import InvalidInputError
from rainuav.nav import UAVNavEnv, flight_cost, planner
from rainuav.nav.task import NavConfig
from rainuav.nav.vector import UAVNavVectorEnv
from rainuav.radio.outputs.maps import RadioMap
from rainuav.radio.scene.scenario import Area, Scenario, Site
from rainuav.rl.config import DQNConfig, TrainConfig
from rainuav.rl.evaluation import flights, reference_flights, summarise
from rainuav.world import in_world


def _map(name: str = "uma", sinr_shift: float = -6.0) -> RadioMap:
    """A 400 m x 400 m map whose SIR and SINR differ (noise), two cells split east/west."""
    h = w = 40
    x = (np.arange(w) + 0.5) * 10
    y = (np.arange(h) + 0.5) * 10
    xx, yy = np.meshgrid(x, y)
    sir = 15.0 - 20.0 * np.exp(-((xx - 200) ** 2 + (yy - 200) ** 2) / 80.0**2)
    area = Area(x_min_m=0, x_max_m=400, y_min_m=0, y_max_m=400, resolution_m=10)
    return RadioMap(
        x_m=x,
        y_m=y,
        extent_m=(0, 400, 0, 400),
        altitude_m=100.0,
        rss_dbm=np.zeros((2, h, w)),
        serving_cell=(xx > 200).astype(np.int64),
        sir_db=sir,
        sinr_db=sir + sinr_shift,
        scenario=Scenario(name=name, area=area, sites=[Site(x_m=200.0, y_m=200.0)]),
        cell_site=np.zeros(2, np.int64),
    )


TASK = {"goal_m": (300.0, 350.0), "max_steps": 100}


# -- which signal, which threshold --------------------------------------------------------------
def test_flies_sinr_by_default_with_the_presets_threshold() -> None:
    rm = _map("uma")
    env = UAVNavEnv(radio_map=rm, **TASK)
    assert env.cfg.signal == "sinr" and env.cfg.min_db == -2.0  # SINR_THRESHOLDS_DB["uma"]
    np.testing.assert_array_equal(env.field.db, rm.sinr_db)
    sir = UAVNavEnv(radio_map=rm, signal="sir", **TASK)
    assert sir.cfg.min_db == 10.0  # the paper's minimum SIR
    np.testing.assert_array_equal(sir.field.db, rm.sir_db)
    # A scenario of no preset, and raw arrays, fall back to 10 dB; a given threshold wins.
    assert UAVNavEnv(radio_map=_map("mine"), **TASK).cfg.min_db == 10.0
    raw = UAVNavEnv(sinr_db=rm.sinr_db, extent_m=rm.extent_m, **TASK)
    assert raw.cfg.signal == "sinr" and raw.cfg.min_db == 10.0
    assert UAVNavEnv(sir_db=rm.sir_db, extent_m=rm.extent_m, **TASK).cfg.signal == "sir"
    assert UAVNavEnv(radio_map=rm, min_db=3.5, **TASK).cfg.min_db == 3.5
    # The rewards are the shortfall below the threshold of the signal flown.
    env.reset(options={"start_m": (105.0, 205.0)})
    _, r, *_ = env.step(0)
    s = float(env.field(115.0, 205.0))
    assert r == pytest.approx(-1.0 - env.cfg.mu * max(0.0, -2.0 - s))


def test_info_names_the_serving_cell() -> None:
    env = UAVNavEnv(radio_map=_map(), **TASK)
    _, info = env.reset(options={"start_m": (195.0, 105.0)})
    assert info["serving_cell"] == 0
    _, _, _, _, info = env.step(0)  # to x = 205: the east cell's pixel
    assert info["serving_cell"] == 1 and set(info) >= {"signal_db", "outage", "position_m"}
    raw = UAVNavEnv(sinr_db=_map().sinr_db, extent_m=(0, 400, 0, 400), **TASK)
    assert raw.reset(seed=0)[1]["serving_cell"] == -1  # a raw array names no cell


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"min_db": float("nan")}, "min_db"),
        ({"min_db": float("inf")}, "min_db"),
        ({"signal": "snr"}, "signal"),
        ({"signal": "sir", "sinr_db": np.zeros((4, 4)), "extent_m": (0, 1, 0, 1)}, "signal"),
        ({"sinr_db": np.zeros((4, 4)), "sir_db": np.zeros((4, 4))}, "sinr_db"),
        ({"sinr_db": np.full((4, 4), np.nan), "extent_m": (0, 1, 0, 1)}, "sinr_db"),
    ],
)
def test_bad_task_input_names_the_field(kwargs: dict, field: str) -> None:
    if not any(k.endswith("_db") and k != "min_db" for k in kwargs):
        kwargs = {"radio_map": _map(), **kwargs}
    with pytest.raises(InvalidInputError, match=field):
        UAVNavEnv(**kwargs, **TASK)


def test_a_map_without_sinr_is_refused_for_sinr() -> None:
    rm = _map()
    rm.sinr_db = None  # e.g. a map object from a version that had no noise model
    with pytest.raises(InvalidInputError, match="sinr_db"):
        UAVNavEnv(radio_map=rm)
    assert UAVNavEnv(radio_map=rm, signal="sir", **TASK).cfg.signal == "sir"


# -- the registered environment -----------------------------------------------------------------
def test_gym_make_takes_a_map_or_a_scenario() -> None:
    rm = _map()
    env = gym.make("rainuav/UAVNav-v0", radio_map=rm, **TASK)
    check_env(env.unwrapped, skip_render_check=True)
    assert env.unwrapped.cfg.min_db == -2.0
    # A preset by name, in rain, with the ray engine (about a second; the default hybrid
    # engine is the same call, slower): the map is the one the radio layer builds.
    env = gym.make("rainuav/UAVNav-v0", scenario="uma", rain_rate_mm_h=50, engine="ray")
    u = env.unwrapped
    assert u.cfg.signal == "sinr" and u.cfg.min_db == -2.0
    obs, info = env.reset(seed=3)
    assert obs.shape == (2,) and 0 <= info["serving_cell"] < 21
    with pytest.raises(InvalidInputError, match="scenario"):
        gym.make("rainuav/UAVNav-v0", scenario="nowhere")
    with pytest.raises(InvalidInputError, match="rain_rate_mm_h needs scenario"):
        gym.make("rainuav/UAVNav-v0", radio_map=rm, rain_rate_mm_h=5.0)


def _random_actions(n_steps: int, n: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).integers(4, size=(n_steps, n))


def test_vector_env_equals_gymnasiums_sync_vector_env() -> None:
    # The task's fixed start (near a corner, so random moves often leave the area), the same
    # random actions: the batched vector env and Gymnasium's own SyncVectorEnv of scalar envs
    # (next-step autoreset) give identical streams, episodes ending and restarting included.
    rm = _map()
    n = 6
    task = {**TASK, "start_m": (25.0, 35.0)}
    vec = gym.make_vec(
        "rainuav/UAVNav-v0", num_envs=n, vectorization_mode="vector_entry_point",
        radio_map=rm, **task,
    )  # fmt: skip
    ref = SyncVectorEnv([lambda: UAVNavEnv(radio_map=rm, **task) for _ in range(n)])
    assert vec.metadata["autoreset_mode"] == ref.metadata["autoreset_mode"]
    a_obs, _ = vec.reset(seed=0)
    b_obs, _ = ref.reset(seed=0)
    np.testing.assert_array_equal(a_obs, b_obs)
    ended = 0
    for acts in _random_actions(400, n, 1):
        a = vec.step(acts)
        b = ref.step(acts)
        for x, y in zip(a[:4], b[:4], strict=True):
            np.testing.assert_array_equal(x, y)
        np.testing.assert_array_equal(a[4]["signal_db"], b[4]["signal_db"])
        np.testing.assert_array_equal(a[4]["serving_cell"], b[4]["serving_cell"])
        ended += int(np.sum(a[2] | a[3]))
    assert ended > n  # episodes ended (and restarted) on the way


def test_vector_env_same_step_autoreset_and_errors() -> None:
    env = UAVNavEnv(radio_map=_map(), **TASK)
    vec = UAVNavVectorEnv(env, 3, AutoresetMode.SAME_STEP)
    vec.reset(seed=0, options={"start_m": (305.0, 325.0)})  # two moves +y from arrival
    vec.step(np.array([1, 1, 3]))
    obs, r, term, _, info = vec.step(np.array([1, 0, 3]))
    assert term.tolist() == [True, False, False] and info["arrived"].tolist() == [1, 0, 0]
    assert r[0] > 1000  # the arrival reward
    np.testing.assert_allclose(info["final_obs"][0], env.observe(np.array([305.0, 345.0])))
    assert info["_final_obs"].tolist() == [True, False, False]
    assert not np.allclose(obs[0], info["final_obs"][0])  # already restarted (a random start)
    with pytest.raises(InvalidInputError, match="num_envs"):
        UAVNavVectorEnv(env, 0)
    with pytest.raises(InvalidInputError, match="actions"):
        vec.step(np.array([0, 4, 1]))


# -- costs and the baseline ---------------------------------------------------------------------
def test_flight_cost_and_excess_cost_by_hand() -> None:
    env = UAVNavEnv(radio_map=_map(), **TASK)
    c = env.cfg
    # Arrived with return R: cost = -(R - R_des); not arrived: -R (the penalty stays in).
    np.testing.assert_allclose(
        flight_cost([c.goal_reward - 30.0, -500.0], [True, False], c), [30.0, 500.0]
    )
    starts = np.array([[15.0, 25.0], [395.0, 15.0], [105.0, 305.0]])
    refs = reference_flights(env, starts)
    opt, line = refs["optimal"], refs["straight_line"]
    assert opt["arrived"].all() and line["arrived"].all()
    # The optimum is never costlier than the straight line; its own excess is 0.
    assert np.all(opt["cost"] <= line["cost"] + 1e-9)
    assert summarise(opt, opt)["mean_excess_cost"] == 0.0
    s = summarise(line, opt)
    want = np.mean((line["cost"] - opt["cost"]) / opt["cost"])
    assert s["mean_excess_cost"] == pytest.approx(want)
    # The cost of the straight line by hand: moves plus mu times the shortfall at each point.
    p = planner.straight_line(env, starts[0])
    sig = env.field(p.path_m[1:, 0], p.path_m[1:, 1])
    by_hand = len(sig) + c.mu * np.maximum(0.0, c.min_db - sig).sum()
    assert line["cost"][0] == pytest.approx(by_hand, rel=1e-12)
    f = flights(env, [p.return_], [True], [p.path_m])
    assert f["outage_sum"][0] == np.sum(sig < c.min_db)


def test_train_cli_sets_every_task_field_and_refuses_bad_values(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from rainuav.train import build_parser, config_from_args, main

    flags = {
        "--task.step-m": "20", "--task.tol-m": "15", "--task.goal-reward": "500",
        "--task.out-of-bounds-penalty": "900", "--task.signal": "sir", "--task.min-db": "3",
        "--task.goal-m": "100,200", "--task.max-steps": "50",
    }  # fmt: skip
    args = build_parser().parse_args([x for kv in flags.items() for x in kv])
    cfg = config_from_args(args)
    t = cfg.task
    assert (t.step_m, t.tol_m, t.goal_reward, t.out_of_bounds_penalty) == (20.0, 15.0, 500.0, 900.0)
    assert (t.signal, t.min_db, t.goal_m, t.max_steps) == ("sir", 3.0, (100.0, 200.0), 50)
    assert main(["--task.min-db", "nan", "--out", str(tmp_path)]) == 2
    assert "min_db" in capsys.readouterr().err


def test_time_budget_ends_training_early(tmp_path: Path) -> None:
    from rainuav.rl.loop import train
    from rainuav.train import budget_note

    cfg = TrainConfig(
        out=str(tmp_path), task=NavConfig(goal_m=(300.0, 350.0), max_steps=60), eval_starts=5,
        validate_every=0, time_budget_s=1e-9, dqn=DQNConfig(episodes=500, lanes=4),
    )  # fmt: skip
    m = train(*in_world(cfg, _map()), progress=False)
    # The budget is spent at once: training ends with the first finished episodes.
    assert 1 <= m["episodes"] < 20, m["episodes"]
    assert (tmp_path / "checkpoint.pt").exists() and (tmp_path / "metrics.json").exists()
    # The command says so, and how to go on (a run that ran its episodes says nothing).
    note = budget_note(m["episodes"], 500, cfg.time_budget_s, tmp_path)
    assert f"after {m['episodes']} of 500 episodes" in note and "--resume --config" in note
    assert budget_note(500, 500, cfg.time_budget_s, tmp_path) == ""


def test_evaluate_refuses_a_run_from_an_incompatible_version(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from rainuav.evaluate import main
    from rainuav.rl.loop import train

    cfg = TrainConfig(
        out=str(tmp_path), task=NavConfig(goal_m=(300.0, 350.0), max_steps=30), eval_starts=3,
        validate_every=0, dqn=DQNConfig(episodes=2, lanes=2),
    )  # fmt: skip
    train(*in_world(cfg, _map()), progress=False)
    text = (tmp_path / "config.toml").read_text()
    # A field this version does not know (a run written by another version).
    (tmp_path / "config.toml").write_text("sir_min_db = 10.0\n" + text)
    assert main([str(tmp_path)]) == 2
    assert "sir_min_db" in capsys.readouterr().err
    # A network that does not fit the checkpoint's weights: the checkpoint's own record of the
    # configuration names the field that differs, before any weight is read.
    (tmp_path / "config.toml").write_text(text.replace("hidden = 128", "hidden = 64"))
    assert main([str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "checkpoint.pt" in err and "dqn.hidden: 128 -> 64" in err, err


def test_a_saved_policy_flies_on_another_map_object_with_shared_references(
    tmp_path: Path,
) -> None:
    # What studies use for the paper's case (f): a run's network flown on a map given as an
    # object. Flying it on its own saved map gives the run's own numbers; reusing the exact
    # planner's flights (references) changes nothing; a map and a world at once is refused.
    from rainuav.radio.outputs.maps import RadioMap
    from rainuav.rl.evaluation import evaluate_saved_run
    from rainuav.rl.loop import train

    cfg = TrainConfig(
        out=str(tmp_path), task=NavConfig(goal_m=(300.0, 350.0), max_steps=30), eval_starts=5,
        validate_every=0, dqn=DQNConfig(episodes=2, lanes=2),
    )  # fmt: skip
    own = train(*in_world(cfg, _map()), progress=False)
    rm = RadioMap.load(tmp_path / "radiomap.npz")
    refs: dict = {}
    first, _, _ = evaluate_saved_run(tmp_path, radio_map=rm, references=refs)
    again, _, _ = evaluate_saved_run(tmp_path, radio_map=rm, references=refs)
    assert len(refs) == 1  # computed once, reused
    for k in ("success_rate", "mean_excess_cost", "optimal_mean_cost", "mean_return"):
        assert first[k] == again[k] == own[k], k
    with pytest.raises(InvalidInputError, match="radio_map"):
        evaluate_saved_run(tmp_path, radio_map=rm, world=in_world(cfg, rm)[1])
