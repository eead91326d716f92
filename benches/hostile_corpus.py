"""The slow part of the hostile-input corpus (tests/test_hostile_inputs.py has the rest):
a real Ctrl-C (SIGINT to the whole process group, as a terminal sends it) during a map build,
a training and a study, and a long evaluation's progress.

    python benches/hostile_corpus.py [--skip-eval]

Each probe prints one line; the script ends with the totals and exits 1 if any probe ended in
a traceback, a hang or a wrong result. About four minutes on 2 cores.
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TINY_STUDY = """
name = "tiny"
seeds = [0]
compute = ["map", "optimal", "learned"]
eval_starts = 4
[base]
scenario = "uma"
engine = "ray"
"dqn.episodes" = 400
validate_every = 0
checkpoint_every = 50
[axes]
rain_rate_mm_h = [50.0, 100.0]
"""


def interrupt(argv: list[str], after_s: float, env: dict[str, str]) -> tuple[int, str, float]:
    """Starts ``python -m ...`` in its own process group, sends SIGINT to the group after
    ``after_s`` and returns (exit code, stderr, seconds from the signal to the exit)."""
    proc = subprocess.Popen(
        [sys.executable, "-m", *argv],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        start_new_session=True,
    )
    time.sleep(after_s)
    os.killpg(proc.pid, signal.SIGINT)
    t0 = time.perf_counter()
    try:
        _, err = proc.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        return -1, "hang: no exit within 120 s of Ctrl-C", 120.0
    return proc.returncode, err, time.perf_counter() - t0


def clean_stop(name: str, rc: int, err: str, waited: float, leftovers: list[Path]) -> bool:
    last = err.replace("\r", "\n").strip().splitlines()[-1:] or [""]
    ok = rc == 130 and "Traceback" not in err and last[0].startswith("interrupted: ")
    ok = ok and not leftovers
    verdict = "clean stop" if ok else "FAILED"
    print(f"{name}: exit {rc}, {waited:.1f} s after Ctrl-C, last line {last[0]!r}: {verdict}")
    if not ok:
        print(err[-2000:])
    return ok


def _ok(ok: bool) -> str:
    return "ok" if ok else "FAILED"


def half_written(folder: Path) -> list[Path]:
    return [p for p in folder.rglob("*.tmp")] if folder.exists() else []


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--skip-eval", action="store_true", help="leave out the 2000-start evaluation")
    args = ap.parse_args()
    results: list[bool] = []
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        env = {**os.environ, "RAINUAV_CACHE_DIR": str(d / "cache"), "MPLBACKEND": "Agg"}
        # A map build (the paper preset's PE marches take ~15 s).
        out = d / "maps"
        rc, err, waited = interrupt(
            ["rainuav.radiomap", "--scenario", "paper", "--no-cache", "--out", str(out)], 6, env
        )
        npz = [out / "radiomap.npz"] if (out / "radiomap.npz").exists() else []
        leftovers = [*half_written(out), *npz]
        results.append(clean_stop("map build", rc, err, waited, leftovers))
        # A training (its map built first, so the signal lands in training), then its resume.
        subprocess.run(
            [sys.executable, "-m", "rainuav.radiomap", "--scenario", "uma", "--out", str(d / "m")],
            check=True, capture_output=True, env=env, timeout=600,
        )  # fmt: skip
        run = d / "run"
        argv = ["rainuav.train", "--scenario", "uma", "--dqn.episodes", "600", "--out", str(run),
                "--checkpoint-every", "50"]  # fmt: skip
        rc, err, waited = interrupt(argv, 20, env)
        results.append(clean_stop("training", rc, err, waited, half_written(run)))
        resumed = subprocess.run(
            [sys.executable, "-m", *argv, "--resume", "--dqn.episodes", "600"],
            capture_output=True, text=True, env=env, timeout=900,
        )  # fmt: skip
        ok = resumed.returncode == 0 and (run / "metrics.json").exists()
        if not ok:
            print(resumed.stderr[-1500:])
        print(f"training resumed after Ctrl-C: exit {resumed.returncode}: {_ok(ok)}")
        results.append(ok)
        # A study with two worker processes.
        spec = d / "study.toml"
        spec.write_text(TINY_STUDY)
        sdir = d / "study"
        argv = ["rainuav.study", str(spec), "--out", str(sdir), "--workers", "2"]
        rc, err, waited = interrupt(argv, 20, env)
        results.append(clean_stop("study (2 workers)", rc, err, waited, half_written(sdir)))
        again = subprocess.run(
            [sys.executable, "-m", *argv], capture_output=True, text=True, env=env, timeout=900
        )
        ok = again.returncode == 0 and (sdir / "results.csv").exists()
        print(f"study resumed after Ctrl-C: exit {again.returncode}: {_ok(ok)}")
        results.append(ok)
        if not args.skip_eval:
            t0 = time.perf_counter()
            ev = subprocess.run(
                [sys.executable, "-m", "rainuav.evaluate", str(run), "--starts", "2000",
                 "--out", str(d / "ev")],
                capture_output=True, text=True, env=env, timeout=1800,
            )  # fmt: skip
            took = time.perf_counter() - t0
            ok = ev.returncode == 0 and "exact plans" in ev.stderr
            if not ok:
                print(ev.stderr[-1500:])
            print(f"evaluate --starts 2000 (two plan chunks): {took:.0f} s, progress: {ok}")
            results.append(ok)
    bad = results.count(False)
    print(f"slow corpus: {len(results)} probes, {len(results) - bad} as they should, {bad} not")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
