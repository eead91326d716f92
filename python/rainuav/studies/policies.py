"""What a study's learned policies do, once its cases are finished (computed by the driver,
from the cases' saved runs, so the same on Ray as locally):

- ``trajectories.png``: every case's network (first seed) flying from the same starts over
  its own map, the exact optimum dashed beside it (the paper's Figs. of learned paths).
- The paper's case (f), for every case whose axis changes only the map (rain rate, wind,
  frequency, engine, scenario) against the base case with the same seed: this case's network
  flown on the base's map (``on_base_*``) and the base's network flown on this case's map
  (``base_policy_*``), each against the exact optimum of the map flown. With the base in rain
  and the case in clear air, ``on_base_*`` is "trained in clear air, flown in rain", to be read
  against the base row's own figures ("trained in rain"). Written to the case's
  ``transfer.json`` (atomically; a rerun skips it) and drawn in its ``transfer.png``.
"""

from __future__ import annotations

import itertools
import json
from pathlib import Path
from typing import Any

from rainuav._io import write_atomic
from rainuav.errors import InvalidInputError
from rainuav.studies.spec import Case, Study

__all__ = ["MAP_AXES", "TRANSFER_COLUMNS", "plot_learned", "read_result", "transfer"]

MAP_AXES = (
    "rain_rate_mm_h", "freq_ghz", "wind_m_s", "wind_model", "scenario", "scenario_file", "engine",
)  # fmt: skip
"""Fields that change the map and not the task: an axis that sets only these can fly a policy
on the other's map."""
TRANSFER_COLUMNS = (
    "on_base_success_rate", "on_base_mean_excess_cost",
    "base_policy_success_rate", "base_policy_mean_excess_cost",
)  # fmt: skip
FIGURE_STARTS = 8
"""Starts drawn per panel (the first of the evaluation starts, the same in every panel)."""


def _fly(
    run: Path, radio_map: Any = None, starts: int | None = None, refs: dict | None = None
) -> tuple[dict, list, Any]:
    from rainuav.rl.evaluation import evaluate_saved_run

    return evaluate_saved_run(run, radio_map=radio_map, starts=starts, references=refs)


def read_result(path: Path) -> dict[str, Any]:
    """A case's `result.json` or `transfer.json`.

    Args:
        path: The file.

    Returns:
        Its table.

    Raises:
        InvalidInputError: A file that is not a JSON table (a study folder handed over with a
            damaged file; named, with how to rerun the case).
    """
    try:
        row = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, ValueError) as err:
        raise InvalidInputError(
            f"{path}: not a readable case result ({type(err).__name__}); delete it to rerun "
            "the case"
        ) from err
    if not isinstance(row, dict):
        raise InvalidInputError(f"{path}: not a case result (a JSON table); delete it to rerun")
    return row


def _title(m: dict[str, Any]) -> str:
    excess = m.get("mean_excess_cost")
    cost = "n/a" if excess is None else f"{100 * excess:.1f}%"
    return f"success {100 * m['success_rate']:.0f}%, excess cost {cost}"


def transfer(study: Study, cases: list[Case], out: Path) -> dict[str, dict[str, Any]]:
    """Case (f) for every map-axis case (the module's docstring), computing what is missing.

    Args:
        study: The study.
        cases: Its cases.
        out: The study's folder.

    Returns:
        `{case id: its transfer figures}` for every case that has them.
    """
    from matplotlib.figure import Figure

    from rainuav.nav.figures import draw_flights, optimal_paths
    from rainuav.radio.outputs.maps import RadioMap

    if study.sweep != "one_at_a_time" or "learned" not in study.compute:
        return {}
    base = {c.seed: c for c in cases if c.axis == "base"}
    found: dict[str, dict[str, Any]] = {}
    maps: dict[Path, Any] = {}  # each map loaded once, and the optimum's flights on it
    refs: dict[Any, Any] = {}
    for c in cases:
        fields = study.axis_fields(c.axis)
        if not fields or not fields <= set(MAP_AXES) or c.seed not in base:
            continue
        folder, bfolder = out / "cases" / c.id, out / "cases" / base[c.seed].id
        done = folder / "transfer.json"
        if not done.exists():
            own_run, base_run = folder / "run", bfolder / "run"
            for r in (own_run, base_run):
                if r not in maps:
                    maps[r] = RadioMap.load(r / "radiomap.npz")
            sides = ("own", "base")
            runs = {"own": own_run, "base": base_run}
            panels = {
                (p, f): _fly(runs[p], maps[runs[f]], refs=refs)
                for p, f in itertools.product(sides, sides)
            }
            name = {"own": c.id.rsplit("_s", 1)[0], "base": base[c.seed].id.rsplit("_s", 1)[0]}
            fig = Figure(figsize=(9.0, 8.4), layout="constrained")
            axes = fig.subplots(2, 2)
            for (i, policy), (j, flown) in itertools.product(enumerate(sides), repeat=2):
                m, rolls, env = panels[(policy, flown)]
                ax = axes[i, j]
                shown = rolls[:FIGURE_STARTS]
                draw_flights(ax, env, shown, optimal_paths(env, shown))
                ax.set_title(
                    f"trained on {name[policy]}, flown on {name[flown]}\n{_title(m)}",
                    fontsize="small",
                )
                ax.set_xticks([])
                ax.set_yticks([])
            axes[0, 0].legend(loc="lower right", fontsize="x-small")
            write_atomic(
                folder / "transfer.png", lambda t, f=fig: f.savefig(t, dpi=90, format="png")
            )
            row = {
                "on_base_success_rate": panels[("own", "base")][0]["success_rate"],
                "on_base_mean_excess_cost": panels[("own", "base")][0]["mean_excess_cost"],
                "base_policy_success_rate": panels[("base", "own")][0]["success_rate"],
                "base_policy_mean_excess_cost": panels[("base", "own")][0]["mean_excess_cost"],
            }
            text = json.dumps(row, indent=2)
            write_atomic(done, lambda t, x=text: t.write_text(x + "\n"))
        found[c.id] = read_result(done)
    return found


def plot_learned(cases: list[Case], rows: dict[str, dict[str, Any]], out: Path) -> bool:
    """Writes `trajectories.png`: each case's network from the same starts over its own map.

    The first seed of each case, from the [`FIGURE_STARTS`][rainuav.studies.policies.FIGURE_STARTS]
    starts, the exact optimum dashed.

    Args:
        cases: The study's cases.
        rows: Their results by case id.
        out: The study's folder.

    Returns:
        False (and no file) when no case has a run.
    """
    import math

    from matplotlib.figure import Figure

    from rainuav.nav.figures import draw_flights, optimal_paths

    first = {}
    for c in cases:
        key = (c.axis, str(dict(c.fields).get(c.axis, "")))
        if key not in first and (out / "cases" / c.id / "run" / "policy.pt").exists():
            first[key] = c
    if not first:
        return False
    n = len(first)
    cols = min(n, 4)
    nrows = math.ceil(n / cols)
    fig = Figure(figsize=(3.5 * cols, 3.6 * nrows), layout="constrained")
    axes = fig.subplots(nrows, cols, squeeze=False)
    for ax, c in zip(axes.flat, first.values(), strict=False):
        _, rolls, env = _fly(out / "cases" / c.id / "run", starts=FIGURE_STARTS)
        draw_flights(ax, env, rolls, optimal_paths(env, rolls))
        r = rows[c.id]
        ax.set_title(f"{c.id.rsplit('_s', 1)[0]}\n{_title(r)}", fontsize="small")
        ax.set_xticks([])
        ax.set_yticks([])
    for ax in list(axes.flat)[n:]:
        ax.set_axis_off()
    axes[0, 0].legend(loc="lower right", fontsize="x-small")
    write_atomic(out / "trajectories.png", lambda t: fig.savefig(t, dpi=90, format="png"))
    return True
