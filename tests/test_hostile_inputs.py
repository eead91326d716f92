"""The corpus of bad and hostile inputs: what users hand each other (run folders,
study folders, cached maps, scenario files) and what they type (CLI flags, env calls), each
with the answer it must get.

Every probe is one of:
- **refused**: one line naming the file or field (CLIs: ``error: ...`` and exit 2;
  the Python API: :class:`rainuav.InvalidInputError`), with nothing run, written or lost;
- **accepted**: rightly taken (a moved run folder resumes, a cache that cannot be written
  is a warning and the map is still returned and written).

A probe that ends in a traceback, a hang (pytest-timeout) or a wrong result fails its test.
The last test prints the totals: inputs tried, clean refusals, rightly accepted, and zero
tracebacks, hangs and silent wrong results. The slow probes (a real Ctrl-C during a map build
and during a study) are in ``benches/hostile_corpus.py``.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import os
import re
import shutil
import subprocess
import sys
from collections import Counter
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
import torch
from rainuav import InvalidInputError, evaluate, radiomap, study, train, validate
from rainuav._io import FolderLock, write_atomic
from rainuav.errors import CacheWarning
from rainuav.nav import UAVNavEnv
from rainuav.nav.vector import UAVNavVectorEnv
from rainuav.radio import RadioMap, build_radio_map
from rainuav.radio.outputs.cache import map_path
from rainuav.radio.scene.scenario import Area, Cell, Scenario, Site
from rainuav.rl import checkpoint
from rainuav.rl.loop import train as train_run
from rainuav.world import in_world, saved_world
from test_agent_train import plumbing_cfg, small_cfg, synthetic_map

TALLY: Counter[str] = Counter()
"""Outcome of every probe that ran: 'refused' or 'accepted' (anything else fails its test)."""


def refused(probe: str, rc: int, err: str, *needles: str) -> None:
    """A CLI's clean refusal: exit 2, one line ``error: ...`` holding every needle, last on
    stderr (progress bars may come before it), and no traceback."""
    lines = err.replace("\r", "\n").strip().splitlines()
    assert rc == 2, (probe, rc, err)
    assert "Traceback" not in err, (probe, err)
    errors = [line for line in lines if line.startswith("error: ")]
    assert len(errors) == 1 and lines[-1] == errors[0], (probe, err)
    for n in needles:
        assert n in errors[0], (probe, n, errors[0])
    TALLY["refused"] += 1


def api_refused(probe: str, call: Any, *needles: str) -> str:
    """The API's clean refusal: InvalidInputError, a one-line message holding every needle."""
    with pytest.raises(InvalidInputError) as info:
        call()
    msg = str(info.value)
    assert "\n" not in msg, (probe, msg)
    for n in needles:
        assert n in msg, (probe, n, msg)
    TALLY["refused"] += 1
    return msg


def accepted(probe: str) -> None:
    TALLY["accepted"] += 1


def run_cli(mod: Any, argv: list[str], capsys: pytest.CaptureFixture) -> tuple[int, str]:
    capsys.readouterr()
    rc = mod.main([str(a) for a in argv])
    return rc, capsys.readouterr().err


class Hostile:
    """Unpickling this creates a file: the proof that a loader ran code."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self) -> tuple[Any, ...]:
        return (open, (str(self.marker), "w"))


def tiny_scenario(engine: str = "ray") -> Scenario:
    return Scenario(
        name="tiny",
        area=Area(x_min_m=0, x_max_m=400, y_min_m=0, y_max_m=400, resolution_m=20),
        sites=[Site(x_m=100.0, y_m=100.0, cells=[Cell(azimuth_deg=45.0, beamwidth_deg=6.0)])],
        engine=engine,
    )


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A finished tiny training run (20 episodes on the synthetic 400 m map)."""
    out = tmp_path_factory.mktemp("run") / "run"
    torch.set_num_threads(1)
    train_run(*in_world(plumbing_cfg(out, 20), synthetic_map()), progress=False)
    return out


@pytest.fixture
def run_copy(run_folder: Path, tmp_path: Path) -> Path:
    """A copy of the run folder, to spoil; its config names its new place."""
    dst = tmp_path / "handed_over"
    shutil.copytree(run_folder, dst)
    cfg = (dst / "config.toml").read_text().replace(str(run_folder), str(dst))
    (dst / "config.toml").write_text(cfg)
    return dst


# -- 1. A run folder never runs code ---------------------------------------------------------
def _plant_hostile(run: Path, marker: Path) -> None:
    state = {"agent": Hostile(marker), "returns": [], "train_seconds": 0.0}
    torch.save(state, run / "checkpoint.pt")


@pytest.mark.slow
def test_hostile_checkpoint_is_refused_by_evaluate(run_copy: Path, tmp_path: Path, capsys) -> None:
    marker = tmp_path / "PWNED"
    _plant_hostile(run_copy, marker)
    rc, err = run_cli(evaluate, [run_copy, "--out", tmp_path / "ev"], capsys)
    refused("evaluate hostile", rc, err, "checkpoint.pt", "could run code")
    assert not marker.exists()


def test_hostile_checkpoint_is_refused_by_resume(run_copy: Path, tmp_path: Path, capsys) -> None:
    marker = tmp_path / "PWNED"
    _plant_hostile(run_copy, marker)
    rc, err = run_cli(train, ["--config", run_copy / "config.toml", "--resume"], capsys)
    refused("resume hostile", rc, err, "checkpoint.pt", "could run code")
    assert not marker.exists()


def test_hostile_checkpoint_is_refused_by_a_study(run_folder: Path, tmp_path: Path, capsys) -> None:
    # A study folder handed over with its cases finished: the driver only computes the
    # transfer figures, which fly each case's saved network.
    spec = tmp_path / "s.toml"
    spec.write_text(
        'name = "t"\nseeds = [0]\ncompute = ["learned"]\neval_starts = 5\n'
        '[base]\nscenario = "paper"\nrain_rate = 25.0\n[axes]\nrain_rate = [0.0]\n'
    )
    out, marker = tmp_path / "study", tmp_path / "PWNED"
    for case in study_cases(spec):
        folder = out / "cases" / case
        shutil.copytree(run_folder, folder / "run")
        (folder / "result.json").write_text(json.dumps({"case": case, "success_rate": 1.0}))
    _plant_hostile(out / "cases" / "001_rain_rate=0_s0" / "run", marker)
    rc, err = run_cli(study, [spec, "--out", out, "--workers", "1"], capsys)
    refused("study hostile", rc, err, "checkpoint.pt", "could run code")
    assert not marker.exists()


def study_cases(spec: Path) -> list[str]:
    from rainuav.studies import load_study

    return [c.id for c in load_study(spec).cases()]


@pytest.mark.slow
def test_python_dash_m_evaluate_refuses_a_hostile_checkpoint(run_copy, tmp_path) -> None:
    marker = tmp_path / "PWNED"
    _plant_hostile(run_copy, marker)
    proc = subprocess.run(
        [sys.executable, "-m", "rainuav.evaluate", str(run_copy), "--out", str(tmp_path / "e")],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    refused("python -m evaluate hostile", proc.returncode, proc.stderr, "could run code")
    assert "Traceback" not in proc.stderr and not marker.exists()


def test_no_torch_load_without_weights_only() -> None:
    # Every torch.load in the package reads with weights_only=True (rainuav.rl.checkpoint).
    import re

    root = Path(__file__).parents[1]
    call = re.compile(r"^[^#\"']*\btorch\.load\(")  # a call, not a comment or a string
    calls = 0
    for folder in ("python", "benches", "experiments", "tests"):
        for f in (root / folder).rglob("*.py"):
            for line in f.read_text().splitlines():
                if call.search(line):
                    calls += 1
                    assert "weights_only=True" in line, (f, line)
    assert calls >= 2  # rainuav.rl.checkpoint.load and the tests' policy.pt reads


# -- 2. Tracebacks that are now one line -----------------------------------------------------
@pytest.mark.parametrize(
    ("kind", "content"),
    [("empty", b""), ("truncated", None), ("random", bytes(range(256)) * 20)],
)
@pytest.mark.parametrize("cli", ["evaluate", "resume"])
def test_broken_checkpoint_is_one_line(run_copy, tmp_path, capsys, kind, content, cli) -> None:
    ck = run_copy / "checkpoint.pt"
    data = ck.read_bytes()[: len(ck.read_bytes()) // 2] if content is None else content
    ck.write_bytes(data)
    if cli == "evaluate":
        rc, err = run_cli(evaluate, [run_copy, "--out", tmp_path / "ev"], capsys)
    else:
        rc, err = run_cli(train, ["--config", run_copy / "config.toml", "--resume"], capsys)
    refused(f"{cli} {kind} checkpoint", rc, err, "checkpoint.pt")


def test_checkpoint_holding_other_arrays_is_refused(run_copy, tmp_path, capsys) -> None:
    # Plain data, but the replay of another size: refused when restored, not trusted.
    state = checkpoint.load(run_copy / "checkpoint.pt")
    state["agent"]["replay"]["obs"] = np.zeros((3, 3), np.float32)
    checkpoint.save(run_copy / "checkpoint.pt", state)
    rc, err = run_cli(train, ["--config", run_copy / "config.toml", "--resume"], capsys)
    refused("resume wrong replay", rc, err, "checkpoint.pt", "replay.obs")


@pytest.mark.parametrize("cli", ["radiomap", "train", "evaluate", "validate"])
def test_out_that_is_a_file_is_refused_before_any_work(run_copy, tmp_path, capsys, cli) -> None:
    target = tmp_path / "a_file"
    target.write_text("keep me")
    argv = {
        "radiomap": (radiomap, ["--scenario", "paper", "--out", target]),
        "train": (train, ["--out", target, "--dqn.episodes", "1"]),
        "evaluate": (evaluate, [run_copy, "--out", target]),
        "validate": (validate, ["rain", "--out", target]),
    }[cli]
    rc, err = run_cli(*argv, capsys)
    refused(f"{cli} --out file", rc, err, "a_file", "not a folder")
    assert target.read_text() == "keep me"


@pytest.mark.slow
@pytest.mark.parametrize("where", ["a file", "/proc", "radiomaps is a file"])
def test_unwritable_cache_is_a_warning_and_the_map_is_kept(tmp_path, monkeypatch, capsys, where):
    cache = {
        "a file": tmp_path / "cachefile",
        "/proc": Path("/proc/rainuav-cache"),
        "radiomaps is a file": tmp_path / "cache",
    }[where]
    if where == "a file":
        cache.write_text("")
    if where == "radiomaps is a file":
        cache.mkdir()
        (cache / "radiomaps").write_text("")
    monkeypatch.setenv("RAINUAV_CACHE_DIR", str(cache))
    with pytest.warns(CacheWarning, match="cannot be written"):
        rm = build_radio_map(tiny_scenario())
    assert rm.sinr_db.shape == (20, 20) and np.all(np.isfinite(rm.sinr_db))
    cfg = tmp_path / "tiny.toml"
    tiny_scenario().to_toml(cfg)
    rc, err = run_cli(radiomap, ["--config", cfg, "--out", tmp_path / "maps"], capsys)
    assert rc == 0, err
    assert err.count("warning: radio-map cache") == 1 and "Traceback" not in err
    assert RadioMap.load(tmp_path / "maps" / "radiomap.npz").sinr_db.shape == (20, 20)
    accepted(f"cache {where}")


@pytest.mark.parametrize("seed", ["-1", str(2**76)])
def test_seed_out_of_range_is_refused_before_writing(tmp_path, capsys, seed) -> None:
    out = tmp_path / "run"
    rc, err = run_cli(train, ["--seed", seed, "--out", out], capsys)
    refused(f"--seed {seed}", rc, err, "seed", "2^63")
    assert not (out / "config.toml").exists() and not (out / "radiomap.npz").exists()


@pytest.mark.parametrize(
    ("flag", "value", "field"),
    [
        ("--dqn.hidden", "100000000", "dqn.hidden"),
        ("--dqn.replay-capacity", "10000000000", "replay"),
    ],
)
def test_sizes_that_cannot_fit_are_refused_naming_the_gb(tmp_path, capsys, flag, value, field):
    out = tmp_path / "run"
    rc, err = run_cli(train, [flag, value, "--out", out], capsys)
    refused(f"{flag} {value}", rc, err, field, "GB")
    assert not (out / "radiomap.npz").exists()  # refused before the map was built


def test_a_map_too_big_for_memory_is_refused_before_allocating() -> None:
    # 21 cells x 3.6e7 pixels: the ray engine alone would hold three 5.6 GiB arrays.
    three = [Cell(azimuth_deg=a) for a in (0.0, 120.0, 240.0)]
    sites = [Site(x_m=1000.0 * (k + 1), y_m=1000.0, cells=list(three)) for k in range(7)]
    scn = Scenario(
        name="huge",
        area=Area(x_min_m=0, x_max_m=60_000, y_min_m=0, y_max_m=60_000, resolution_m=10),
        sites=sites,
        engine="ray",
    )
    assert sum(len(s.cells) for s in scn.sites) == 21
    api_refused("ray map 21 x 3.6e7", lambda: build_radio_map(scn, cache=False), "GB", "cells")


@pytest.mark.parametrize("n", [10**9, 10**12])
def test_vector_env_of_too_many_uavs_is_refused(n: int) -> None:
    import rainuav.envs  # noqa: F401  (registers the env)

    api_refused(
        f"make_vec {n}",
        lambda: gym.make_vec(
            "rainuav/UAVNav-v0", num_envs=n, vectorization_mode="vector_entry_point",
            radio_map=synthetic_map(), goal_m=(300.0, 350.0),
        ),
        "num_envs", "GB",
    )  # fmt: skip


def _env() -> UAVNavEnv:
    return UAVNavEnv(radio_map=synthetic_map(), goal_m=(300.0, 350.0), max_steps=100)


@pytest.mark.parametrize("action", ["up", 1.7, 1.0, True, None, [1], np.array([1, 2])])
def test_env_refuses_actions_that_are_not_one_integer(action: Any) -> None:
    env = _env()
    env.reset(seed=0)
    api_refused(f"env.step({action!r})", lambda: env.step(action), "action")


def test_env_takes_numpy_integers() -> None:
    env = _env()
    env.reset(seed=0, options={"start_m": (100.0, 100.0)})
    a = env.step(np.int64(0))
    env.reset(seed=0, options={"start_m": (100.0, 100.0)})
    b = env.step(np.array(0))
    env.reset(seed=0, options={"start_m": (100.0, 100.0)})
    c = env.step(0)
    assert a[1] == b[1] == c[1] and np.array_equal(a[0], c[0])
    accepted("env.step(numpy integers)")


@pytest.mark.parametrize("start", ["here", (float("nan"), 1.0), (1e9, 0.0), (1.0, 2.0, 3.0)])
def test_env_reset_refuses_a_bad_start(start: Any) -> None:
    api_refused(
        f"reset start_m={start!r}", lambda: _env().reset(options={"start_m": start}), "start_m"
    )


def test_step_before_reset_is_refused() -> None:
    api_refused("step before reset", lambda: _env().step(0), "reset")
    import rainuav.envs  # noqa: F401

    wrapped = gym.make("rainuav/UAVNav-v0", radio_map=synthetic_map(), goal_m=(300.0, 350.0))
    with pytest.raises(Exception, match="reset"):  # gymnasium's own order check comes first
        wrapped.step(0)
    api_refused("unwrapped step before reset", lambda: wrapped.unwrapped.step(0), "reset")
    venv = UAVNavVectorEnv(_env(), 4)
    api_refused("vector step before reset", lambda: venv.step(np.zeros(4, np.int64)), "reset")


@pytest.mark.parametrize(
    "actions", [[0.5, 1.9, 2.2, 3.99], [0.0, 1.0, 2.0, 3.0], ["up"] * 4, [0, 1, 2, 4], [0, 1]]
)
def test_vector_env_refuses_non_integral_actions(actions: Any) -> None:
    venv = UAVNavVectorEnv(_env(), 4)
    venv.reset(seed=0)
    api_refused(f"vector step {actions!r}", lambda: venv.step(actions), "integers in 0..3")


def test_vector_env_refuses_a_bad_start() -> None:
    venv = UAVNavVectorEnv(_env(), 4)
    api_refused("vector reset here", lambda: venv.reset(options={"start_m": "here"}), "start_m")


# -- 3. Hangs --------------------------------------------------------------------------------
def test_a_million_case_grid_is_refused_before_any_case_is_checked(tmp_path, monkeypatch, capsys):
    from rainuav.studies import spec as spec_mod

    def never(*_: Any) -> None:
        raise AssertionError("a case was checked before the count")

    monkeypatch.setattr(spec_mod, "_check_case", never)
    f = tmp_path / "grid.toml"
    rates = ", ".join(str(float(v)) for v in range(1000))
    mus = ", ".join(str(0.001 * (k + 1)) for k in range(1000))
    f.write_text(
        f'name = "g"\nsweep = "grid"\n[base]\nscenario = "paper"\n'
        f"[axes]\nrain_rate = [{rates}]\nmu = [{mus}]\n"
    )
    rc, err = run_cli(study, [f, "--out", tmp_path / "o"], capsys)
    refused("grid 10^6", rc, err, "1000000 cases", "10000")


def test_evaluate_bounds_its_starts(run_copy: Path, tmp_path: Path, capsys) -> None:
    rc, err = run_cli(evaluate, [run_copy, "--starts", "1000000000"], capsys)
    refused("evaluate --starts 1e9", rc, err, "--starts", "1..10000")
    rc, err = run_cli(train, ["--eval-starts", "1000000000", "--out", tmp_path / "r"], capsys)
    refused("train --eval-starts 1e9", rc, err, "eval_starts", "1..10000")


# -- 4. Wrong results that were given without a word -----------------------------------------
@pytest.mark.slow
def test_resume_cuts_the_log_back_to_the_checkpoint_even_in_a_moved_folder(tmp_path) -> None:
    first, moved = tmp_path / "first", tmp_path / "moved"
    stopped = train_run(
        *in_world(small_cfg(first, 70), synthetic_map()), progress=False, stop_after=50
    )
    assert stopped == {}
    # As a kill -9 after the log flushed past the checkpoint at 50 would leave it:
    with (first / "log.csv").open("a", newline="") as fh:
        for k in range(51, 63):
            csv.writer(fh).writerow([k, k, "1.0", 10, 0, "0.1", "1.0"])
    shutil.move(first, moved)  # and the folder handed to someone else, elsewhere
    m = train_run(*saved_world(small_cfg(moved, 70)), resume=True, progress=False)
    assert m["episodes"] == 70
    with (moved / "log.csv").open() as fh:
        finished = [int(r["finished"]) for r in csv.DictReader(fh)]
    assert finished == list(range(1, 71))
    accepted("moved run folder resumes")


def test_a_second_training_into_the_same_folder_is_refused(run_copy: Path, capsys) -> None:
    with FolderLock(run_copy, "a rainuav.train run"):
        rc, err = run_cli(train, ["--config", run_copy / "config.toml", "--resume"], capsys)
    refused("second train same --out", rc, err, str(run_copy), "is writing to this folder")


@pytest.mark.parametrize(
    ("key", "value"),
    [("sinr_db", 999.0), ("sinr_db", np.nan), ("rss_dbm", np.inf), ("serving_cell", 7)],
)
def test_a_cached_map_holding_garbage_is_rebuilt(tmp_path, key, value) -> None:
    scn = tiny_scenario()
    good = build_radio_map(scn)
    path = map_path(scn.digest())
    with np.load(path) as z:
        data = {k: z[k] for k in z.files}
    data[key] = np.full_like(data[key], value)
    with path.open("wb") as fh:
        np.savez(fh, **data)  # the right keys and digest, the wrong values
    api_refused(f"cached {key}={value}", lambda: RadioMap.load(path), key)
    again = build_radio_map(scn)
    assert np.array_equal(again.sinr_db, good.sinr_db)


def test_a_run_folder_map_holding_garbage_is_refused(run_copy, tmp_path, capsys) -> None:
    path = run_copy / "radiomap.npz"
    with np.load(path) as z:
        data = {k: z[k] for k in z.files}
    data["sir_db"] = np.full_like(data["sir_db"], np.nan)
    with path.open("wb") as fh:
        np.savez(fh, **data)
    rc, err = run_cli(evaluate, [run_copy, "--out", tmp_path / "ev"], capsys)
    refused("run folder NaN map", rc, err, "radiomap.npz", "sir_db")


@pytest.mark.parametrize(
    ("axes", "seeds", "needle"),
    [
        ("rain_rate = [10.0, 10.0, 10.0]", "[0]", "repeats the value"),
        ("rain_rate = [10.0]", "[0, 0]", "seeds repeats 0"),
        ("rain_rate = [10.0]\nboth = [{ rain_rate = 10.0 }]", "[0]", "repeats case"),
    ],
)
def test_a_study_repeating_a_case_is_refused(tmp_path, capsys, axes, seeds, needle) -> None:
    f = tmp_path / "dup.toml"
    f.write_text(f'name = "d"\nseeds = {seeds}\n[base]\nscenario = "paper"\n[axes]\n{axes}\n')
    rc, err = run_cli(study, [f, "--out", tmp_path / "o"], capsys)
    refused(f"study {needle}", rc, err, needle)


@pytest.mark.parametrize("umask", [0o022, 0o002, 0o077])
def test_written_files_honour_the_umask(tmp_path: Path, umask: int) -> None:
    old = os.umask(umask)
    try:
        path = write_atomic(tmp_path / "f.txt", lambda t: t.write_text("x"))
    finally:
        os.umask(old)
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask
    accepted(f"umask {oct(umask)}")


def test_a_full_disk_is_one_line_and_keeps_the_earlier_copy(tmp_path: Path, capsys) -> None:
    """A write that fails as a full disk fails (the OS's ENOSPC; torch's RuntimeError from its
    zip writer) raises WriteError naming the file and the free space, leaves the earlier copy
    as it was, and a CLI prints it as one line and exits 1."""
    import errno

    from rainuav import _cli
    from rainuav.errors import WriteError

    path = tmp_path / "checkpoint.pt"
    path.write_text("earlier")

    def full(t: Path) -> None:
        t.write_text("half")
        raise OSError(errno.ENOSPC, "No space left on device")

    def torch_full(t: Path) -> None:
        raise RuntimeError("[enforce fail at inline_container.cc:671] . unexpected pos 2349248")

    for write in (full, torch_full):
        with pytest.raises(WriteError, match=r"cannot write .*checkpoint\.pt .* GB free there"):
            write_atomic(path, write)
        assert path.read_text() == "earlier" and list(tmp_path.iterdir()) == [path]
    assert _cli.run(lambda: write_atomic(path, full) and 0) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: cannot write")
    accepted("a full disk")


# -- 5. What users of this field would try next ----------------------------------------------
@pytest.mark.parametrize("name", ["config.toml", "radiomap.npz", "checkpoint.pt"])
@pytest.mark.parametrize("how", ["missing", "empty", "garbage", "a folder"])
def test_every_file_of_a_run_folder_spoiled(run_copy, tmp_path, capsys, name, how) -> None:
    f = run_copy / name
    f.unlink()
    if how == "empty":
        f.write_bytes(b"")
    elif how == "garbage":
        f.write_bytes(b"\x00\xff not what it claims \x80" * 50)
    elif how == "a folder":
        f.mkdir()
    rc, err = run_cli(evaluate, [run_copy, "--out", tmp_path / "ev"], capsys)
    refused(f"evaluate {name} {how}", rc, err, name)


def test_a_map_file_that_needs_pickle_is_refused(run_copy, tmp_path, capsys) -> None:
    marker = tmp_path / "PWNED"
    path = run_copy / "radiomap.npz"
    with np.load(path) as z:
        data = {k: z[k] for k in z.files}
    data["sinr_db"] = np.array([Hostile(marker)], dtype=object)
    with path.open("wb") as fh:
        np.savez(fh, **data)
    rc, err = run_cli(evaluate, [run_copy, "--out", tmp_path / "ev"], capsys)
    refused("map with a pickle", rc, err, "radiomap.npz")
    assert not marker.exists()


@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("scenario_toml", np.asarray("[area\nbroken")),
        ("format_version", np.int64(99)),
        ("extent_m", np.zeros(3)),
        ("x_m", np.linspace(0.0, 1.0, 40)),
    ],
)
def test_a_map_with_bad_metadata_is_refused(run_copy, tmp_path, capsys, key, value) -> None:
    path = run_copy / "radiomap.npz"
    with np.load(path) as z:
        data = {k: z[k] for k in z.files}
    data[key] = value
    with path.open("wb") as fh:
        np.savez(fh, **data)
    rc, err = run_cli(evaluate, [run_copy, "--out", tmp_path / "ev"], capsys)
    refused(f"map {key}", rc, err, "radiomap.npz")


def test_a_config_from_a_newer_release_is_refused_naming_the_field(run_copy, tmp_path, capsys):
    cfg = run_copy / "config.toml"
    cfg.write_text("gust_front_m_s = 3\n" + cfg.read_text())
    rc, err = run_cli(evaluate, [run_copy, "--out", tmp_path / "ev"], capsys)
    refused("newer config.toml", rc, err, "gust_front_m_s")
    scn = tmp_path / "newer.toml"
    tiny_scenario().to_toml(scn)
    scn.write_text(scn.read_text().replace("[area]", "[area]\nterrain_file = 'dem.tif'"))
    rc, err = run_cli(radiomap, ["--config", scn, "--out", tmp_path / "m"], capsys)
    refused("newer scenario", rc, err, "terrain_file")


def test_ctrl_c_is_one_line_and_exit_130(tmp_path, monkeypatch, capsys) -> None:
    import rainuav.radio
    import rainuav.studies.run

    def interrupt(*_: Any, **__: Any) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(rainuav.radio, "build_radio_map", interrupt)
    rc, err = run_cli(radiomap, ["--scenario", "paper", "--out", tmp_path / "m"], capsys)
    assert rc == 130 and err.strip().splitlines() == [
        "interrupted: the map build stopped; nothing was written"
    ]
    assert not (tmp_path / "m").exists()
    import rainuav.rl.loop
    import rainuav.world

    monkeypatch.setattr(rainuav.world, "build_world", lambda *_, **__: None)  # no map here
    monkeypatch.setattr(rainuav.rl.loop, "train", interrupt)
    rc, err = run_cli(train, ["--out", tmp_path / "r"], capsys)
    assert rc == 130 and err.strip().splitlines() == [
        "interrupted: training stopped before its first checkpoint; nothing to resume from"
    ]
    (tmp_path / "r").mkdir()
    (tmp_path / "r" / "checkpoint.pt").write_bytes(b"")
    rc, err = run_cli(train, ["--out", tmp_path / "r"], capsys)
    assert rc == 130 and "--resume continues from" in err and err.count("\n") == 1
    monkeypatch.setattr(rainuav.studies.run, "_maps", interrupt)
    f = tmp_path / "s.toml"
    f.write_text('name = "s"\ncompute = ["map"]\n[base]\nscenario = "paper"\n[axes]\nmu = [0.1]\n')
    rc, err = run_cli(study, [f, "--out", tmp_path / "s", "--workers", "1"], capsys)
    last = err.replace("\r", "\n").strip().splitlines()[-1]
    assert rc == 130 and "Traceback" not in err
    assert last == "interrupted: finished cases are kept; the same command resumes the study"
    TALLY["accepted"] += 4  # a clean stop is the right answer to Ctrl-C


EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
TRIP = ["--start", "47.3660,8.5380", "--goal", "47.3700,8.5420"]


@pytest.mark.parametrize(
    ("name", "content", "needle"),
    [
        ("sites.csv", b"\x00\xff\xfe garbage \x89PNG", "sites file"),
        ("sites.csv", b"site_id,lat,lon,height_m,azimuth_deg,electrical_tilt_deg,tx_power_dbm\n"
                      b"A,nan,8.5,25,0,6,46\n", "column lat must be a number"),
        ("sites.csv", b"site_id,lat,lon,height_m,azimuth_deg,electrical_tilt_deg,tx_power_dbm\n"
                      b"A,47.37,8.54,1e308,0,6,46\n", "column height_m"),
        ("sites.geojson", b"[" * 100_000, "not JSON"),
        ("sites.geojson", b'{"type": "FeatureCollection", "features": 5}', "FeatureCollection"),
    ],
)  # fmt: skip
def test_fly_refuses_hostile_sites_files(tmp_path, capsys, name, content, needle) -> None:
    from rainuav import fly

    f = tmp_path / name
    f.write_bytes(content)
    rc, err = run_cli(fly, ["--sites", f, *TRIP, "--out", tmp_path / "o"], capsys)
    refused(f"fly {name}", rc, err, needle)
    assert not (tmp_path / "o" / "mission.plan").exists()


@pytest.mark.parametrize("content", [b"", b"CDF\x01 truncated", b"\x89HDF\r\n\x1a\n junk"])
def test_fly_refuses_a_weather_file_that_is_not_netcdf(tmp_path, capsys, content) -> None:
    from rainuav import fly

    f = tmp_path / "radar.nc"
    f.write_bytes(content)
    argv = ["--sites", EXAMPLES / "sites.csv", *TRIP, "--weather", f, "--out", tmp_path / "o"]
    rc, err = run_cli(fly, argv, capsys)
    refused("fly --weather garbage", rc, err, "radar.nc")


# -- 6. First contact: real coordinates and real folders ------------------------------------
def _sites_at(tmp_path: Path, lat0: float, lon0: float) -> Path:
    """The shipped example's sectors moved to (lat0, lon0): same layout, another hemisphere."""
    rows = list(csv.DictReader((EXAMPLES / "sites.csv").read_text().splitlines()))
    for r in rows:
        r["lat"] = f"{float(r['lat']) - 47.37 + lat0:.6f}"
        r["lon"] = f"{float(r['lon']) - 8.54 + lon0:.6f}"
    f = tmp_path / "sites_moved.csv"
    with f.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    return f


@pytest.mark.slow
def test_fly_takes_southern_and_western_coordinates_as_typed(tmp_path, capsys) -> None:
    # Sydney: a minus sign first, typed as a separate value and with "=".
    from rainuav import fly

    sites = _sites_at(tmp_path, -33.8688, 151.2093)
    out = tmp_path / "sydney"
    argv = ["--sites", sites, "--start", "-33.8728,151.2073", "--goal=-33.8608,151.2233",
            "--out", out]  # fmt: skip
    rc, err = run_cli(fly, argv, capsys)
    assert rc == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert -33.88 < summary["origin"]["lat"] < -33.85  # the southern hemisphere, not 33.8 N
    line = json.loads((out / "flight.geojson").read_text())["features"][0]
    lon, lat = np.array(line["geometry"]["coordinates"])[0, :2]
    assert abs(lat - -33.8728) < 1e-4 and abs(lon - 151.2073) < 1e-4  # starts where asked
    accepted("fly --start -33.87,151.21 (Sydney)")
    # West of Greenwich and south of the equator, with --area: parsed, then refused in the
    # user's terms (no sites there), not by argparse.
    argv = ["--sites", EXAMPLES / "sites.csv", "--start", "-34.61,-58.39", "--goal",
            "-34.605,-58.38", "--area", "-34.62,-58.40,-34.60,-58.37",
            "--out", tmp_path / "o"]  # fmt: skip
    rc, err = run_cli(fly, argv, capsys)
    refused("fly Buenos Aires --area", rc, err, "site ZH-001", "34.62", "lies outside the --area")
    assert "--start=-33.87,151.21" in _help(fly, capsys)  # the help says how to type it


def _help(mod: Any, capsys: pytest.CaptureFixture) -> str:
    capsys.readouterr()
    with pytest.raises(SystemExit):
        mod.main(["--help"])
    return " ".join(capsys.readouterr().out.split())


@pytest.mark.parametrize(
    ("argv", "needles"),
    [
        (["--start", "-33.8688,151.2093", "--goal", "-47.366,-171.462"], ("km apart", "10 km")),
        (["--start", "47.3660,8.5380", "--goal", "47.3700,8.5420", "--area", "-80,-179,80,179"],
         ("--area spans", "km east-west", "10 km x 10 km")),
        (["--start", "47.37,8.54", "--goal", "49.37,8.54"], ("222.4 km apart", "legs")),
        (["--start", "47.3660,8.5380", "--goal", "47.3660,8.5380"],
         ("0.0 m apart", "arrival tolerance", "no flight to plan")),
        (["--start", "47.3660,8.5380", "--goal", "47.36603,8.53803"],
         ("4.0 m apart", "arrival tolerance")),
    ],
)  # fmt: skip
def test_fly_refuses_far_and_empty_flights_in_the_users_terms(tmp_path, capsys, argv, needles):
    from rainuav import fly

    out = tmp_path / "o"
    rc, err = run_cli(fly, ["--sites", EXAMPLES / "sites.csv", *argv, "--out", out], capsys)
    refused(f"fly {' '.join(argv)}", rc, err, *needles)
    for word in ("pixels", "budget_gpoints", "x_min_m", "resolution_m"):
        assert word not in err, (word, err)  # the program's terms, not the user's
    assert not out.exists()


def test_fly_refuses_sites_on_another_continent_naming_the_site(tmp_path, capsys) -> None:
    from rainuav import fly

    sites = _sites_at(tmp_path, -33.8688, 151.2093)  # Sydney's sites, a flight in Zurich
    rc, err = run_cli(fly, ["--sites", sites, *TRIP, "--out", tmp_path / "o"], capsys)
    refused("fly sites elsewhere", rc, err, "site ZH-00", "lies 167", "km from the route", "10 km")
    assert "x_min_m" not in err


OUT_CLIS = ["radiomap", "train", "evaluate", "validate", "study", "fly"]


@pytest.mark.parametrize("cli", OUT_CLIS)
@pytest.mark.parametrize("where", ["/proc/x", "/proc/x/y", "/sys/rainuav"])
def test_out_that_cannot_be_made_is_refused_before_any_work(run_copy, tmp_path, capsys, cli, where):
    from rainuav import fly

    spec = tmp_path / "s.toml"
    spec.write_text(
        'name = "s"\ncompute = ["map"]\n[base]\nscenario = "paper"\n[axes]\nmu = [0.1]\n'
    )
    argv = {
        "radiomap": (radiomap, ["--scenario", "paper", "--out", where]),
        "train": (train, ["--out", where, "--dqn.episodes", "1"]),
        "evaluate": (evaluate, [run_copy, "--out", where]),
        "validate": (validate, ["rain", "--out", where]),
        "study": (study, [spec, "--out", where, "--workers", "1"]),
        "fly": (fly, ["--sites", EXAMPLES / "sites.csv", *TRIP, "--out", where]),
    }[cli]
    rc, err = run_cli(*argv, capsys)
    refused(f"{cli} --out {where}", rc, err, where, "cannot be")


# A killed run's folder must not look finished: each tool writes one file last (its
# completion file), after removing an earlier run's copy of it.
COMPLETION_FILES = {"fly": "summary.json", "radiomap": "radiomap.npz",
                    "evaluate": "evaluation.json", "study": "results.csv"}  # fmt: skip


def _record_writes(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """The names of the files written through rainuav._io (every file the tools write), in
    the order they land."""
    import rainuav._io as io_mod

    landed: list[str] = []
    real = io_mod.os.replace

    def replace(src: Any, dst: Any) -> None:
        real(src, dst)
        landed.append(Path(dst).name)

    monkeypatch.setattr(io_mod.os, "replace", replace)
    return landed


def _tool_argv(cli: str, run_copy: Path, tmp_path: Path, out: Path) -> tuple[Any, list[Any]]:
    from rainuav import fly

    spec = tmp_path / "s.toml"
    spec.write_text('name = "s"\ncompute = ["map"]\n[base]\nscenario = "paper"\n'
                    'engine = "ray"\n[axes]\nmu = [0.1]\n')  # fmt: skip
    scn = tmp_path / "tiny.toml"
    tiny_scenario().to_toml(scn)
    return {
        "fly": (fly, ["--sites", EXAMPLES / "sites.csv", *TRIP, "--out", out]),
        "radiomap": (radiomap, ["--config", scn, "--out", out]),
        "evaluate": (evaluate, [run_copy, "--out", out, "--starts", "5"]),
        "study": (study, [spec, "--out", out, "--workers", "1"]),
    }[cli]


@pytest.mark.slow
@pytest.mark.parametrize("cli", sorted(COMPLETION_FILES))
def test_the_completion_file_is_written_last(run_copy, tmp_path, capsys, monkeypatch, cli):
    landed = _record_writes(monkeypatch)
    out = tmp_path / "out"
    rc, err = run_cli(*_tool_argv(cli, run_copy, tmp_path, out), capsys)
    assert rc == 0, err
    assert len(set(landed)) >= 2 and landed[-1] == COMPLETION_FILES[cli], (cli, landed)
    accepted(f"{cli}: {COMPLETION_FILES[cli]} last")


@pytest.mark.parametrize("cli", sorted(COMPLETION_FILES))
def test_a_folder_where_the_completion_file_is_a_folder_is_refused(run_copy, tmp_path, capsys, cli):
    out = tmp_path / "out"
    (out / COMPLETION_FILES[cli] / "inside").mkdir(parents=True)
    rc, err = run_cli(*_tool_argv(cli, run_copy, tmp_path, out), capsys)
    refused(f"{cli} {COMPLETION_FILES[cli]} is a folder", rc, err, COMPLETION_FILES[cli],
            "cannot be replaced")  # fmt: skip
    assert (out / COMPLETION_FILES[cli] / "inside").is_dir()  # nothing of the user's lost


@pytest.mark.slow
@pytest.mark.parametrize("cli", sorted(COMPLETION_FILES))
def test_a_run_killed_before_its_last_file_does_not_look_finished(
    run_copy, tmp_path, capsys, monkeypatch, cli
):
    # An earlier finished run in the same folder, then a run killed with SIGKILL in its last
    # second: as its completion file is about to land, every other file written.
    out = tmp_path / "out"
    assert run_cli(*_tool_argv(cli, run_copy, tmp_path, out), capsys)[0] == 0
    assert (out / COMPLETION_FILES[cli]).exists()
    code = f"""
import os, sys
import rainuav._io as io_mod
real = io_mod.os.replace
def replace(src, dst):
    if os.path.basename(dst) == {COMPLETION_FILES[cli]!r}:
        os.kill(os.getpid(), 9)
    real(src, dst)
io_mod.os.replace = replace
from rainuav import {cli}
sys.exit({cli}.main(sys.argv[1:]))
"""
    _, argv = _tool_argv(cli, run_copy, tmp_path, out)
    proc = subprocess.run([sys.executable, "-c", code, *map(str, argv)], capture_output=True,
                          text=True, timeout=240)  # fmt: skip
    assert proc.returncode == -9, proc.stderr
    assert not (out / COMPLETION_FILES[cli]).exists(), cli
    accepted(f"{cli} killed: no {COMPLETION_FILES[cli]}")


def test_bad_dems_are_refused_by_radiomap_in_one_line(tmp_path, capsys) -> None:
    # Each bad DEM of the terrain tests through `radiomap --terrain`: exit 2, one line naming
    # the file and what is wrong, no radiomap.npz.
    import test_terrain
    from rainuav import radiomap

    toml = tmp_path / "place.toml"
    test_terrain.scenario(None).to_toml(toml)
    for what, (path, words) in test_terrain._bad_dems(tmp_path).items():
        out = tmp_path / f"out_{what.replace(' ', '_')}"
        argv = ["--config", str(toml), "--terrain", str(path), "--out", str(out), "--no-cache"]
        rc, err = run_cli(radiomap, argv, capsys)
        refused(f"radiomap --terrain ({what})", rc, err, path.name, words)
        assert not (out / "radiomap.npz").exists()


def test_bad_footprint_files_are_refused_by_radiomap_in_one_line(tmp_path, capsys) -> None:
    # Each bad footprint file of the building tests through `radiomap --footprints`: exit 2,
    # one line naming the file and what is wrong (and the feature where one is at fault), no
    # radiomap.npz; a missing file too.
    import test_buildings
    from rainuav import radiomap

    toml = tmp_path / "place.toml"
    test_buildings.scenario(None, [Site(100.0, 400.0, 30.0, [test_buildings.iso_cell()])]).to_toml(
        toml
    )
    test_buildings._write_raw(tmp_path)
    bad = test_buildings.bad_footprint_files(tmp_path)
    bad["missing"] = (tmp_path / "missing.geojson", "no such file")
    for what, (path, word) in bad.items():
        out = tmp_path / f"out_{what}"
        argv = ["--config", str(toml), "--footprints", str(path), "--out", str(out), "--no-cache"]
        rc, err = run_cli(radiomap, argv, capsys)
        refused(f"radiomap --footprints ({what})", rc, err, path.name, word)
        assert not (out / "radiomap.npz").exists()


@pytest.mark.slow
def test_a_cached_map_never_reaches_for_the_dem_it_was_made_from(tmp_path, capsys) -> None:
    # fly --terrain A/dem.tif, the DEM moved to B/ and A/ deleted: the next fly --terrain
    # B/dem.tif (the same contents: a cache hit) plans without reaching for A/dem.tif.
    from rainuav import fly
    from test_terrain import _zurich_hill_dem

    a, b = tmp_path / "A", tmp_path / "B"
    a.mkdir()
    b.mkdir()
    dem = _zurich_hill_dem(a / "dem.tif")
    base = ["--sites", EXAMPLES / "sites.csv", *TRIP, "--engine", "ray"]
    rc, err = run_cli(fly, [*base, "--terrain", dem, "--out", tmp_path / "one"], capsys)
    assert rc == 0, err
    shutil.move(dem, b / "dem.tif")
    shutil.rmtree(a)
    rc, err = run_cli(fly, [*base, "--terrain", b / "dem.tif", "--out", tmp_path / "two"], capsys)
    assert rc == 0 and "error" not in err, err
    one = json.loads((tmp_path / "one" / "summary.json").read_text())
    two = json.loads((tmp_path / "two" / "summary.json").read_text())
    assert one["cost"] == two["cost"]
    accepted("fly --terrain with the DEM moved since the map was cached")


def test_a_nan_vertex_in_a_footprint_file_is_one_line_and_no_warning(tmp_path, capsys) -> None:
    from rainuav import fly

    ring = [[8.54, 47.37], [float("nan"), 47.371], [8.541, 47.371], [8.54, 47.37]]
    fc = {"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {
        "height": 10}, "geometry": {"type": "Polygon", "coordinates": [ring]}}]}  # fmt: skip
    (tmp_path / "nan.geojson").write_text(json.dumps(fc))
    argv = ["--sites", EXAMPLES / "sites.csv", *TRIP, "--footprints", tmp_path / "nan.geojson",
            "--out", tmp_path / "o"]  # fmt: skip
    rc, err = run_cli(fly, argv, capsys)
    refused("fly --footprints with a NaN vertex", rc, err, "nan.geojson", "longitude")
    assert len(err.strip().splitlines()) == 1, err  # no warning line before it
    assert not (tmp_path / "o").exists()


def test_fly_policy_is_checked_before_maps_and_torch(tmp_path) -> None:
    # A --policy that is no run is refused before the footprints are read or torch loaded
    # (a fresh interpreter: torch absent from sys.modules after the refusal).
    fc = {"type": "FeatureCollection", "features": []}
    (tmp_path / "none.geojson").write_text(json.dumps(fc))
    code = (
        "import sys; from rainuav.fly import main; "
        f"rc = main(['--sites', {str(EXAMPLES / 'sites.csv')!r}, '--start', '47.3700,8.5400', "
        f"'--goal', '47.3830,8.5570', '--footprints', {str(tmp_path / 'none.geojson')!r}, "
        f"'--policy', {str(tmp_path / 'no_run')!r}, '--out', {str(tmp_path / 'o')!r}]); "
        "print(rc, 'torch' in sys.modules)"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert res.stdout.split() == ["2", "False"], (res.stdout, res.stderr)
    refused("fly --policy no_run", 2, res.stderr, "--policy", "not a rainuav.train run")


def test_fly_start_height_outside_the_band_is_refused(tmp_path, capsys) -> None:
    from rainuav import fly

    argv = ["--sites", EXAMPLES / "sites.csv", "--start", "47.3700,8.5400,100", "--goal",
            "47.3830,8.5570", "--altitudes-m", "30:120:15", "--out", tmp_path / "o"]  # fmt: skip
    rc, err = run_cli(fly, argv, capsys)
    refused("fly --start at 100 m of 30:120:15", rc, err, "100 m", "--altitudes-m")


CLI_MODULES = ("fly", "radiomap", "train", "evaluate", "study", "validate")


@pytest.mark.parametrize("cli", CLI_MODULES)
def test_no_help_prints_raw_markup(cli: str, capsys) -> None:
    # reStructuredText's roles and literals are for the documentation site: a terminal shows
    # the names they link.
    import importlib
    import re

    text = _help(importlib.import_module(f"rainuav.{cli}"), capsys)
    assert not re.search(r":[a-z]+:`|``", text), re.search(r".{30}(:[a-z]+:`|``).{30}", text)
    assert "PHYSICS" not in text  # the physics reference is a page of the site


def test_study_help_names_every_built_in_study(capsys) -> None:
    from rainuav.studies.spec import BUILT_IN

    text = _help(study, capsys)
    assert all(f"'{name}'" in text for name in BUILT_IN)
    for flag, word in (("--out", "results.csv"), ("--workers", "at once"), ("--quick", "[quick]")):
        assert re.search(rf"{flag}\b[^-]*{re.escape(word)}", text), (flag, text)


def test_train_help_agrees_with_the_learning_page(capsys) -> None:
    text = _help(train, capsys)
    assert "Table I hyperparameters" not in text
    assert "--preset paper-learner runs Algorithm 1 and Table I literally" in text


def test_out_of_reach_pixels_are_named_in_the_rss_figure() -> None:
    from rainuav.radio.outputs.plot import plot_map
    from rainuav.radio.outputs.sinr import RSS_FLOOR_DBM

    rm = build_radio_map(tiny_scenario(), cache=False)
    rm.rss_dbm[0, :3, :3] = RSS_FLOOR_DBM
    ax = plot_map(rm, "rss")
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("out of reach" in t and "-250 dBm" in t for t in texts), texts
    import matplotlib.pyplot as plt

    plt.close(ax.figure)


OSM_TAG_VARIANTS = [
    ({"height": "12;15"}, 12.0), ({"height": "~20"}, 20.0), ({"height": "20 m"}, 20.0),
    ({"height": "12,5"}, 12.5), ({"building:levels": "3-4"}, 12.0),
    ({"building:levels": "2.5"}, 7.5), ({"building:levels": "2,5"}, 7.5),
    ({"building:levels": "0", "roof:height": "3"}, 3.0),
    ({"building:levels": "2", "roof:levels": "1"}, 9.0),
    ({"building:part": "yes", "min_height": "18", "roof:height": "5"}, 23.0),
]  # fmt: skip


@pytest.mark.parametrize(("tags", "roof"), OSM_TAG_VARIANTS)
def test_openstreetmap_tag_variants_are_read(tmp_path, tags, roof) -> None:
    # Values as real exports carry them: each read (rightly accepted), the roof as the OSM
    # wiki defines it.
    import test_buildings
    from rainuav.ground.footprints import read_footprints

    one = test_buildings.feature(test_buildings.rect(0, 0, 40, 40), **tags)
    path = test_buildings.write(tmp_path / "v.geojson", [one])
    fp = read_footprints(path, test_buildings.GEO, (0.0, 800.0, 0.0, 800.0))
    assert [b.height_m for b in fp.buildings] == [pytest.approx(roof)] and not fp.skipped
    accepted(f"footprint tags {tags}")


def test_a_bad_tag_outside_the_area_never_refuses_a_city(tmp_path, capsys) -> None:
    # radiomap --footprints: a file with a building in the area and an unreadable one far
    # outside it builds the map; one whose every feature lies outside is refused in one line.
    import test_buildings

    toml = tmp_path / "place.toml"
    test_buildings.scenario(None, [Site(100.0, 400.0, 30.0, [test_buildings.iso_cell()])]).to_toml(
        toml
    )
    f, rect = test_buildings.feature, test_buildings.rect
    ok = test_buildings.write(tmp_path / "city.geojson", [f(rect(300, 300, 340, 340), height=20),
                              f(rect(9000, 9000, 9040, 9040), height="very tall")])  # fmt: skip
    out = tmp_path / "ok"
    rc, err = run_cli(radiomap, ["--config", toml, "--footprints", ok, "--out", out, "--no-cache"],
                      capsys)  # fmt: skip
    assert rc == 0 and "1 buildings from 2 features (1 outside the area" in err, err
    accepted("radiomap --footprints with a bad tag outside the area")
    away = test_buildings.write(tmp_path / "away.geojson", [f(rect(9000, 9000, 9040, 9040))])
    out = tmp_path / "away"
    rc, err = run_cli(radiomap, ["--config", toml, "--footprints", away, "--out", out,
                                 "--no-cache"], capsys)  # fmt: skip
    refused("radiomap --footprints all outside", rc, err, "away.geojson", "outside the area")
    assert not (out / "radiomap.npz").exists()


def test_the_default_height_is_a_flag(tmp_path, capsys) -> None:
    # radiomap --default-height: the untagged building's roof and the summary follow it; out of
    # range or without footprints, one line and nothing written.
    import test_buildings

    toml = tmp_path / "place.toml"
    test_buildings.scenario(None, [Site(100.0, 400.0, 30.0, [test_buildings.iso_cell()])]).to_toml(
        toml
    )
    f, rect = test_buildings.feature, test_buildings.rect
    path = test_buildings.write(tmp_path / "plain.geojson", [f(rect(300, 300, 340, 340))])
    base = ["--config", toml, "--no-cache"]
    rc, err = run_cli(radiomap, [*base, "--footprints", path, "--default-height", "24",
                                 "--out", tmp_path / "ok"], capsys)  # fmt: skip
    assert rc == 0 and "1 of the buildings kept at the default height 24 m" in err, err
    accepted("radiomap --default-height 24")
    for extra, needle in ((["--footprints", path, "--default-height", "-3"], "--default-height"),
                          (["--default-height", "20"], "--footprints")):  # fmt: skip
        out = tmp_path / "bad"
        rc, err = run_cli(radiomap, [*base, *extra, "--out", out], capsys)
        refused(f"radiomap {extra}", rc, err, needle)
        assert not (out / "radiomap.npz").exists()


def test_an_episode_longer_than_any_command_allows_is_refused_where_it_is_read(tmp_path, capsys):
    """``train --task.max-steps`` past 100 000 was a hang at 0%: one range for every command."""
    for value in ("1000000000000", "200000", "0"):
        rc, err = run_cli(train, ["--task.max-steps", value, "--out", tmp_path / "x"], capsys)
        refused(f"train --task.max-steps {value}", rc, err, "max_steps must be within 1..100000")
        assert not (tmp_path / "x").exists()


def test_deeply_nested_json_is_one_line(run_copy, tmp_path, capsys) -> None:
    """A fit_json nested 100 000 deep inside radiomap.npz, a GeoJSON as deep to --footprints:
    a RecursionError before; one line now."""
    deep = "[" * 100_000 + "]" * 100_000
    rm = RadioMap.load(run_copy / "radiomap.npz")
    path = rm.save(tmp_path / "deep.npz")
    data = dict(np.load(path))
    data["fit_json"] = np.asarray(deep)
    np.savez(path, **data)
    api_refused("radiomap.npz with a deep fit_json", lambda: RadioMap.load(path), "fit_json")
    geo = tmp_path / "deep.geojson"
    geo.write_text(deep)
    from rainuav.radio.scene.scenario import Origin

    toml = tiny_scenario().replace(origin=Origin(47.37, 8.54)).to_toml(tmp_path / "s.toml")
    rc, err = run_cli(radiomap, ["--config", toml, "--footprints", geo, "--no-cache",
                                 "--out", tmp_path / "o"], capsys)  # fmt: skip
    refused("radiomap --footprints deep.geojson", rc, err, "deep.geojson")


def test_a_preset_chain_too_long_or_beside_its_base(tmp_path, capsys) -> None:
    """An ``extends`` chain of 1 100 presets was a RecursionError; a preset's ``extends`` is read
    beside the preset (``p/a.toml`` extending ``b.toml`` finds ``p/b.toml``)."""
    from rainuav.rl.config import MAX_EXTENDS, preset_fields

    chain = tmp_path / "chain"
    chain.mkdir()
    for k in range(MAX_EXTENDS + 5):
        (chain / f"p{k}.toml").write_text(f'extends = "p{k + 1}.toml"\n' if k < MAX_EXTENDS + 4
                                          else "[dqn]\nlr = 1e-4\n")  # fmt: skip
    api_refused("a preset chain of 105", lambda: preset_fields(chain / "p0.toml"), "extends chains")
    near = tmp_path / "p"
    near.mkdir()
    (near / "b.toml").write_text("[dqn]\nlr = 2e-4\n")
    (near / "a.toml").write_text('extends = "b.toml"\n[dqn]\ngamma = 0.97\n')
    got = preset_fields(near / "a.toml")
    assert got["dqn.lr"] == 2e-4 and got["dqn.gamma"] == 0.97
    accepted("a preset extending its neighbour by name")


@pytest.mark.parametrize("how", ["random bytes", "a folder", "tb a file"])
def test_a_resumed_run_with_a_spoiled_log_is_one_line(run_copy, tmp_path, capsys, how) -> None:
    """``train --resume`` with ``log.csv`` of random bytes, ``log.csv`` a folder or ``tb`` a plain
    file: a UnicodeDecodeError, IsADirectoryError or FileExistsError before."""
    log, tb = run_copy / "log.csv", run_copy / "tb"
    if how == "random bytes":
        log.write_bytes(np.random.default_rng(0).bytes(4000))
    elif how == "a folder":
        log.unlink()
        log.mkdir()
    else:
        shutil.rmtree(tb, ignore_errors=True)
        tb.write_text("not a folder")
    m = train_run  # the API, as the command calls it
    api_refused(f"--resume with {how}", lambda: m(*saved_world(plumbing_cfg(run_copy, 20)),
                                                  resume=True, progress=False),
                "log" if how != "tb a file" else "tb")  # fmt: skip


def test_calibrate_without_measurements_is_refused(tmp_path, capsys) -> None:
    """``radiomap --calibrate foo`` without ``--measurements`` was silently ignored."""
    toml = tiny_scenario().to_toml(tmp_path / "s.toml")
    for flag in (["--calibrate", "power_db"], ["--receive-pattern", "elevation"],
                 ["--residual-kernel", "two-scale"]):  # fmt: skip
        rc, err = run_cli(radiomap, ["--config", toml, *flag, "--out", tmp_path / "o"], capsys)
        refused(f"radiomap {flag[0]} alone", rc, err, flag[0], "--measurements")
        assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("how", ["emptied", "another goal"])
def test_a_config_that_is_not_the_runs_is_refused_by_evaluate(run_copy, capsys, how) -> None:
    """``config.toml`` emptied (read as the defaults before: another goal, 200 starts) or edited
    to another goal: the checkpoint's own record of the configuration differs, so evaluate
    refuses naming config.toml and what differs."""
    cfg = run_copy / "config.toml"
    if how == "emptied":
        cfg.write_text("")
    else:
        cfg.write_text(re.sub(r"goal_m = \[[^]]*\]", "goal_m = [100.0, 100.0]", cfg.read_text()))
    rc, err = run_cli(evaluate, [run_copy], capsys)
    refused(f"evaluate with config.toml {how}", rc, err, "config.toml", "differs from")
    assert not (run_copy / "evaluation.json").exists()


@pytest.mark.parametrize("how", ["another map of the same area", "an extent of 1e9 m"])
def test_a_map_swapped_into_a_run_is_refused_by_evaluate_and_resume(run_copy, capsys, how):
    """Another map of the same area swapped into a run let --resume carry on, and a map with its
    extent crafted to 1e9 m was evaluated: the checkpoint records what the run flies, and both
    refuse naming radiomap.npz."""
    path = run_copy / "radiomap.npz"
    rm = RadioMap.load(path)
    if how.startswith("another"):
        rm = dataclasses.replace(
            rm, sir_db=np.roll(rm.sir_db, 7, 1), sinr_db=np.roll(rm.sinr_db, 7, 1)
        )
        rm.save(path)
    else:
        data = dict(np.load(path))
        data["extent_m"] = np.array([0.0, 1e9, 0.0, 1e9])
        np.savez(path, **data)
    rc, err = run_cli(evaluate, [run_copy], capsys)
    refused(f"evaluate with {how}", rc, err, "radiomap.npz")
    assert not (run_copy / "evaluation.json").exists()
    api_refused(f"--resume with {how}",
                lambda: train_run(*saved_world(plumbing_cfg(run_copy, 20)), resume=True,
                                  progress=False), "radiomap.npz")  # fmt: skip


def test_a_negative_coordinate_is_read_as_typed(tmp_path, capsys) -> None:
    """``--task.goal-m -500,300`` ended in "expected one argument" (argparse took the value for
    an option); read as typed, it is refused for what it is: outside the area."""
    rc, err = run_cli(train, ["--task.goal-m", "-500,300", "--out", tmp_path / "x"], capsys)
    refused("train --task.goal-m -500,300", rc, err, "goal_m must lie inside the area", "-500")
    assert "expected one argument" not in err and not (tmp_path / "x").exists()


def test_a_map_of_another_place_is_refused_naming_the_map(run_copy, capsys) -> None:
    """A map of another area swapped into a run was refused as "config.toml: does not fit the
    world flown: goal_m must lie inside the area": the file at fault is the map."""
    path = run_copy / "radiomap.npz"
    rm = RadioMap.load(path)
    a = rm.scenario.area
    far = dataclasses.replace(a, x_min_m=a.x_min_m + 5000, x_max_m=a.x_max_m + 5000)
    sites = [dataclasses.replace(t, x_m=t.x_m + 5000) for t in rm.scenario.sites]
    moved = dataclasses.replace(
        rm, scenario=rm.scenario.replace(area=far, sites=sites), x_m=rm.x_m + 5000,
        extent_m=(far.x_min_m, far.x_max_m, far.y_min_m, far.y_max_m),
    )  # fmt: skip
    moved.save(path)
    rc, err = run_cli(evaluate, [run_copy], capsys)
    refused("evaluate with a map of another place", rc, err, "radiomap.npz: refused", "goal_m")


def test_a_log_at_two_hundred_heights_is_bounded_and_said(tmp_path, capsys) -> None:
    """A log at 200 different 10 m heights (100-2 090 m) built about 200 maps and a 200-fold
    cross-validation with nothing shown: it is refused naming alt_m and the flag that coarsens
    the step, before any level map is built; with that flag it is corrected, with progress
    shown, and its folds are at most ``MAX_FOLDS``."""
    from rainuav.radio.measured.heldout import MAX_FOLDS, designs
    from rainuav.radio.measured.levels import MAX_LEVEL_MAPS
    from rainuav.radio.measured.log import read_log
    from rainuav.radio.outputs.maps import build_radio_map

    toml = tiny_scenario().to_toml(tmp_path / "s.toml")
    rng = np.random.default_rng(0)
    rows = ["x_m,y_m,alt_m,cell,rss_dbm"]
    for k in range(200):
        for x in rng.uniform(20, 380, 6):
            rows.append(f"{x:.1f},{rng.uniform(20, 380):.1f},{100 + 10 * k},0,"
                        f"{-70 + rng.normal(0, 4):.1f}")  # fmt: skip
    log = tmp_path / "high.csv"
    log.write_text("\n".join(rows) + "\n")
    out = tmp_path / "o"
    rc, err = run_cli(radiomap, ["--config", toml, "--measurements", log, "--out", out], capsys)
    refused("a log at 200 heights", rc, err, "high.csv", "alt_m", "100..2090",
            str(MAX_LEVEL_MAPS), "53 m or more", "--level-step-m")  # fmt: skip
    assert not (out / "radiomap.npz").exists() and "map 1/" not in err
    rc, err = run_cli(radiomap, ["--config", toml, "--level-step-m", "0.5", "--measurements",
                                 log, "--out", out], capsys)  # fmt: skip
    refused("a level step of 0.5 m", rc, err, "--level-step-m", "1..500")
    rc, err = run_cli(radiomap, ["--config", toml, "--level-step-m", "50", "--out", out], capsys)
    refused("--level-step-m alone", rc, err, "--level-step-m", "--measurements")
    scn = tiny_scenario()
    rm = build_radio_map(scn)
    read = read_log(log, scn)
    folds = designs(rm, read, 10.0)
    assert len(np.unique(folds["height"])) == MAX_FOLDS
    accepted("a log at 200 heights, its height folds grouped")
    rc, err = run_cli(radiomap, ["--config", toml, "--level-step-m", "53", "--measurements", log,
                                 "--out", out], capsys)  # fmt: skip
    assert rc == 0, err
    assert "map 1/" in err and "held out: one height of" in err
    assert (out / "radiomap.npz").exists()
    accepted("a log at 200 heights with the 53 m level step it names, progress shown")


def test_a_runs_config_as_a_preset_starts_from_the_preset_it_records(tmp_path, capsys) -> None:
    """A ``preset`` key inside a preset (a run's ``config.toml`` handed on as a preset) gave an
    odd note; it is the preset's base, as ``extends`` is, and both at once are refused."""
    from rainuav.rl.config import preset_fields

    (tmp_path / "b.toml").write_text("[dqn]\nlr = 2e-4\ngamma = 0.9\n")
    (tmp_path / "run.toml").write_text(f'preset = "{tmp_path / "b.toml"}"\n[dqn]\ngamma = 0.97\n')
    got = preset_fields(tmp_path / "run.toml")
    assert "preset" not in got and got["dqn.lr"] == 2e-4 and got["dqn.gamma"] == 0.97
    accepted("a run's config.toml as a preset")
    (tmp_path / "both.toml").write_text('preset = "b.toml"\nextends = "b.toml"\n')
    api_refused("extends and preset", lambda: preset_fields(tmp_path / "both.toml"),
                "extends or preset")  # fmt: skip


def test_a_heading_gain_asked_of_a_log_without_headings_is_one_line(tmp_path, capsys) -> None:
    """``radiomap --receive-pattern heading`` with a log that has no heading_deg column: one
    line naming the log and the column, nothing written."""
    toml = tiny_scenario().to_toml(tmp_path / "s.toml")
    rng = np.random.default_rng(1)
    rows = ["x_m,y_m,alt_m,cell,rss_dbm"] + [
        f"{rng.uniform(20, 380):.1f},{rng.uniform(20, 380):.1f},100,0,{-70 + rng.normal():.1f}"
        for _ in range(200)
    ]
    log = tmp_path / "nohead.csv"
    log.write_text("\n".join(rows) + "\n")
    out = tmp_path / "o"
    rc, err = run_cli(radiomap, ["--config", toml, "--measurements", log, "--receive-pattern",
                                 "heading", "--out", out], capsys)  # fmt: skip
    refused("--receive-pattern heading without headings", rc, err, "nohead.csv", "heading_deg")
    assert not (out / "radiomap.npz").exists()


def test_the_corpus_totals(capsys) -> None:
    total = sum(TALLY.values())
    with capsys.disabled():
        print(
            f"\nhostile-input corpus: {total} inputs tried, {TALLY['refused']} cleanly refused, "
            f"{TALLY['accepted']} rightly accepted, 0 tracebacks, 0 hangs, 0 silent wrong results"
        )
    # Every probe that ran ended as one of the two (a traceback, hang or wrong result fails
    # its own test before this one); with the whole module run, the corpus is this size.
    assert set(TALLY) <= {"refused", "accepted"}
    if total:
        assert TALLY["refused"] > 0


@pytest.mark.parametrize(
    "record",
    [
        {"cell": 0},
        {"cell": 0, "length_m": "x", "amplitude_db": 1, "noise_db": 1},
        {"cell": 0, "length_m": -5, "amplitude_db": 1, "noise_db": 1},
        {
            "cell": 0,
            "length_m": 5,
            "amplitude_db": 1,
            "noise_db": 1,
            "components": [{"amplitude_db": "x", "east_m": 5, "north_m": 5}],
        },
        {
            "cell": 0,
            "length_m": 5,
            "amplitude_db": 1,
            "noise_db": 1,
            "components": [{"amplitude_db": 1, "east_m": -5, "north_m": 5}],
        },
    ],
)
def test_a_crafted_residual_record_is_refused_by_the_path_draw(record) -> None:
    """A map handed over may carry any ``fit_json``: a residual record without its numbers, or
    with a negative length, is one line from ``path_outage_draws``, not a KeyError."""
    import dataclasses

    from rainuav.radio.measured.outage import path_outage_draws

    rm = synthetic_map()
    crafted = dataclasses.replace(rm, fit={"residual": [record]},
                                  prior_rss_dbm=np.asarray(rm.rss_dbm, dtype=float))  # fmt: skip
    px = (np.array([1, 2]), np.array([3, 4]))
    api_refused("a crafted residual", lambda: path_outage_draws(crafted, px, 0.0, draws=20),
                "residual of cell 0")  # fmt: skip
