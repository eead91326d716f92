"""The navigation environment, its batched stepper and the exact planner."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import rainuav
from gymnasium.utils.env_checker import check_env
from rainuav.nav import LoiteringWarning, UAVNavEnv
from rainuav.nav import planner as plan

EXT = (0.0, 400.0, 0.0, 300.0)


def small_map(seed: int = 0, h: int = 30, w: int = 40) -> np.ndarray:
    return np.random.default_rng(seed).uniform(-10, 30, (h, w))


def env(**kw) -> UAVNavEnv:
    base = {"sir_db": small_map(), "extent_m": EXT, "goal_m": (300.0, 200.0)}
    return UAVNavEnv(**{**base, **kw})


def test_check_env_and_registration() -> None:
    e = env()
    check_env(e, skip_render_check=True)
    made = gym.make("rainuav/UAVNav-v0", sir_db=small_map(), extent_m=EXT, goal_m=(300.0, 200.0))
    assert made.observation_space.shape == (2,)


def test_sir_interpolation_semantics() -> None:
    s = np.array([[0.0, 10.0], [20.0, 30.0]])
    e = UAVNavEnv(sir_db=s, extent_m=(0, 20, 0, 20), goal_m=(10, 10))
    f = e.field
    assert f(5.0, 5.0) == 0.0  # sample [0, 0] at the cell centre (5, 5)
    assert f(15.0, 15.0) == 30.0
    assert f(10.0, 5.0) == pytest.approx(5.0)  # halfway between [0,0] and [0,1]
    assert f(0.0, 0.0) == 0.0  # clamp beyond the outermost centres
    assert f(10.0, 10.0) == pytest.approx(15.0)


def test_step_semantics() -> None:
    e = env(mu=0.5, goal_reward=100.0, out_of_bounds_penalty=1000.0, max_steps=3)
    obs, info = e.reset(options={"start_m": (5.0, 150.0)})
    assert obs.dtype == np.float32 and obs == pytest.approx([5 / 400, 0.5])
    _, r, term, trunc, info = e.step(2)  # -x: leaves the area
    sir = e.field(0.0, 150.0)
    assert term and not trunc
    assert r == pytest.approx(-1 - 0.5 * max(0, 10 - sir) - 1000.0)
    assert info["position_m"] == pytest.approx([0.0, 150.0])
    e.reset(options={"start_m": (290.0, 200.0)})
    _, r, term, _, info = e.step(0)  # +x onto the goal
    assert term and info["arrived"]
    assert r == pytest.approx(-1 - 0.5 * max(0, 10 - e.field(300.0, 200.0)) + 100.0)
    e.reset(options={"start_m": (100.0, 100.0)})
    outs = [e.step(1)[2:4] for _ in range(3)]
    assert outs == [(False, False), (False, False), (False, True)]


def test_rewards_and_loitering_warning() -> None:
    e = env(reward="outage", mu=2.0)
    e.reset(options={"start_m": (100.0, 100.0)})
    _, r, *_ = e.step(0)
    assert r in (-1.0, -3.0)
    with pytest.warns(LoiteringWarning):
        env(reward="linear")


def test_batched_stepper_equals_scalar_env() -> None:
    e = env()
    rng = np.random.default_rng(3)
    n, steps = 64, 40
    starts = np.array([e.sample_start(rng) for _ in range(n)])
    actions = rng.integers(0, 4, (steps, n))
    off = np.zeros((n, 2), dtype=np.int64)
    t = np.zeros(n, dtype=np.int64)
    done = np.zeros(n, dtype=bool)
    batch_rewards = np.zeros((steps, n))
    for k in range(steps):
        r = e.step_batch(starts, off, np.zeros(n, dtype=np.int64), t, actions[k])
        batch_rewards[k] = np.where(done, np.nan, r["reward"])
        done |= r["terminated"] | r["truncated"]
        off, t = r["offset"], r["t"]
    for i in range(n):
        e.reset(options={"start_m": starts[i]})
        for k in range(steps):
            _, rew, term, trunc, _ = e.step(actions[k, i])
            assert rew == batch_rewards[k, i]  # bit-exact
            if term or trunc:
                break


@pytest.mark.parametrize("reward", ["shortfall", "outage", "linear"])
def test_planner_against_brute_force(reward: str, best_return_of_every_sequence) -> None:
    # 6 moves, 4^6 sequences: the DP optimum must equal the best enumerated return.
    kw = {
        "sir_db": small_map(1, 4, 5),
        "extent_m": (0, 50, 0, 40),
        "goal_m": (30.0, 30.0),
        "max_steps": 6,
        "mu": 0.3,
        "reward": reward,
        "goal_reward": 50.0,
    }
    if reward == "linear":
        with pytest.warns(LoiteringWarning):
            e = UAVNavEnv(**kw)
    else:
        e = UAVNavEnv(**kw)
    for start in ([0.0, 0.0], [10.0, 30.0], [45.0, 5.0]):
        p = plan.optimal(e, start)
        best = best_return_of_every_sequence(e, np.array(start), 6)
        assert p.return_ == pytest.approx(best, abs=1e-9)


def test_plans_replay_to_their_return() -> None:
    e = env(max_steps=120)
    starts = np.array([e.sample_start(np.random.default_rng(i)) for i in range(20)])
    for p in plan.optimal_many(e, starts):
        e.reset(options={"start_m": p.path_m[0]})
        g = 0.0
        for k, a in enumerate(p.actions):
            _, r, *_, info = e.step(a)
            g += r
            np.testing.assert_array_equal(info["position_m"], p.path_m[k + 1])
        assert g == p.return_
        base = plan.straight_line(e, p.path_m[0])
        assert base.return_ <= p.return_ + 1e-9


@pytest.mark.parametrize(
    ("kw", "needle"),
    [
        ({"sir_db": np.full((3, 3), np.nan)}, "sir_db"),
        ({"sir_db": np.ones(5)}, "sir_db"),
        ({"extent_m": (400.0, 0.0, 0.0, 300.0)}, "extent_m"),
        ({"goal_m": (500.0, 10.0)}, "goal_m"),
        ({"step_m": 0.0}, "step_m"),
        ({"tol_m": -1.0}, "tol_m"),
        ({"max_steps": 0}, "max_steps"),
        ({"reward": "bonus"}, "reward"),
        ({"start_m": (-5.0, 0.0)}, "start_m"),
    ],
)
def test_bad_input(kw, needle) -> None:
    with pytest.raises(ValueError, match=needle) as info:
        env(**kw)
    assert isinstance(info.value, rainuav.InvalidInputError)


def bfs_moves_to_goal(e: UAVNavEnv, start: np.ndarray) -> float:
    """Breadth-first search over the lattice through ``start`` inside the area."""
    x0, x1, y0, y1 = e.field.extent
    s, goal = e.cfg.step_m, np.asarray(e.cfg.goal_m)
    seen, frontier, depth = {(0, 0)}, [(0, 0)], 0
    while frontier:
        nxt = []
        for k in frontier:
            q = start + s * np.array(k)
            if np.hypot(*(q - goal)) <= e.cfg.tol_m:
                return depth
            for m in ((1, 0), (0, 1), (-1, 0), (0, -1)):
                k2 = (k[0] + m[0], k[1] + m[1])
                q2 = start + s * np.array(k2)
                if k2 not in seen and x0 <= q2[0] <= x1 and y0 <= q2[1] <= y1:
                    seen.add(k2)
                    nxt.append(k2)
        frontier, depth = nxt, depth + 1
    return np.inf


@pytest.mark.parametrize("tol", [4.0, 10.0, 23.0])
def test_moves_to_goal_against_search(tol: float) -> None:
    # Exact integers on every start, including a goal at the area's edge (300 m wide area,
    # goal at x = 395: part of the arrival disc lies outside) and tolerances below, at and
    # above the step.
    rng = np.random.default_rng(3)
    for goal in ((300.0, 200.0), (395.0, 150.0)):
        e = env(goal_m=goal, tol_m=tol)
        starts = rng.uniform((0, 0), (400, 300), (25, 2))
        want = [bfs_moves_to_goal(e, p) for p in starts]
        np.testing.assert_array_equal(e.stepper.moves_to_goal(starts), want)


def test_shielded_flights_always_arrive_in_time() -> None:
    # Any policy that keeps to the safe moves arrives within max_steps from every start that
    # can arrive at all: random safe moves from 200 starts, the tightest limit for each.
    e = env()
    rng = np.random.default_rng(4)
    starts = rng.uniform((0, 0), (400, 300), (200, 2))
    need = e.stepper.moves_to_goal(starts)
    for slack in (0, 7):
        ew = env(max_steps=int(need.max()) + slack)
        off, t = np.zeros((200, 2), np.int64), np.zeros(200, np.int64)
        live, arrived = np.ones(200, bool), np.zeros(200, bool)
        limit = need + slack  # each start's own deadline, counted through t
        while live.any():
            i = np.flatnonzero(live)
            pos = starts[i] + ew.cfg.step_m * off[i]
            # Shift each UAV's clock so that its own deadline is the env's max_steps.
            clock = t[i] + (ew.cfg.max_steps - limit[i]).astype(np.int64)
            ok = ew.stepper.safe_actions(pos, clock)
            a = np.array([rng.choice(np.flatnonzero(row)) for row in ok])
            r = ew.step_batch(starts[i], off[i], np.zeros_like(i), clock, a)
            off[i], t[i] = r["offset"], t[i] + 1
            assert not r["out"].any()
            arrived[i[r["arrived"]]] = True
            live[i[r["terminated"] | r["truncated"]]] = False
        assert arrived.all()
        assert np.all(t <= limit)


def test_planner_refuses_plans_beyond_memory() -> None:
    # A 40 km x 40 km area at 10 m steps with a 10 000-move horizon: each plan would keep
    # 16 million lattice points x 10 kB of policy (~160 GB). The planner checks before it
    # allocates and names the size; before, the allocation aborted the
    # Python process.
    env = UAVNavEnv(
        sir_db=np.zeros((4, 4)),
        extent_m=(0.0, 40_000.0, 0.0, 40_000.0),
        goal_m=(20_000.0, 20_000.0),
        max_steps=10_000,
    )
    with pytest.raises(rainuav.InvalidInputError, match=r"max_steps.*needs \d+\.\d+ GB"):
        plan.optimal_many(env, [[100.0, 100.0], [39_000.0, 100.0]])
    with pytest.raises(rainuav.InvalidInputError, match="max_steps"):
        plan.optimal(env, [100.0, 100.0])


def test_the_binding_takes_one_signal_array_and_one_task() -> None:
    """The Rust planner reads one array (time, level, north, east) and one task built from the
    configuration (``rust_task``); a plan through it is the environment's plan, and a mask,
    a start level or a task item that does not fit is refused by its name."""
    from rainuav import _core
    from rainuav.nav.task import NavConfig

    e = env(max_steps=40)
    want = plan.optimal(e, [50.0, 50.0])
    cfg = NavConfig(goal_m=(300.0, 200.0), max_steps=40, min_db=e.cfg.min_db)
    task = plan.rust_task(cfg, EXT)
    sig = np.ascontiguousarray(small_map()[None, None])
    starts = np.array([[50.0, 50.0, 0.0]])
    ((ret, actions, path, ticks),) = _core.plan_optimal_levels(sig, np.zeros(1), starts, task)
    assert ret == pytest.approx(want.return_, abs=1e-9)  # the same programme: to rounding
    np.testing.assert_array_equal(actions, want.actions)
    np.testing.assert_array_equal(path[:, :2], want.path_m)
    np.testing.assert_array_equal(ticks, np.arange(len(actions) + 1))
    bad = [
        ({"blocked": np.zeros((2, 30, 40), np.uint8)}, {}, "blocked"),
        ({}, {"climb": [1]}, "climb"),
        ({}, {"dt_s": 0.0}, "dt_s"),
        ({}, {"reward": "best"}, "reward"),
    ]
    for extra, items, needle in bad:
        with pytest.raises(rainuav.InvalidInputError, match=needle):
            _core.plan_optimal_levels(sig, np.zeros(1), starts, {**task, **items}, **extra)
    with pytest.raises(rainuav.InvalidInputError, match="starts"):
        _core.plan_optimal_levels(sig, np.zeros(1), np.array([[50.0, 50.0, 1.0]]), task)
    with pytest.raises(KeyError, match="mu"):
        _core.plan_optimal_levels(
            sig, np.zeros(1), starts, {k: v for k, v in task.items() if k != "mu"}
        )


def test_chance_weighted_planner_against_brute_force(best_return_of_every_sequence) -> None:
    """The ``"chance"`` reward (a move costs ``1 + mu P``, ``P`` the field's ``outage_p`` where
    it ends): the Rust planner's plan against every 6-move sequence flown by the Python
    environment with that reward, to 1e-9; and the environment against the same environment on
    the field ``-P`` with the ``shortfall`` reward at 0 dB, whose base reward is the same
    ``-1 - mu max(0, 0 + P)`` (another code path), move by move."""
    from rainuav.nav.field import SignalField

    rng = np.random.default_rng(4)
    prob = rng.uniform(0, 1, (4, 5))
    kw = {"extent_m": (0, 50, 0, 40), "goal_m": (30.0, 30.0), "max_steps": 6, "mu": 0.7,
          "goal_reward": 50.0}  # fmt: skip
    field = SignalField(small_map(2, 4, 5), kw.pop("extent_m"), outage_p=prob)
    e = UAVNavEnv(field=field, reward="chance", min_db=5.0, **kw)
    for start in ([0.0, 0.0], [10.0, 30.0], [45.0, 5.0]):
        p = plan.optimal(e, start)
        best = best_return_of_every_sequence(e, np.array(start), 6)
        assert p.return_ == pytest.approx(best, abs=1e-9)
    twin = UAVNavEnv(sir_db=-prob, extent_m=field.extent, reward="shortfall", min_db=0.0, **kw)
    for env_ in (e, twin):
        env_.reset(options={"start_m": [10.0, 10.0]})
    for a in rng.integers(0, 4, 6):
        r1, r2 = e.step(int(a))[1], twin.step(int(a))[1]
        assert r1 == pytest.approx(r2, abs=1e-12)
    with pytest.raises(rainuav.errors.InvalidInputError, match="outage probabilities"):
        UAVNavEnv(sir_db=-prob, extent_m=field.extent, reward="chance", **kw)
