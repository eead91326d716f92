"""The documentation's tutorials run end to end, as scripts, on a small budget (``--small``):
they finish and write what the pages say they write. The published figures come from their
full budgets (``docs/tutorials/*.md``)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TUTORIALS = ROOT / "docs" / "tutorials"
QUIET_S = {"radiomap_in_rain.py": 5, "train_evaluate_fly.py": 45}
"""Each tutorial's wall time with ``--small`` on an idle 2-core machine, rounded up (measured:
1.6 s and 24-44 s, with an empty map cache)."""
HANG_FACTOR = 12
"""A tutorial counts as hung past this multiple of its quiet time (a load of 7-10 on 2 cores
made the second 6.6 times slower than quiet and more): time limits catch hangs, not slowness."""


def _limit(script: str) -> int:
    return HANG_FACTOR * QUIET_S[script]


def _run(script: str, *args: str) -> str:
    proc = subprocess.run(
        [sys.executable, str(TUTORIALS / script), "--small", *args],
        capture_output=True, text=True, timeout=_limit(script), cwd=ROOT,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "Traceback" not in proc.stderr
    return proc.stdout


@pytest.mark.slow
@pytest.mark.timeout(_limit("radiomap_in_rain.py") + 60)
def test_a_radio_map_of_your_network_in_rain(tmp_path: Path) -> None:
    out = _run("radiomap_in_rain.py", "--out", str(tmp_path))
    assert (tmp_path / "radiomap_in_rain.png").stat().st_size > 10_000
    assert "clear air: SINR median" in out and "50 mm/h: SINR median" in out


@pytest.mark.slow
@pytest.mark.timeout(_limit("train_evaluate_fly.py") + 60)
def test_train_evaluate_and_fly_a_policy(tmp_path: Path) -> None:
    _run("train_evaluate_fly.py", "--out", str(tmp_path))
    storms = tmp_path / "storms"
    assert (storms / "metrics.json").exists() and (storms / "checkpoint.pt").exists()
    ev = json.loads((storms / "eval_storms_1000000-1000000" / "evaluation.json").read_text())
    assert "mean" in ev
    summary = json.loads((tmp_path / "flight" / "summary.json").read_text())
    assert summary["flown_by"].startswith("network")
    assert (tmp_path / "flight" / "mission.plan").exists()
