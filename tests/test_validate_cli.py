"""`python -m rainuav.validate rain` writes the figure and the table it promises."""

from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from rainuav import medium


@pytest.mark.slow
def test_validate_rain_cli(tmp_path: Path) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "rainuav.validate", "rain", "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        check=True,
        env={"MPLBACKEND": "Agg", "PATH": ""},
    )
    assert "ITU-R P.838-3 H" in proc.stdout
    png = tmp_path / "rain_attenuation.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with (tmp_path / "rain_attenuation.csv").open() as fh:
        rows = list(csv.reader(fh))
    header, body = rows[0], np.array(rows[1:], dtype=float)
    assert len(body) == 200
    # The CSV holds what the library computes (written with 7 significant digits).
    f_hz = body[:, 0] * 1e9
    col = header.index("forward-scattering V [dB/km]")
    want = medium.specific_attenuation(f_hz, 12.5, polarization="v")
    np.testing.assert_allclose(body[:, col], want, rtol=1e-5)
    col = header.index("ITU-R P.838-3 H [dB/km]")
    np.testing.assert_allclose(body[:, col], medium.itu_p838(f_hz, 12.5), rtol=1e-5)
    # No temporary files left behind by the atomic writes.
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "rain_attenuation.csv",
        "rain_attenuation.png",
    ]
