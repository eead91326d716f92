"""Studies end to end through the CLI: outputs (case f and the trajectory figures among them),
resume after a real kill, the same results with one or two workers
and on Ray, and bad study files refused before any work."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest
from rainuav.errors import InvalidInputError
from rainuav.studies import load_study
from rainuav.study import main

TINY = """
name = "tiny"
seeds = [0]
compute = ["map", "optimal", "learned"]
eval_starts = 4

[base]
scenario = "uma"
engine = "ray"
"dqn.episodes" = 3
"dqn.lanes" = 2
validate_every = 0
checkpoint_every = 2

[axes]
rain_rate_mm_h = [50.0]
"""


def _write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "study.toml"
    p.write_text(text)
    return p


@pytest.fixture(scope="module")
def two_workers(
    tmp_path_factory: pytest.TempPathFactory, session_cache: Path
) -> tuple[Path, list, str]:
    """The tiny study run once from scratch on two local worker processes (its folder, rows
    and results.csv): what every other way of running it (one process, resumed, killed, on
    Ray) must reproduce."""
    from rainuav.studies import run_study

    tmp = tmp_path_factory.mktemp("two_workers")
    out = tmp / "a"
    with pytest.MonkeyPatch.context() as mp:  # the session's map cache, as in every test
        mp.setenv("RAINUAV_CACHE_DIR", str(session_cache))
        rows = run_study(load_study(_write(tmp, TINY)), out, workers=2, progress=False)
    return out, rows, (out / "results.csv").read_text()


@pytest.mark.slow
def test_tiny_study_end_to_end_does_not_depend_on_workers(
    tmp_path: Path, two_workers: tuple[Path, list, str]
) -> None:
    # Two cases (the base in clear air, 50 mm/h), tiny trainings on the ray engine's map, run
    # on two workers (the fixture).
    out, _, csv = two_workers
    cases = sorted(p.name for p in (out / "cases").iterdir())
    assert cases == ["000_base_s0", "001_rain_rate_mm_h=50_s0"]
    for c in cases:
        for name in ("result.json", "optimal.png", "run/metrics.json", "run/policy.pt"):
            assert (out / "cases" / c / name).exists(), (c, name)
    lines = csv.splitlines()
    assert len(lines) == 3 and lines[0].startswith("case,axis,value,seed")
    report = (out / "report.md").read_text()
    assert "rain_rate_mm_h | 50" in report and "optimal.png" in report and "maps.png" in report
    for png in (
        "maps.png",
        "rss.png",
        "trajectories.png",
        "cases/001_rain_rate_mm_h=50_s0/transfer.png",
    ):
        assert (out / png).read_bytes()[:4] == b"\x89PNG", png
    # Case (f): the rain case's network flown on the clear base map and the base's network
    # flown in the rain, each a success rate in [0, 1], in the table and in the report.
    row = dict(zip(lines[0].split(","), lines[2].split(","), strict=True))
    for k in ("on_base_success_rate", "base_policy_success_rate"):
        assert 0.0 <= float(row[k]) <= 1.0, (k, row[k])
    base_row = dict(zip(lines[0].split(","), lines[1].split(","), strict=True))
    assert base_row["on_base_success_rate"] == ""  # the base is not flown against itself
    assert "the paper's case f" in report and "trajectories.png" in report
    # A case whose result was deleted is run again, alone, in one process through the command
    # line, to the same results. (The whole study in one process after a real kill: the next
    # test.)
    study = _write(tmp_path, TINY)
    first = (out / "cases" / cases[0] / "result.json").stat().st_mtime_ns
    (out / "cases" / cases[1] / "result.json").unlink()
    assert main([str(study), "--out", str(out), "--workers", "1"]) == 0
    assert (out / "cases" / cases[0] / "result.json").stat().st_mtime_ns == first
    assert (out / "cases" / cases[1] / "result.json").exists()
    assert (out / "results.csv").read_text() == csv


@pytest.mark.slow
def test_a_study_killed_mid_case_reruns_to_the_same_results(
    tmp_path: Path, two_workers: tuple[Path, list, str]
) -> None:
    # A real kill (SIGKILL, no clean-up) while the second case trains, in one process; the
    # rerun redoes that case only and ends with the results.csv of the uninterrupted run on
    # two workers.
    study = _write(tmp_path, TINY)
    out = tmp_path / "killed"
    cmd = [sys.executable, "-m", "rainuav.study", str(study), "--out", str(out), "--workers", "1"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    second = out / "cases" / "001_rain_rate_mm_h=50_s0"
    deadline = time.monotonic() + 240
    try:
        while not (second / "run").exists():  # the second case has started training
            assert proc.poll() is None, "the study ended before it could be killed"
            assert time.monotonic() < deadline, "the second case never started"
            time.sleep(0.01)
    finally:
        proc.kill()
        proc.wait(timeout=60)
    assert not (second / "result.json").exists()  # killed mid-case, not after it
    first = (out / "cases" / "000_base_s0" / "result.json").stat().st_mtime_ns
    assert main([str(study), "--out", str(out), "--workers", "1"]) == 0
    assert (out / "cases" / "000_base_s0" / "result.json").stat().st_mtime_ns == first
    assert (out / "results.csv").read_text() == two_workers[2]


@pytest.mark.parametrize(
    ("change", "needle"),
    [
        (("[axes]", "[axes]\nbogus = [1]"), "bogus"),
        (("rain_rate_mm_h = [50.0]", "rain_rate_mm_h = []"), "rain_rate"),
        (("rain_rate_mm_h = [50.0]", "rain_rate_mm_h = [50.0, 900.0]"), "rain_rate"),
        (('scenario = "uma"', 'scenario = "nowhere"'), "scenario"),
        (("eval_starts = 4", "eval_starts = 0"), "eval_starts"),
        (('name = "tiny"', 'name = "tiny"\nextra = 1'), "extra"),
        (('"dqn.episodes" = 3', '"dqn.episodes" = -3'), "episodes"),
        (("rain_rate_mm_h = [50.0]", "rain_rate = [{ bogus = 1.0 }]"), "bogus"),
        (("rain_rate_mm_h = [50.0]", "rain_rate = [50.0, { wind_m_s = 2.0 }]"), "rain_rate"),
        (
            ("rain_rate_mm_h = [50.0]", 'w = [{ wind_m_s = 2.0, wind_model = "gale" }]'),
            "wind_model",
        ),
    ],
)
def test_bad_study_files_are_refused_before_any_work(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], change: tuple[str, str], needle: str
) -> None:
    study = _write(tmp_path, TINY.replace(*change))
    out = tmp_path / "out"
    assert main([str(study), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and needle in err, err
    assert not out.exists()


def test_built_in_studies_load_and_name_their_cases() -> None:
    paper = load_study("paper-sweeps")
    ids = [c.id for c in paper.cases()]
    assert ids[0] == "000_base_s0" and len(ids) == len(set(ids))
    axes = {c.axis for c in paper.cases()}
    assert axes == {"base", "rain_rate_mm_h", "mu", "wind_m_s", "paper_wind"}
    mmwave = {c.axis for c in load_study("mmwave").cases()}
    assert mmwave == {"base", "rain_rate_mm_h", "freq_ghz", "scenario"}
    # A compound axis sets several fields at once: the paper's wind factor at 2 and 5 m/s.
    paper_wind = [c for c in paper.cases() if c.axis == "paper_wind"]
    assert [c.id for c in paper_wind] == ["008_paper_wind=2-paper_s0", "009_paper_wind=5-paper_s0"]
    assert [dict(c.fields)["wind_model"] for c in paper_wind] == ["paper", "paper"]
    assert paper.axis_fields("paper_wind") == {"wind_m_s", "wind_model"}
    quick = paper.with_quick()
    assert dict(quick.cases()[0].fields)["dqn.episodes"] == 300
    with pytest.raises(InvalidInputError, match="study file"):
        load_study("no_such_study.toml")


@pytest.mark.slow
def test_ray_gives_the_local_results(tmp_path: Path, two_workers: tuple[Path, list, str]) -> None:
    # The same tiny study as Ray tasks on a local instance (2 CPUs): the same rows and
    # results.csv as on local workers, and every case's files in the driver's folder.
    import ray
    from rainuav.studies import run_study

    study = load_study(_write(tmp_path, TINY))
    local = two_workers[1]
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        remote = run_study(study, tmp_path / "ray", progress=False, ray_address="local")
    finally:
        ray.shutdown()

    def timeless(rows: list) -> list:
        return [{k: v for k, v in r.items() if k != "training_seconds"} for r in rows]

    assert timeless(remote) == timeless(local)
    assert (tmp_path / "ray" / "results.csv").read_text() == two_workers[2]
    for c in study.cases():
        for name in ("result.json", "optimal.png", "run/policy.pt"):
            assert (tmp_path / "ray" / "cases" / c.id / name).exists(), (c.id, name)


@pytest.mark.slow
def test_the_storms_study_grids_speeds_and_storms_and_reports_the_baselines(tmp_path) -> None:
    storms = load_study("storms")
    cases = storms.cases()
    speeds = sorted({dict(c.fields)["storm_speed_m_s"] for c in cases})
    assert cases[1].id == "001_grid=0,1_s0"  # speed 0, storm 1
    assert speeds == [0.0, 5.0, 10.0, 20.0] and len(cases) == 8
    assert storms.with_quick().eval_starts == 20 and storms.eval_starts == 100
    # A small moving-weather case: the frozen take-off plan and re-planning are reported
    # beside the exact space-time optimum, never below it.
    from rainuav.studies.run import run_case
    from rainuav.studies.spec import Case

    fields = {"scenario": "storm", "storm_seed": 0, "storm_speed_m_s": 20.0, "engine": "ray",
              "slice_s": 30.0}  # fmt: skip
    case = Case(0, "grid", tuple(sorted(fields.items())), 0)
    row = run_case(case, ["map", "optimal"], 5, str(tmp_path / "c"))
    assert row["storm_seed"] == 0 and row["storm_speed_m_s"] == 20.0
    for name in ("frozen_plan", "replan", "straight_line"):
        assert row[f"{name}_mean_excess_cost"] >= -1e-9, name
    assert row["replan_outage_share"] is not None
