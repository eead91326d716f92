"""Every CLI answers a missing or malformed file with one line naming the file and the
problem, and exit code 2; never a traceback."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from rainuav import evaluate, radiomap, train

MALFORMED = "seed = 1\n[dqn\nlr = 0.1\n"


@pytest.fixture
def files(tmp_path: Path) -> dict[str, Path]:
    bad = tmp_path / "bad.toml"
    bad.write_text(MALFORMED)
    return {"missing": tmp_path / "missing.toml", "malformed": bad, "dir": tmp_path}


@pytest.mark.parametrize(
    ("cli", "args", "kind", "needle"),
    [
        (train, ["--config", "{missing}"], "missing", "no such file"),
        (train, ["--config", "{malformed}"], "malformed", "not valid TOML"),
        (train, ["--scenario-file", "{missing}", "--out", "{dir}/run"], "missing", "no such file"),
        (train, ["--scenario-file", "{malformed}", "--out", "{dir}/run"], "malformed", "TOML"),
        (radiomap, ["--config", "{missing}"], "missing", "no such file"),
        (radiomap, ["--config", "{malformed}"], "malformed", "not valid TOML"),
        (evaluate, ["{missing}"], "missing", "missing config.toml"),
    ],
)
def test_cli_names_the_bad_file_and_exits_2(files, capsys, cli, args, kind, needle) -> None:
    argv = [a.format(**{k: str(v) for k, v in files.items()}) for a in args]
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("error: ") and needle in lines[0], err
    assert files[kind].name in lines[0], err


def test_wrongly_typed_config_field_is_named(tmp_path: Path, capsys) -> None:
    cfg = tmp_path / "run.toml"
    cfg.write_text('seed = "zero"\n[dqn]\nepisodes = 3\n')
    assert train.main(["--config", str(cfg), "--out", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "seed" in err, err


@pytest.mark.slow
def test_python_dash_m_prints_no_traceback(tmp_path: Path) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "rainuav.train", "--config", str(tmp_path / "missing.toml")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert proc.stderr.strip() == f"error: config file {tmp_path / 'missing.toml'}: no such file"
