"""The training job: Algorithm 1 with several UAVs in flight at once.

[`train()`][rainuav.rl.loop.train] receives a built world ([`rainuav.world`][rainuav.world]: the
signal and the task), builds its environment and the agent, then runs
[`run_loop()`][rainuav.rl.loop.run_loop], which reads top to bottom: act, step the UAVs, store their
N-step transitions, learn (sample, double-Q target, loss, optimiser step), and per finished episode
anneal, sync the target, record stages, validate and checkpoint. The run ends with
[`finish()`][rainuav.rl.loop.finish] (evaluation, ``policy.pt``, ``metrics.json``, figures).

Outputs in ``cfg.out``: ``config.toml``, the world's signal (``radiomap.npz``, or
``radiomap_series.npz`` for a weather that moves, ``radiolevels.npz`` among flight levels),
``log.csv``, TensorBoard events, ``checkpoint.pt`` (every ``checkpoint_every`` finished
episodes; ``resume=True`` with the same configuration continues from it and reproduces the
uninterrupted run), and at the end
``metrics.json``, ``policy.pt``, ``returns.png``, ``trajectories.png`` and ``stages.png``.
"""

from __future__ import annotations

import dataclasses
import json
import time
from pathlib import Path
from typing import Any

import numpy as np
import tomli_w
import torch

from rainuav._io import FolderLock, check_out_dir, write_atomic
from rainuav.errors import InvalidInputError
from rainuav.nav.env import UAVNavEnv
from rainuav.radio.storms import check_storm_seed
from rainuav.rl import checkpoint
from rainuav.rl.collect import (
    Lanes,
    exploration_moves,
    greedy_rollouts,
    observe,
    step,
)
from rainuav.rl.config import (
    TrainConfig,
    check_config,
    config_diff,
    random_streams,
    to_dict,
)
from rainuav.rl.dqn import Agent
from rainuav.rl.evaluation import (
    Validation,
    eval_starts,
    evaluate_run_policy,
)
from rainuav.rl.learner import learner_ends, learning_reward, training_level, training_task
from rainuav.rl.plots import plot_policy, plot_returns, plot_stages, plot_storm_flights
from rainuav.rl.references import optimal_flights
from rainuav.rl.runlog import RunLog
from rainuav.rl.setup import check_fits, make_agent, pick_device, torch_settings
from rainuav.world import World, build_world, task_of
from rainuav.world.pool import VALIDATION_SEEDS, StormPool

__all__ = ["finish", "load_checkpoint", "run_loop", "save_checkpoint", "storm_slot", "train"]

RESUME_MAY_DIFFER = ("device", "out", "time_budget_s")
"""Fields a resumed run may change (the rest must equal the checkpoint's): the device, the
folder's path (a run folder moved or copied elsewhere resumes where it now is; its results do
not depend on where it lives) and the wall-clock budget (a run its budget stopped, on a slower
machine, continues with a larger one to the episodes it was given, as if it had never
stopped)."""


# -- setup ------------------------------------------------------------------------------------
def save_checkpoint(path: Path, state: dict[str, Any]) -> None:
    """Tensors and plain data only ([`rainuav.rl.checkpoint`][rainuav.rl.checkpoint]), to a
    temporary file, then rename."""
    checkpoint.save(path, state)


CHECKPOINT_KEYS = (
    "agent", "env_rng", "lanes", "started", "returns", "successes", "stages", "pending",
    "validation", "train_seconds", "torch_rng", "config",
)  # fmt: skip
"""What a training checkpoint holds."""


def load_checkpoint(path: Path, cfg: TrainConfig) -> dict[str, Any]:
    """The checkpoint at ``path`` (read as data:
    [`rainuav.rl.checkpoint.load()`][rainuav.rl.checkpoint.load]), refused if its run's
    configuration differs from ``cfg`` (the differing fields are named)."""
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
) -> dict[str, Any]:
    """Runs the whole job in ``world`` (built by the caller from the configuration's world part,
    [`rainuav.world.build_world()`][rainuav.world.build_world]; tests hand in small synthetic
    worlds; its task must be the configuration's) and returns the metrics; the world's signal is
    saved with the run. ``stop_after`` ends the call, as an interruption would, at the first
    checkpoint with at least that many finished episodes (``resume=True`` then continues exactly);
    it returns ``{}``. Sets no process-wide state that outlives the call (torch's thread count and
    determinism are restored). ``yardstick``: allow an evaluation storm (a per-storm network trained
    on the very storm a generalist is judged on, as the specialist it is compared with; not on the
    CLI)."""
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
            return run_loop(cfg, agent, env, out, saved, progress, stop_after, ref_env, world.pool)


def storm_slot(
    pool: StormPool, lanes: Lanes, k: int, per_storm: np.ndarray, storm_episodes: int
) -> int:
    """The storm of the pool lane ``k``'s next episode flies, counted in ``per_storm``.

    Of the storms that have had ``storm_episodes`` episodes, the one with the fewest UAVs in flight
    drains: it takes no new episode (unless it is the only storm), so it stays the emptiest, and
    once no UAV flies it any more it is renewed
    ([`StormPool.renew()`][rainuav.world.pool.StormPool.renew]); one at a time, so the others keep
    the UAVs flying. The lane takes the storm with the fewest UAVs in flight (the first on ties), so
    with as many storms as lanes each UAV has its own."""
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
) -> dict[str, Any]:
    """Algorithm 1 over ``cfg.dqn.episodes`` episodes, ``lanes`` UAVs at a time; from ``saved`` (a
    checkpoint's state) when resuming. Returns [`finish()`][rainuav.rl.loop.finish]'s metrics, or
    ``{}`` when stopped at ``stop_after``. ``pool``: the storms the UAVs fly
    ([`storm_slot()`][rainuav.rl.loop.storm_slot]); validation, stages and the evaluation then fly
    ``ref_env`` (default: ``env``)."""
    d = cfg.dqn
    ref = env if ref_env is None else ref_env
    lanes = Lanes.empty(min(d.lanes, d.episodes), d.n_step, d.gamma)
    n_val = cfg.validate_starts if cfg.validate_every else 0
    val_starts = eval_starts(ref, n_val, cfg.eval_seed + 2)
    checks = Validation(val_starts, optimal_flights(ref, val_starts))
    stage_every = max(1, d.episodes // max(cfg.stages, 1))
    stage_starts = eval_starts(ref, 5, cfg.eval_seed + 1)
    weather = env.view is not None
    per_storm = np.zeros(pool.bank.worlds if pool else 1, dtype=np.int64)

    def launch(k: int, episode: int) -> None:
        start, goal, world = training_task(env, d, env.np_random)
        if pool is not None:
            world = storm_slot(pool, lanes, k, per_storm, cfg.storm_episodes)
        lanes.launch(k, start, episode, goal, world, training_level(env, d, start, env.np_random))

    started, returns, successes, stages = 0, [], [], []
    train_seconds, pending = 0.0, 0  # pending: transitions not yet paid for by a gradient step
    if saved is not None:
        try:
            agent.load_state_dict(saved["agent"])
            env.np_random.bit_generator.state = saved["env_rng"]
            lanes.load_state_dict(saved["lanes"])
            checks.load_state_dict(saved["validation"])
            torch.set_rng_state(saved["torch_rng"])
            started, pending, stages = int(saved["started"]), int(saved["pending"]), saved["stages"]
            returns, successes = list(saved["returns"]), list(saved["successes"])
            train_seconds = float(saved["train_seconds"])
            if pool is not None:
                pool.load_state_dict(saved["pool"]["pool"])
                per_storm[:] = np.asarray(saved["pool"]["per_storm"], dtype=np.int64)
        except (KeyError, TypeError, ValueError, RuntimeError, AttributeError, IndexError) as err:
            raise InvalidInputError(
                f"checkpoint {out / 'checkpoint.pt'}: refused (does not fit this run: "
                f"{type(err).__name__}: {str(err).splitlines()[0] if str(err) else ''})"
            ) from err
        if not (0 <= len(returns) <= started <= d.episodes and len(successes) == len(returns)):
            raise InvalidInputError(
                f"checkpoint {out / 'checkpoint.pt'}: refused (its episode counts are inconsistent)"
            )
    else:
        for k in range(len(lanes.t)):
            launch(k, started)
            started += 1
    log = RunLog(out, saved is not None, d.episodes, len(returns), progress)
    t0 = time.perf_counter()
    losses: list[float] = []
    try:
        while lanes.active.any():
            # Act and step every UAV in flight.
            idx = np.flatnonzero(lanes.active)
            pos = lanes.start[idx] + env.cfg.step_m * lanes.offset[idx]
            goal = lanes.goal[idx] if weather else None  # each UAV's destination and world
            world = lanes.world[idx] if pool is not None else None
            level, t = lanes.level[idx], lanes.t[idx]
            obs = agent.observe(observe(env, pos, level, t, goal, world), t)
            act = agent.act(obs, lanes.episode[idx], exploration_moves(env, level))
            r = step(env, lanes.start[idx], lanes.offset[idx], level, t, act, goal, world)
            lanes.offset[idx], lanes.level[idx], lanes.t[idx] = r["offset"], r["level"], r["t"]
            lanes.ret[idx] += r["reward"]
            # Store: each UAV's N-step window hands finished transitions to the replay.
            nobs = agent.observe(observe(env, r["position"], r["level"], r["t"], goal, world),
                                 r["t"])  # fmt: skip
            stop = learner_ends(d, r)
            learn_r = learning_reward(env, d, pos, r, goal)
            for j, k in enumerate(idx):
                for tr in lanes.windows[k].push(
                    obs[j], int(act[j]), float(learn_r[j]), nobs[j], bool(stop[j]),
                    bool(r["truncated"][j]),
                ):  # fmt: skip
                    agent.replay.add(*tr)
            # Learn: one gradient step (sample, double-Q target, loss, step) per train_every.
            pending += len(idx)
            for _ in range(pending // d.train_every):
                loss = agent.learn()
                if loss is not None:
                    losses.append(loss)
            pending %= d.train_every
            # Finished episodes: log, anneal, sync, stages, validate, relaunch the lane.
            finished_before = len(returns)
            for j in np.flatnonzero(r["terminated"] | r["truncated"]):
                k = idx[j]
                returns.append(float(lanes.ret[k]))
                successes.append(bool(r["arrived"][j]))
                n_done = len(returns)
                seconds = time.perf_counter() - t0 + train_seconds
                eps = float(agent.epsilon(lanes.episode[k]))
                row = (int(lanes.episode[k]), float(lanes.ret[k]), int(lanes.t[k]))
                log.episode(n_done, (*row, successes[-1], eps, seconds))
                agent.anneal(n_done)
                if n_done % d.target_sync_episodes == 0:
                    agent.sync()
                if n_done > d.average_from * d.episodes:
                    agent.accumulate_average()
                if n_done % stage_every == 0:
                    # Greedy rollouts from given starts draw nothing from the training rng;
                    # they and the checks fly the network the run reports.
                    with agent.reporting():
                        stages.append((n_done, greedy_rollouts(agent, ref, stage_starts)))
                if cfg.validate_every and n_done % cfg.validate_every == 0:
                    with agent.reporting():
                        success, excess = checks.check(agent, ref, n_done)
                    log.tb.add_scalar("validation/success", success, n_done)
                    log.tb.add_scalar("validation/mean_excess_cost", excess, n_done)
                if started < d.episodes:
                    launch(k, started)
                    started += 1
                else:
                    lanes.active[k] = False
            n_done = len(returns)
            if n_done == finished_before:
                continue
            if losses:
                log.tb.add_scalar("loss", float(np.mean(losses)), n_done)
                losses.clear()
            if log.bar is not None:
                log.bar.set_postfix(
                    ret=f"{np.mean(returns[-100:]):.0f}",
                    success=f"{np.mean(successes[-100:]):.2f}",
                    eps=f"{agent.epsilon(started - 1):.3f}",
                )
                log.bar.update(n_done - finished_before)
            # Checkpoint at every checkpoint_every finished episodes and at the end.
            crossed = n_done // cfg.checkpoint_every > finished_before // cfg.checkpoint_every
            # A wall-clock budget ends training at the first finished episode past it.
            spent = time.perf_counter() - t0 + train_seconds
            over_budget = bool(cfg.time_budget_s) and spent >= cfg.time_budget_s
            if crossed or n_done == d.episodes or over_budget:
                log.fh.flush()
                save_checkpoint(
                    out / "checkpoint.pt",
                    {
                        "agent": agent.state_dict(),
                        "env_rng": env.np_random.bit_generator.state,
                        "lanes": lanes.state_dict(),
                        "started": started,
                        "returns": returns,
                        "successes": successes,
                        "stages": stages,
                        "pending": pending,
                        "validation": checks.state_dict(),
                        "train_seconds": time.perf_counter() - t0 + train_seconds,
                        "torch_rng": torch.get_rng_state(),
                        "config": to_dict(cfg),
                        "pool": None
                        if pool is None
                        else {"pool": pool.state_dict(), "per_storm": per_storm.copy()},
                    },
                )
                if stop_after is not None and stop_after <= n_done < d.episodes:
                    return {}
            if over_budget:
                break
    finally:
        log.close()
    train_seconds += time.perf_counter() - t0
    if pool is not None:
        pool.close()
    return finish(cfg, agent, ref, returns, stages, train_seconds, out, checks, pool)


def finish(
    cfg: TrainConfig,
    agent: Agent,
    env: UAVNavEnv,
    returns: list[float],
    stages: list,
    train_seconds: float,
    out: Path,
    checks: Validation,
    pool: StormPool | None = None,
) -> dict[str, Any]:
    """Evaluates the run
    ([`rainuav.rl.evaluation.evaluate_run_policy()`][rainuav.rl.evaluation.evaluate_run_policy]),
    saves the evaluated network's weights to ``policy.pt`` and writes ``metrics.json`` and the
    figures."""
    metrics, rolls = evaluate_run_policy(cfg, agent, env, checks)
    policy = {k: v.detach().cpu() for k, v in agent.online.state_dict().items()}
    save_checkpoint(out / "policy.pt", {"online": policy, "config": to_dict(cfg)})
    metrics["training_seconds"] = train_seconds
    metrics["episodes"] = len(returns)
    metrics["device"] = str(agent.device)
    if pool is not None:  # where the training time went, and which storms it flew
        metrics["storms_flown"] = len(pool.flown)
        metrics["storm_map_seconds"] = pool.map_seconds
        metrics["storm_wait_seconds"] = pool.wait_seconds
        metrics["evaluated_on_storm_seed"] = VALIDATION_SEEDS[0]
    text = json.dumps(metrics, indent=2)
    write_atomic(out / "metrics.json", lambda t: t.write_text(text + "\n"))
    plot_returns(returns, out / "returns.png", checks.history)
    plot_policy(env, metrics, rolls[:40], out / "trajectories.png")
    if env.field.varies and isinstance(env, UAVNavEnv):  # (among levels: trajectories.png)
        plot_storm_flights(env, rolls[:6], out / "storm_flights.png")
    if stages:
        plot_stages(env, stages, out / "stages.png")
    return metrics
