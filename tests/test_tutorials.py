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


def _run(script: str, *args: str, timeout: int) -> str:
    proc = subprocess.run(
        [sys.executable, str(TUTORIALS / script), "--small", *args],
        capture_output=True, text=True, timeout=timeout, cwd=ROOT,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "Traceback" not in proc.stderr
    return proc.stdout


@pytest.mark.slow
def test_a_radio_map_of_your_network_in_rain(tmp_path: Path) -> None:
    out = _run("radiomap_in_rain.py", "--out", str(tmp_path), timeout=240)
    assert (tmp_path / "radiomap_in_rain.png").stat().st_size > 10_000
    assert "clear air: SINR median" in out and "50 mm/h: SINR median" in out


@pytest.mark.slow
def test_train_evaluate_and_fly_a_policy(tmp_path: Path) -> None:
    _run("train_evaluate_fly.py", "--out", str(tmp_path), timeout=290)
    storms = tmp_path / "storms"
    assert (storms / "metrics.json").exists() and (storms / "checkpoint.pt").exists()
    ev = json.loads((storms / "eval_storms_1000000-1000000" / "evaluation.json").read_text())
    assert "mean" in ev
    summary = json.loads((tmp_path / "flight" / "summary.json").read_text())
    assert summary["flown_by"].startswith("network")
    assert (tmp_path / "flight" / "mission.plan").exists()
