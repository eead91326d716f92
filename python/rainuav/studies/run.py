"""Running a study: each case in its own folder, in parallel worker processes, resumable.

On a Ray cluster (``ray_address``) each case is a Ray task (not a Tune trial: a case is a
fixed computation, with no search or early stopping for Tune to drive, and resuming is the
folder rule below either way); the maps go to the object store once per scenario.

A case computes what the study asks (``map``, ``optimal``, ``learned``) and writes ``result.json``
last, atomically: a case folder with ``result.json`` is finished and a rerun skips it; anything else
in a folder without it is redone. Cases run in spawned worker processes (``workers``); maps are
built once per distinct scenario through the map cache
([`rainuav.radio.outputs.cache`][rainuav.radio.outputs.cache]), before the cases, so parallel cases
never build the same map twice. ``results.csv`` and ``report.md`` are written from the finished
cases in case order, so they do not depend on the number of workers; ``results.csv`` is the study
folder's last file (removed when a run starts), so a folder holding it is complete."""

from __future__ import annotations

import csv
import io
import json
import multiprocessing as mp
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any

import numpy as np

from rainuav._io import begin_folder, write_atomic
from rainuav.errors import InvalidInputError
from rainuav.studies.altitude import ALTITUDE_COLUMNS
from rainuav.studies.figures import plot_maps
from rainuav.studies.policies import TRANSFER_COLUMNS, plot_learned, read_result, transfer
from rainuav.studies.spec import Case, Study, case_scenario, train_config

__all__ = ["COLUMNS", "run_case", "run_study", "write_tables"]

COLUMNS = (
    "case", "axis", "value", "seed", "scenario", "rain_rate_mm_h", "freq_ghz", "min_db",
    "storm_seed", "storm_speed_m_s",
    "map_median_sinr_db", "map_outage_share",
    "optimal_mean_cost", "optimal_mean_signal_db", "optimal_outage_share",
    "straight_line_mean_excess_cost",
    "frozen_plan_mean_excess_cost", "replan_mean_excess_cost", "frozen_plan_outage_share",
    "replan_outage_share",
    "success_rate", "mean_excess_cost", "worst_excess_cost", "mean_signal_db", "outage_share",
    *TRANSFER_COLUMNS,
    *ALTITUDE_COLUMNS,
)  # fmt: skip
"""The columns of ``results.csv``: same study, same seeds, same file (wall times stay in each
case's ``result.json``)."""


def run_case(
    case: Case, compute: list[str], eval_starts: int, folder: str, radio_map: Any = None
) -> dict[str, Any]:
    """Computes one case into its folder, `result.json` written last.

    Args:
        case: The case.
        compute: What to compute (`map`, `optimal`, `learned`, `altitudes`).
        eval_starts: The evaluation starts.
        folder: The case's folder.
        radio_map: The case's map (or maps in time) where the caller has it (Ray passes it from the
            object store); None: built or taken from the cache.

    Returns:
        The case's row.
    """
    from rainuav.nav.figures import plot_trajectories
    from rainuav.rl.evaluation import eval_starts as starts_of
    from rainuav.rl.evaluation import reference_flights, summarise
    from rainuav.rl.loop import train
    from rainuav.world import build_source, task_of, world_from

    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    fields = dict(case.fields)
    cfg = train_config(fields, case.seed, str(out / "run"))
    cfg.eval_starts = eval_starts
    scn = case_scenario(fields, cfg)
    rm = radio_map if radio_map is not None else build_source(cfg, scn)
    world = world_from(rm, task_of(cfg))
    env = world.env()
    assert env.cfg.min_db is not None
    value = {"base": "", "grid": case.value}.get(case.axis, fields.get(case.axis, case.value))
    row: dict[str, Any] = {
        "case": case.id, "axis": case.axis, "value": value, "seed": case.seed,
        "scenario": scn.name, "rain_rate_mm_h": scn.medium.rain_rate_mm_h,
        "freq_ghz": scn.freq_hz / 1e9, "min_db": env.cfg.min_db,
    }  # fmt: skip
    if cfg.scenario == "storm" and not cfg.scenario_file:
        row["storm_seed"] = cfg.storm_seed
        speed = cfg.storm_speed_m_s
        row["storm_speed_m_s"] = "as drawn" if speed is None else speed
    if "map" in compute:
        sig = env.field.db
        row["map_median_sinr_db"] = float(np.median(sig))
        row["map_outage_share"] = float(np.mean(sig < env.cfg.min_db))
    if "optimal" in compute or "learned" in compute:
        starts = starts_of(env, eval_starts, cfg.eval_seed)
        refs = reference_flights(env, starts, cfg.replan_every)
        opt = summarise(refs["optimal"], refs["optimal"])
        line = summarise(refs["straight_line"], refs["optimal"])
        for name in ("frozen_plan", "replan"):  # where the weather moves
            if name in refs:
                base = summarise(refs[name], refs["optimal"])
                row[f"{name}_mean_excess_cost"] = base["mean_excess_cost"]
                row[f"{name}_outage_share"] = base["outage_share"]
        row["optimal_mean_cost"] = opt["mean_cost"]
        row["optimal_mean_signal_db"] = opt["mean_signal_db"]
        row["optimal_outage_share"] = opt["outage_share"]
        row["straight_line_mean_excess_cost"] = line["mean_excess_cost"]
        paths = refs["optimal"]["paths"][:20]  # planned above, not again
        plot_trajectories(env, [], out / "optimal.png", f"{case.id}: exact optimum", paths)
    if "altitudes" in compute:
        from rainuav.studies.altitude import altitude_row

        starts = starts_of(env, eval_starts, cfg.eval_seed)
        at_100 = env if scn.area.altitude_m == 100.0 else None
        row.update(altitude_row(scn, env.cfg, starts, at_100))
    if "learned" in compute:
        m = train(cfg, world, progress=False)
        for k in ("success_rate", "mean_excess_cost", "worst_excess_cost", "mean_signal_db"):
            row[k] = m[k]
        row["outage_share"] = m["outage_share"]
        row["training_seconds"] = m["training_seconds"]
    text = json.dumps(row, indent=2)
    write_atomic(out / "result.json", lambda t: t.write_text(text + "\n"))
    return row


def _maps(cases: list[Case]) -> tuple[dict[str, Any], dict[str, str]]:
    """Each distinct scenario's map (or maps in time), built once (and cached), and each
    case's key: ``({key: map or series}, {case id: key})``."""
    from rainuav.world import build_source, source_key

    maps: dict[str, Any] = {}
    of: dict[str, str] = {}
    for case in cases:
        fields = dict(case.fields)
        cfg = train_config(fields, case.seed, "unused")
        scn = case_scenario(fields, cfg)
        key = source_key(cfg, scn)
        if key not in maps:
            maps[key] = build_source(cfg, scn)
        of[case.id] = key
    return maps, of


def _ray_case(
    case: Case, compute: list[str], eval_starts: int, radio_map: Any
) -> tuple[dict[str, Any], dict[str, bytes]]:
    """A case on a Ray worker: computed in a temporary folder there, returned as its row and
    its files (so the driver's folder holds every case wherever it ran)."""
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        row = run_case(case, compute, eval_starts, tmp, radio_map)
        files = {
            str(p.relative_to(tmp)): p.read_bytes() for p in Path(tmp).rglob("*") if p.is_file()
        }
    return row, files


def _unpack(folder: Path, files: dict[str, bytes]) -> None:
    """Writes a case's files, ``result.json`` last (each atomically)."""
    for name in sorted(files, key=lambda n: n == "result.json"):
        target = folder / name
        target.parent.mkdir(parents=True, exist_ok=True)
        write_atomic(target, lambda t, b=files[name]: t.write_bytes(b))


def _run_ray(study: Study, todo: list[Case], out: Path, ray_address: str, bar: Any) -> None:
    """Each case as a Ray task (1 CPU) on the cluster at ``ray_address`` (``"auto"``: the
    one this machine belongs to; ``"local"``: a local instance with the cores here); each
    distinct map goes to the object store once and is shared by its cases."""
    try:
        import ray
    except ImportError as err:
        raise InvalidInputError(
            "--ray needs Ray: pip install '.[ray]' from the rainuav clone"
        ) from err
    if not ray.is_initialized():
        ray.init(address=None if ray_address == "local" else ray_address)
    maps, of = _maps(todo)
    refs = {k: ray.put(v) for k, v in maps.items()}
    task = ray.remote(num_cpus=1)(_ray_case)
    pending = {task.remote(c, study.compute, study.eval_starts, refs[of[c.id]]): c for c in todo}
    while pending:
        done, _ = ray.wait(list(pending), num_returns=1)
        case = pending.pop(done[0])
        _, files = ray.get(done[0])
        _unpack(out / "cases" / case.id, files)
        if bar is not None:
            bar.update(1)


def _leave_ctrl_c_to_the_driver() -> None:
    """Worker processes ignore SIGINT: Ctrl-C reaches the whole process group, and only the
    driver answers it (one line, then it stops the workers), so no worker prints a
    traceback."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _stop(pool: ProcessPoolExecutor) -> None:
    """Cancels the cases not started and ends the workers running cases (their folders hold
    no ``result.json``, so a rerun computes them again)."""
    workers = list(getattr(pool, "_processes", {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for p in workers:
        p.terminate()
    for p in workers:
        p.join(timeout=10)


def run_study(
    study: Study,
    out: Path,
    workers: int = 1,
    progress: bool = True,
    ray_address: str | None = None,
) -> list[dict[str, Any]]:
    """Runs every unfinished case of a study and writes its tables.

    Each case runs into `out/cases/<case id>` (a case already finished is read back, so an
    interrupted study resumes); then `results.csv` and `report.md` are written.

    Args:
        study: The study ([`load_study()`][rainuav.studies.spec.load_study]).
        out: The study's folder.
        workers: Local processes running cases at once.
        progress: A line on standard error per case.
        ray_address: Run the cases as Ray tasks: "local" (Ray started here), "auto" (the
            cluster already running) or a cluster's address; None: local processes.

    Returns:
        One row of results a case, in case order.
    """
    cases = study.cases()
    begin_folder(out, "results.csv")  # written again, last, once every case is done
    todo = [c for c in cases if not (out / "cases" / c.id / "result.json").exists()]
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=len(cases), initial=len(cases) - len(todo), desc="study", unit="case")
    args = [(c, study.compute, study.eval_starts, str(out / "cases" / c.id)) for c in todo]
    try:
        if ray_address is not None:
            _run_ray(study, todo, out, ray_address, bar)
        elif workers <= 1 or len(todo) <= 1:
            _maps(todo)  # built once here; the cases find them in the cache
            for a in args:
                run_case(*a)
                if bar is not None:
                    bar.update(1)
        else:
            _maps(todo)
            ctx = mp.get_context("spawn")
            pool = ProcessPoolExecutor(
                max_workers=workers, mp_context=ctx, initializer=_leave_ctrl_c_to_the_driver
            )
            try:
                for fut in as_completed([pool.submit(run_case, *a) for a in args]):
                    fut.result()
                    if bar is not None:
                        bar.update(1)
            except BaseException:
                _stop(pool)  # Ctrl-C or a failed case: the cases in flight stop now
                raise
            pool.shutdown()
    finally:
        if bar is not None:
            bar.close()
    rows = [read_result(out / "cases" / c.id / "result.json") for c in cases]
    if "map" in study.compute:
        plot_maps(cases, out / "maps.png", "sinr")
        plot_maps(cases, out / "rss.png", "rss")
    if "learned" in study.compute:
        moved = transfer(study, cases, out)
        for r in rows:
            r.update(moved.get(r["case"], {}))
        plot_learned(cases, {r["case"]: r for r in rows}, out)
    write_tables(study, rows, out)
    return rows


def _fmt(v: Any) -> str:
    if v is None or v == "":
        return ""
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def write_tables(study: Study, rows: list[dict[str, Any]], out: Path) -> None:
    """Writes `results.csv` (one row a case) and `report.md`.

    The report has the table, then per axis the change of each figure against the base case, mean
    and spread over seeds.

    Args:
        study: The study.
        rows: The cases' rows, in case order.
        out: The study's folder.
    """
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(COLUMNS)
    for r in rows:
        w.writerow([_fmt(r.get(c)) for c in COLUMNS])
    shown = [c for c in COLUMNS if any(r.get(c) not in (None, "") for r in rows)]
    lines = [f"# Study `{study.name}`", "", f"{len(rows)} cases ({study.sweep}).", ""]
    lines += ["| " + " | ".join(shown) + " |", "|" + "---|" * len(shown)]
    lines += ["| " + " | ".join(_fmt(r.get(c)) for c in shown) + " |" for r in rows]
    base = [r for r in rows if r["axis"] == "base"]
    text = ("outage_by_altitude", "cost_by_altitude")  # several numbers in one cell
    figures = [c for c in shown if c in COLUMNS[10:] and c not in (*TRANSFER_COLUMNS, *text)]
    if base:
        lines += ["", "## Change against the base case, seed by seed (mean, min..max)", ""]
        lines += [
            "| axis | value | " + " | ".join(figures) + " |",
            "|" + "---|" * (2 + len(figures)),
        ]
        ref = {r["seed"]: r for r in base}
        groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
        for r in rows:
            if r["axis"] != "base":
                groups.setdefault((r["axis"], _fmt(r["value"])), []).append(r)
        for (axis, value), rs in groups.items():
            cells = []
            for c in figures:
                d = [
                    r[c] - ref[r["seed"]][c]
                    for r in rs
                    if r.get(c) is not None and ref.get(r["seed"], {}).get(c) is not None
                ]
                cells.append("" if not d else f"{np.mean(d):+.4g} ({min(d):+.3g}..{max(d):+.3g})")
            lines.append(f"| {axis} | {value} | " + " | ".join(cells) + " |")
    if (out / "maps.png").exists():
        lines += ["", "## SINR maps and their change against the base", "", "![maps](maps.png)"]
    if (out / "rss.png").exists():
        lines += ["", "## Received power (best cell) and its change against the base", ""]
        lines += ["![rss](rss.png)"]
    if (out / "trajectories.png").exists():
        lines += ["", "## Learned trajectories (network alone, the same starts in every panel)", ""]
        lines += ["![trajectories](trajectories.png)"]
    moved = [r for r in rows if r.get("on_base_success_rate") is not None]
    if moved:
        ref = {r["seed"]: r for r in base}
        lines += ["", "## A policy flown on the other map (the paper's case f)", ""]
        lines += [
            "Success and mean excess cost over the exact optimum of the map flown. "
            "Read each row's 'trained here, flown on base' against 'base's own', and "
            "'base's policy flown here' against 'trained here, flown here'.",
            "",
            "| case | trained here, flown here | trained here, flown on base | "
            "base's policy, flown here | base's own |",
            "|---|---|---|---|---|",
        ]

        def pair(s: Any, e: Any) -> str:
            return f"{100 * s:.1f}% / " + ("n/a" if e is None else f"{100 * e:.1f}%")

        for r in moved:
            b = ref[r["seed"]]
            lines.append(
                f"| {r['case']} | {pair(r['success_rate'], r['mean_excess_cost'])} | "
                f"{pair(r['on_base_success_rate'], r['on_base_mean_excess_cost'])} | "
                f"{pair(r['base_policy_success_rate'], r['base_policy_mean_excess_cost'])} | "
                f"{pair(b['success_rate'], b['mean_excess_cost'])} |"
            )
        lines += [""] + [f"![{r['case']}](cases/{r['case']}/transfer.png)" for r in moved]
    figs = sorted((out / "cases").glob("*/optimal.png"))
    if figs:
        lines += ["", "## Exact optimum per case", ""]
        lines += [f"![{p.parent.name}](cases/{p.parent.name}/optimal.png)" for p in figs]
    text = "\n".join(lines) + "\n"
    write_atomic(out / "report.md", lambda t: t.write_text(text))
    # Last: a study folder holding results.csv is complete.
    write_atomic(out / "results.csv", lambda t: t.write_text(buf.getvalue()))
