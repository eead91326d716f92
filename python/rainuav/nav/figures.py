"""Figures of flights over an environment's map: a policy's flights beside the exact optimum's,
flights at stages of training, flights through a signal that changes in time. Built with
matplotlib's ``Figure`` (no pyplot, no backend switch), so plotting sets no process-wide
state; a flight is its record (``path``, and among levels ``ticks`` and ``levels``), whoever
flew it."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from rainuav._io import write_atomic
from rainuav.nav.env import UAVNavEnv

__all__ = [
    "draw_flights",
    "map_image",
    "optimal_paths",
    "plot_policy",
    "plot_stages",
    "plot_storm_flights",
    "plot_trajectories",
]


def map_image(ax: Any, env: UAVNavEnv) -> Any:
    """The task's signal map drawn on an Axes, its colour scale centred on the outage threshold.

    Where it changes in time, at take-off; among levels, the lowest level's.

    Args:
        ax: The matplotlib Axes.
        env: The environment.

    Returns:
        The image (for a colour bar).
    """
    x0, x1, y0, y1 = env.field.extent
    lo = float(env.cfg.min_db if env.cfg.min_db is not None else 0.0)
    field = env.field.level(0)
    return ax.imshow(
        field.frozen(0.0).db,
        origin="lower",
        extent=(x0, x1, y0, y1),
        cmap="RdYlGn",
        vmin=lo - 15.0,
        vmax=lo + 15.0,
    )


def draw_flights(ax: Any, env: UAVNavEnv, rolls: list, optimal: Sequence[Any] = ()) -> Any:
    """Flights over the map, the paper's way.

    The policy's paths black, starts as red crosses, the destination as a blue triangle.

    Args:
        ax: The matplotlib Axes.
        env: The environment.
        rolls: The flights ([`greedy_rollouts()`][rainuav.rl.collect.greedy_rollouts]).
        optimal: The exact planner's paths from the same starts (dashed blue).

    Returns:
        The map's image (for a colour bar).
    """
    x0, x1, y0, y1 = env.field.extent
    im = map_image(ax, env)
    for k, p in enumerate(optimal):
        ax.plot(p[:, 0], p[:, 1], "--", color="tab:blue", lw=0.9, alpha=0.8,
                label="exact optimum" if k == 0 else None)  # fmt: skip
        ax.plot(p[0, 0], p[0, 1], "rx", ms=6)
    for k, r in enumerate(rolls):
        ax.plot(r["path"][:, 0], r["path"][:, 1], "-", color="k", lw=0.8, alpha=0.7,
                label="policy" if k == 0 else None)  # fmt: skip
        ax.plot(r["path"][0, 0], r["path"][0, 1], "rx", ms=6)
    ax.plot(*env.cfg.goal_m, "b^", ms=10, label="destination")
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    return im


def plot_trajectories(
    env: UAVNavEnv,
    rolls: list,
    path: Path,
    title: str,
    optimal: Sequence[Any] = (),
    heights: Sequence[Any] = (),
) -> None:
    """Writes the flights over the map with a colour bar, a legend and axes.

    Among levels, beside it each flight's altitude against time.

    Args:
        env: The environment.
        rolls: The flights.
        path: The PNG.
        title: The figure's title.
        optimal: The exact planner's paths from the same starts.
        heights: Among levels, the optimum's `(ticks, levels)` a flight (dashed blue).
    """
    from matplotlib.figure import Figure

    levels = env.altitudes_m is not None
    fig = Figure(figsize=(11.4 if levels else 6.4, 5.4))
    ax, *side = fig.subplots(1, 2 if levels else 1, squeeze=False)[0]
    im = draw_flights(ax, env, rolls, optimal)
    if levels:
        alts, move_s = env.field.altitudes_m, env.cfg.move_s
        for k, (ticks, lv) in enumerate(heights):
            side[0].plot(ticks * move_s, alts[lv], "--", color="tab:blue", lw=0.9, alpha=0.8,
                         label="exact optimum" if k == 0 else None)  # fmt: skip
        for k, r in enumerate(rolls):
            side[0].plot(r["ticks"] * move_s, alts[r["levels"]], "-", color="k", lw=0.8,
                         alpha=0.7, label="policy" if k == 0 else None)  # fmt: skip
        side[0].set_xlabel("time [s]")
        side[0].set_ylabel("altitude [m]")
        side[0].set_yticks(alts)
        side[0].legend(loc="upper right", fontsize="small")
        when = ", at take-off" if env.field.varies else ""
        side[0].set_title(f"heights flown (map: the lowest level, {alts[0]:g} m{when})")
    label = f"{env.cfg.signal.upper()} [dB] (outage below {env.cfg.min_db:g})"
    fig.colorbar(im, ax=ax, label=label)
    ax.legend(loc="lower right", fontsize="small")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title)
    fig.tight_layout()
    write_atomic(path, lambda t: fig.savefig(t, dpi=110, format="png"))


def optimal_paths(env: UAVNavEnv, rolls: list) -> list:
    """The exact planner's paths from the starts of some flights (to draw beside them).

    Args:
        env: The environment.
        rolls: The flights.

    Returns:
        The paths.
    """
    return [p.path_m for p in optimal_plans(env, rolls)]


def optimal_plans(env: UAVNavEnv, rolls: list) -> list:
    """The exact planner's plans from the starts of some flights.

    Args:
        env: The environment.
        rolls: The flights.

    Returns:
        The [`Plan`][rainuav.nav.planner.Plan]s.
    """
    from rainuav.nav import planner

    starts = np.array([r["path"][0] for r in rolls]).reshape(-1, 2)
    if env.altitudes_m is not None:
        return planner.optimal_among_levels(env, starts)  # type: ignore[arg-type]
    return planner.optimal_many(env, starts)


def plot_policy(env: UAVNavEnv, metrics: dict[str, Any], rolls: list, path: Path) -> None:
    """Writes the network's flights beside the exact optimum's from the same starts.

    Among levels, with the heights flown.

    Args:
        env: The environment.
        metrics: The run's metrics.
        rolls: The network's flights.
        path: The PNG.
    """
    plans = optimal_plans(env, rolls)
    heights = [(p.ticks, p.levels) for p in plans] if env.altitudes_m is not None else []  # type: ignore[union-attr]
    excess = metrics.get("mean_excess_cost")
    cost = "n/a" if excess is None else f"{100 * excess:.1f}%"
    title = f"network alone: success {100 * metrics['success_rate']:.0f}%, excess cost {cost}"
    plot_trajectories(env, rolls, path, title, [p.path_m for p in plans], heights)


def plot_stages(env: UAVNavEnv, stages: list[tuple[int, list]], path: Path) -> None:
    """Writes the greedy network's flights at stages of training, one panel a stage.

    Args:
        env: The environment.
        stages: `(episode, flights)` of each stage.
        path: The PNG.
    """
    from matplotlib.figure import Figure

    n = max(1, len(stages))
    # Constrained layout keeps the titles inside the figure (tight_layout cut them off the
    # square image panels).
    fig = Figure(figsize=(3.6 * n, 3.9), layout="constrained")
    axs = fig.subplots(1, n, squeeze=False)
    for ax, (ep, rolls) in zip(axs[0], stages, strict=False):
        map_image(ax, env)
        for r in rolls:
            ax.plot(r["path"][:, 0], r["path"][:, 1], "k-", lw=0.8)
            ax.plot(r["path"][0, 0], r["path"][0, 1], "rx")
        ax.plot(*env.cfg.goal_m, "b^")
        ax.set_title(f"after {ep} episodes")
        ax.set_xlabel("east [m]")
    axs[0][0].set_ylabel("north [m]")
    write_atomic(path, lambda t: fig.savefig(t, dpi=100, format="png"))


def plot_storm_flights(env: UAVNavEnv, rolls: list, path: Path, panels: int = 3) -> None:
    """Writes flights through a signal that changes in time, one panel an instant.

    From take-off to two thirds of the longest flight, each panel over the SINR of that instant,
    with the network's flights (black), the frozen take-off plan's (orange) and the exact space-time
    optimum's (dashed blue) from the same starts, drawn up to that instant (a dot: where the UAV
    is).

    Args:
        env: The environment.
        rolls: The network's flights.
        path: The PNG.
        panels: The instants drawn.
    """
    from matplotlib.figure import Figure

    from rainuav.nav import baselines, planner

    starts = np.array([r["path"][0] for r in rolls]).reshape(-1, 2)
    flights = {
        "network alone": ([r["path"] for r in rolls], "-"),
        "frozen take-off plan": ([p.path_m for p in baselines.frozen_plans(env, starts)], "-"),
        "exact optimum": ([p.path_m for p in planner.optimal_many(env, starts)], "--"),
    }
    colours = {"network alone": "k", "frozen take-off plan": "tab:orange", "exact optimum": "b"}
    longest = max(len(p) for ps, _ in flights.values() for p in ps) - 1
    moves = [round(k * 2 * longest / (3 * max(panels - 1, 1))) for k in range(panels)]
    fig = Figure(figsize=(4.2 * panels, 4.4), layout="constrained")
    axs = fig.subplots(1, panels, squeeze=False)[0]
    x0, x1, y0, y1 = env.field.extent
    lo = float(env.cfg.min_db if env.cfg.min_db is not None else 0.0)
    for ax, m in zip(axs, moves, strict=True):
        t_s = float(env.stepper.time_s(np.array([m]))[0])
        im = ax.imshow(
            env.field.frozen(t_s).db, origin="lower", extent=(x0, x1, y0, y1),
            cmap="RdYlGn", vmin=lo - 15.0, vmax=lo + 15.0,
        )  # fmt: skip
        for name, (paths, style) in flights.items():
            for i, p in enumerate(paths):
                now = p[: m + 1]
                ax.plot(p[:, 0], p[:, 1], style, color=colours[name], lw=0.6, alpha=0.25)
                ax.plot(now[:, 0], now[:, 1], style, color=colours[name], lw=1.2,
                        label=name if i == 0 else None)  # fmt: skip
                ax.plot(*now[-1], "o", color=colours[name], ms=3)
        ax.plot(*env.cfg.goal_m, "b^", label="destination" if m == moves[0] else None)
        ax.set_title(f"t = {t_s:.0f} s")
        ax.set_xlabel("east [m]")
    axs[0].set_ylabel("north [m]")
    axs[0].legend(loc="lower right", fontsize="x-small")
    fig.colorbar(im, ax=list(axs), label=f"{env.cfg.signal.upper()} [dB]", shrink=0.8)
    write_atomic(path, lambda t: fig.savefig(t, dpi=100, format="png"))
