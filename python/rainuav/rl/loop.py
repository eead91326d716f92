"""The training job: Algorithm 1 with several UAVs in flight at once.

[`train()`][rainuav.rl.loop.train] receives a built world ([`rainuav.world`][rainuav.world]: the
signal and the task), builds its environment and the agent, then runs
[`run_loop()`][rainuav.rl.loop.run_loop], which reads top to bottom: collect (act, step the UAVs,
store their N-step transitions), update (sample, double-Q target, loss, optimiser step), and per
finished episode the agent's schedules (learning rate, target sync, weight averaging) and the
callbacks ([`rainuav.rl.callbacks`][rainuav.rl.callbacks]: log, stages, validation, then the
checkpoint and the wall-clock budget); the run's state is one object,
[`RunState`][rainuav.rl.callbacks.RunState], which the checkpoint saves and a resumed run
restores. The run ends with
[`finish()`][rainuav.rl.report.finish] (evaluation, ``policy.pt``, ``metrics.json``, figures).

Outputs in ``cfg.out``: ``config.toml``, the world's signal (``radiomap.npz``, or
``radiomap_series.npz`` for a weather that moves, ``radiolevels.npz`` among flight levels),
``log.csv``, TensorBoard events, ``checkpoint.pt`` (every ``checkpoint_every`` finished
episodes; ``resume=True`` with the same configuration continues from it and reproduces the
uninterrupted run), and at the end
``metrics.json``, ``policy.pt``, ``returns.png``, ``trajectories.png`` and ``stages.png``.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import tomli_w

from rainuav._io import FolderLock, check_out_dir, write_atomic
from rainuav.errors import InvalidInputError, TrainingDivergedError
from rainuav.nav.env import UAVNavEnv
from rainuav.nav.references import optimal_flights
from rainuav.nav.training import positions
from rainuav.radio.scene.storms import check_storm_seed
from rainuav.rl import checkpoint
from rainuav.rl.callbacks import (
    Callback,
    Checkpoint,
    EpisodeLog,
    RunState,
    Stages,
    TimeBudget,
    ValidationChecks,
)
from rainuav.rl.collect import Lanes
from rainuav.rl.config import (
    TrainConfig,
    check_config,
    random_streams,
    to_dict,
)
from rainuav.rl.dqn import Agent
from rainuav.rl.evaluation import (
    Validation,
    check_map_digest,
    eval_starts,
)
from rainuav.rl.learner import learner_ends, learning_reward, training_level, training_task
from rainuav.rl.report import finish
from rainuav.rl.resume import RESUME_MAY_DIFFER, config_diff
from rainuav.rl.runlog import RunLog
from rainuav.rl.setup import check_fits, make_agent, pick_device, torch_settings
from rainuav.world import World, build_world, task_of
from rainuav.world.pool import VALIDATION_SEEDS, StormPool

__all__ = [
    "collect",
    "finish",
    "load_checkpoint",
    "run_loop",
    "save_checkpoint",
    "storm_slot",
    "train",
    "update",
]


# -- setup ------------------------------------------------------------------------------------
def save_checkpoint(path: Path, state: dict[str, Any]) -> None:
    """Writes a checkpoint: tensors and plain data only, to a temporary file, then renamed.

    Args:
        path: The file.
        state: The run's state ([`rainuav.rl.checkpoint`][rainuav.rl.checkpoint]).
    """
    checkpoint.save(path, state)


CHECKPOINT_KEYS = RunState.KEYS
"""What a training checkpoint holds: the state object's own keys
([`RunState.KEYS`][rainuav.rl.callbacks.RunState.KEYS])."""


def load_checkpoint(path: Path, cfg: TrainConfig) -> dict[str, Any]:
    """The checkpoint of a run to resume, read as data.

    Args:
        path: The file ([`load()`][rainuav.rl.checkpoint.load]).
        cfg: The configuration resumed with.

    Returns:
        The checkpoint's state.

    Raises:
        InvalidInputError: No checkpoint there, one that is not a run's, or a run's configuration
            that differs from `cfg` (the fields named).
    """
    if not path.exists():
        raise InvalidInputError(f"--resume: no checkpoint at {path}")
    state = checkpoint.load(path, CHECKPOINT_KEYS)
    if not isinstance(state["config"], dict):
        raise InvalidInputError(f"checkpoint {path}: refused (its config is not a table)")
    diff = config_diff(state["config"], cfg, ignore=RESUME_MAY_DIFFER)
    if diff:
        raise InvalidInputError(
            f"--resume: the configuration differs from the checkpoint's in {'; '.join(diff)}"
        )
    return state


# -- the job ----------------------------------------------------------------------------------
def train(
    cfg: TrainConfig,
    world: World,
    *,
    resume: bool = False,
    progress: bool = True,
    stop_after: int | None = None,
    yardstick: bool = False,
    callbacks: Sequence[Callback] = (),
) -> dict[str, Any]:
    """Trains a dueling double DQN in a world and evaluates it against the exact optimum.

    The run writes its folder (``cfg.out``: the checkpoint, the policy, ``metrics.json``, the
    log and the figures; the world's signal is saved with it) and sets no process-wide state
    that outlives the call (torch's thread count and determinism are restored).

    Args:
        cfg: The whole run ([`TrainConfig`][rainuav.rl.config.TrainConfig]).
        world: Built from the configuration's world part by
            [`rainuav.world.build_world()`][rainuav.world.build_world] (tests hand in small
            synthetic worlds); its task must be the configuration's.
        resume: Continue the run in ``cfg.out`` from its checkpoint, exactly.
        progress: A progress line on standard error.
        stop_after: End the call, as an interruption would, at the first checkpoint with at
            least that many finished episodes (``resume=True`` then continues exactly).
        yardstick: Allow an evaluation storm (a per-storm network trained on the very storm a
            generalist is judged on, as the specialist it is compared with; not on the CLI).
        callbacks: More [`Callback`][rainuav.rl.callbacks.Callback]s, called after the run's
            own (one whose ``on_step`` returns True ends training, which then finishes as at its
            last episode).

    Returns:
        The metrics (``metrics.json``'s contents: success rate and excess cost over the exact
        optimum on the evaluation starts, beside the baselines'); ``{}`` after ``stop_after``.

    Raises:
        InvalidInputError: A world that is not the configuration's, or a resume without a
            checkpoint or with another configuration.
        TrainingDivergedError: The loss, weights or returns stopped being finite (nothing
            non-finite is saved).

    Examples:
        ```python
        import tempfile

        from rainuav.nav.task import NavConfig
        from rainuav.rl import DQNConfig, TrainConfig, train
        from rainuav.world import build_world

        cfg = TrainConfig(scenario="uma", engine="ray", out=tempfile.mkdtemp(), eval_starts=4,
                          validate_every=0, task=NavConfig(goal_m=(1400.0, 1600.0), max_steps=200),
                          dqn=DQNConfig(episodes=20, learning_starts=100))
        metrics = train(cfg, build_world(cfg), progress=False)
        print(metrics["episodes"], "episodes; greedy success", metrics["success_rate"])
        ```
    """
    check_config(cfg)
    if cfg.scenario == "storm" and not cfg.scenario_file and not yardstick:
        check_storm_seed(cfg.storm_seed, training=True)
    if not isinstance(world, World):
        raise InvalidInputError(f"world must be a rainuav.world.World (got {type(world).__name__})")
    want = task_of(cfg)
    if dataclasses.replace(world.task, min_db=want.min_db) != want:
        raise InvalidInputError(f"the world's task {world.task} is not the configuration's {want}")
    check_fits(cfg)
    out = check_out_dir(cfg.out, "out")
    device = pick_device(cfg.device)
    out.mkdir(parents=True, exist_ok=True)
    with FolderLock(out, "a rainuav.train run"):
        saved = load_checkpoint(out / "checkpoint.pt", cfg) if resume else None
        world.save(out)
        write_atomic(out / "config.toml", lambda t: t.write_text(tomli_w.dumps(to_dict(cfg))))
        env = world.env()
        if saved is not None and world.pool is None:
            check_map_digest(saved, world.field, out)
        # A storm pool's run is checked, validated and evaluated on a validation storm, with
        # the task's fixed destination.
        ref_env = None
        if world.pool is not None:
            spec = dataclasses.replace(
                cfg, storm_pool=0, storm_seed=VALIDATION_SEEDS[0], random_goal=False
            )
            ref_env = build_world(spec).env()
        with torch_settings(device):
            agent = make_agent(cfg, env, device)  # seeds torch with cfg.seed
            env.np_random = np.random.default_rng(random_streams(cfg.seed)["env"])
            return run_loop(
                cfg, agent, env, out, saved, progress, stop_after, ref_env, world.pool, callbacks
            )


def storm_slot(
    pool: StormPool, lanes: Lanes, k: int, per_storm: np.ndarray, storm_episodes: int
) -> int:
    """The storm of the pool a lane's next episode flies.

    Of the storms that have had `storm_episodes` episodes, the one with the fewest UAVs in flight
    drains: it takes no new episode (unless it is the only storm), so it stays the emptiest, and
    once no UAV flies it any more it is renewed
    ([`StormPool.renew()`][rainuav.world.pool.StormPool.renew]); one at a time, so the others keep
    the UAVs flying. The lane takes the storm with the fewest UAVs in flight (the first on ties), so
    with as many storms as lanes each UAV has its own.

    Args:
        pool: The storm pool.
        lanes: The UAVs in flight.
        k: The lane.
        per_storm: The episodes each storm has had (counted here).
        storm_episodes: The episodes a storm flies before it is renewed.

    Returns:
        The storm's slot.
    """
    others = lanes.active.copy()
    others[k] = False
    load = np.bincount(lanes.world[others], minlength=len(per_storm))
    drain = -1
    if (per_storm >= storm_episodes).any():
        big = np.iinfo(np.int64).max
        drain = int(np.argmin(np.where(per_storm >= storm_episodes, load, big)))
        if load[drain] == 0:
            pool.renew(drain)
            per_storm[drain], drain = 0, -1
    choices = np.array([s for s in range(len(per_storm)) if s != drain] or [drain])
    slot = int(choices[np.argmin(load[choices])])
    per_storm[slot] += 1
    return slot


def run_loop(
    cfg: TrainConfig,
    agent: Agent,
    env: UAVNavEnv,
    out: Path,
    saved: dict[str, Any] | None,
    progress: bool,
    stop_after: int | None,
    ref_env: UAVNavEnv | None = None,
    pool: StormPool | None = None,
    callbacks: Sequence[Callback] = (),
) -> dict[str, Any]:
    """Algorithm 1 over `cfg.dqn.episodes` episodes, `lanes` UAVs at a time.

    Each pass collects a move of every UAV in flight ([`collect()`][rainuav.rl.loop.collect]),
    learns ([`update()`][rainuav.rl.loop.update]), and per finished episode updates the agent's
    schedules, calls the callbacks ([`rainuav.rl.callbacks`][rainuav.rl.callbacks]: log, stages,
    validation) and relaunches the lane; after a pass that finished some, the log, the budget and
    the checkpoint.

    Args:
        cfg: The run's configuration.
        agent: The agent.
        env: The environment trained in.
        out: The run's folder.
        saved: A checkpoint's state to resume from; None: a new run.
        progress: A progress bar.
        stop_after: End the call after this many episodes (a test of resuming); None: the run's.
        ref_env: The environment validation, stages and the evaluation fly (default: `env`).
        pool: The storms the UAVs fly ([`storm_slot()`][rainuav.rl.loop.storm_slot]).
        callbacks: Callbacks beside the run's own.

    Returns:
        [`finish()`][rainuav.rl.report.finish]'s metrics, or `{}` when stopped at `stop_after`.
    """
    d = cfg.dqn
    ref = env if ref_env is None else ref_env
    n_val = cfg.validate_starts if cfg.validate_every else 0
    val_starts = eval_starts(ref, n_val, cfg.eval_seed + 2)
    run = RunState(
        agent=agent,
        env=env,
        lanes=Lanes.empty(min(d.lanes, d.episodes), d.n_step, d.gamma),
        checks=Validation(val_starts, optimal_flights(ref, val_starts)),
        pool=pool,
        per_storm=np.zeros(pool.bank.worlds if pool else 1, dtype=np.int64),
    )
    stages = Stages(
        max(1, d.episodes // max(cfg.stages, 1)), ref, eval_starts(ref, 5, cfg.eval_seed + 1)
    )

    def launch(k: int) -> None:
        start, goal, world = training_task(env, d, env.np_random)
        if pool is not None:
            world = storm_slot(pool, run.lanes, k, run.per_storm, cfg.storm_episodes)
        level = training_level(env, d, start, env.np_random)
        run.lanes.launch(k, start, run.started, goal, world, level)
        run.started += 1

    if saved is not None:
        run.load_state_dict(saved, out / "checkpoint.pt", d.episodes)
    else:
        for k in range(len(run.lanes.t)):
            launch(k)
    log = RunLog(out, saved is not None, d.episodes, run.done, progress)
    ckpt = Checkpoint(out / "checkpoint.pt", cfg, log, stop_after)
    per_episode = [EpisodeLog(log), stages, ValidationChecks(cfg.validate_every, ref, log)]
    per_episode += callbacks
    per_step = [per_episode[0], TimeBudget(cfg.time_budget_s), *callbacks]
    run.t0 = time.perf_counter()
    try:
        while run.lanes.active.any():
            idx, r = collect(run, cfg)
            update(run, len(idx))
            before = run.done
            for j in np.flatnonzero(r["terminated"] | r["truncated"]):
                k = idx[j]
                run.returns.append(float(run.lanes.ret[k]))
                run.successes.append(bool(r["arrived"][j]))
                agent.schedule(run.done)
                for cb in per_episode:
                    cb.on_episode(run, k)
                if run.started < d.episodes:
                    launch(k)
                else:
                    run.lanes.active[k] = False
            if run.done == before:
                continue
            stopping = any([cb.on_step(run, before) for cb in per_step])  # each one, in order
            if ckpt.after(run, before, stopping):
                return {}
            if stopping:
                break
    finally:
        log.close()
    if pool is not None:
        pool.close()
    return finish(cfg, agent, ref, run.returns, run.stages, run.seconds(), out, run.checks, pool)


def collect(run: RunState, cfg: TrainConfig) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """One move of every UAV in flight: observe, act (epsilon-greedy), step.

    Each UAV's finished N-step transitions go to the replay.

    Args:
        run: The run's state.
        cfg: The run's configuration.

    Returns:
        `(lanes that moved, the step's results)`.
    """
    env, agent, lanes, d = run.env, run.agent, run.lanes, cfg.dqn
    idx = np.flatnonzero(lanes.active)
    pos = positions(env, lanes.start[idx], lanes.offset[idx])
    # each UAV's destination (where its observation holds one: the weather's) and world
    goal = lanes.goal[idx] if "goal" in getattr(env.observation_space, "spaces", {}) else None
    world = lanes.world[idx] if run.pool is not None else None
    level, t = lanes.level[idx], lanes.t[idx]
    obs = agent.observe(env.observe_batch(pos, level, t, goal, world), t)
    act = agent.act(obs, lanes.episode[idx], env.exploration_moves(level))
    r = env.step_batch(lanes.start[idx], lanes.offset[idx], level, t, act, goal, world)
    lanes.offset[idx], lanes.level[idx], lanes.t[idx] = r["offset"], r["level"], r["t"]
    lanes.ret[idx] += r["reward"]
    nobs = agent.observe(env.observe_batch(r["position"], r["level"], r["t"], goal, world), r["t"])
    stop = learner_ends(d, r)
    learn_r = learning_reward(env, d, pos, r, goal)
    for j, k in enumerate(idx):
        for tr in lanes.windows[k].push(
            obs[j], int(act[j]), float(learn_r[j]), nobs[j], bool(stop[j]), bool(r["truncated"][j])
        ):
            agent.replay.add(*tr)
    return idx, r


def update(run: RunState, moves: int) -> None:
    """The gradient steps new transitions pay for: one per `train_every`.

    Args:
        run: The run's state.
        moves: The transitions collected since the last update.

    Raises:
        TrainingDivergedError: A loss that is not finite ([`diverged()`][rainuav.rl.loop.diverged]).
    """
    every = run.agent.cfg.train_every
    run.pending += moves
    for _ in range(run.pending // every):
        loss = run.agent.learn()
        if loss is not None:
            if not math.isfinite(loss):
                raise diverged(run.agent, loss)
            run.losses.append(loss)
    run.pending %= every


def diverged(agent: Agent, loss: float) -> TrainingDivergedError:
    """The one-line error of a training whose loss stopped being finite.

    It names the gradient step and the settings that usually cause it.

    Args:
        agent: The agent.
        loss: The loss.

    Returns:
        The [`TrainingDivergedError`][rainuav.errors.TrainingDivergedError] to raise.
    """
    c = agent.cfg
    return TrainingDivergedError(
        f"training diverged at gradient step {agent.updates}: the loss is {loss} (dqn.lr "
        f"{c.lr:g}, dqn.grad-clip {c.grad_clip:g}, dqn.loss {c.loss}, dqn.reward-scale "
        f"{c.reward_scale:g}); lower dqn.lr, keep dqn.grad-clip above 0 or use the huber loss. "
        "Nothing of this step was saved"
    )
