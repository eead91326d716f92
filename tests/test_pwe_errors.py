"""Bad input to the PE gets a ValueError naming the argument; Ctrl-C stops a march."""

from __future__ import annotations

import re
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
import rainuav
from rainuav import pwe

U0 = np.ones((16, 16), dtype=np.complex64)
GOOD = {"dx_m": 0.1, "dy_m": 0.1, "dz_m": 1.0, "steps": 2, "freq_hz": 4.9e9}


@pytest.mark.parametrize(
    ("change", "needle"),
    [
        ({"u0": np.full((16, 16), np.nan)}, "u0"),
        ({"u0": np.full((16, 16), np.inf, dtype=complex)}, "u0"),
        ({"u0": np.ones(16)}, "u0"),
        ({"u0": np.ones((2, 16))}, "nx"),
        ({"dx_m": 0.0}, "dx_m"),
        ({"dy_m": -1.0}, "dy_m"),
        ({"dz_m": np.nan}, "dz_m"),
        ({"steps": 0}, "steps"),
        ({"steps": 1.5}, "steps"),
        ({"freq_hz": -1.0}, "freq_hz"),
        ({"propagator": "paraxial"}, "propagator"),
        ({"ground": "pec"}, "ground"),
        ({"absorber": 0.6}, "absorber"),
        ({"absorber": np.nan}, "absorber"),
        ({"x_absorber_every": 0}, "x_absorber_every"),
        ({"x_absorber_every": 65}, "x_absorber_every"),
        ({"x_absorber_every": 2.5}, "x_absorber_every"),
        ({"record_rows": [16]}, "record_rows"),
        ({"record_column": -1}, "record_column"),
        ({"n": np.ones((3, 3))}, "n"),
        ({"n": np.nan}, "n"),
        ({"n": np.full((16, 16), np.nan)}, "n"),
        ({"obstacles": np.ones((3, 3), dtype=bool)}, "obstacles"),
        ({"obstacles": np.full(16, np.nan)}, "obstacles"),
        ({"obstacles": lambda s: np.ones((3, 3), dtype=bool)}, "obstacles"),
        ({"n": lambda s: np.ones((4, 4))}, "n(0)"),
    ],
)
def test_bad_input(change, needle) -> None:
    kw = {"u0": U0, **GOOD, **change}
    u0 = kw.pop("u0")
    with pytest.raises(ValueError, match=re.escape(needle)) as info:
        pwe.march(u0, **kw)
    assert isinstance(info.value, rainuav.InvalidInputError)


def test_grid_too_large_is_refused_with_the_number() -> None:
    # 10^6 steps x 4096 samples x 8 bytes of recording = 33 GB > this machine's memory.
    u0 = np.zeros((4096, 8), dtype=np.complex64)
    with pytest.raises(rainuav.InvalidInputError, match=r"needs \d+\.\d+ GB"):
        pwe.march(u0, **{**GOOD, "steps": 1_000_000}, record_rows=[0])


def test_gaussian_beam_bad_input() -> None:
    with pytest.raises(rainuav.InvalidInputError, match="beamwidth_deg"):
        pwe.gaussian_beam(8, 8, 0.1, 0.1, freq_hz=5e9, height_m=0, elevation_deg=0, beamwidth_deg=0)
    with pytest.raises(rainuav.InvalidInputError, match="dx_m"):
        pwe.gaussian_beam(8, 8, 0.0, 0.1, freq_hz=5e9, height_m=0, elevation_deg=0, beamwidth_deg=5)
    with pytest.raises(rainuav.InvalidInputError, match="nx"):
        pwe.gaussian_beam(2, 8, 0.1, 0.1, freq_hz=5e9, height_m=0, elevation_deg=0, beamwidth_deg=5)
    with pytest.raises(rainuav.InvalidInputError, match="gain_db"):
        pwe.pattern_source(
            8,
            8,
            0.1,
            0.1,
            freq_hz=5e9,
            height_m=0,
            azimuth_deg=[0, 1],
            elevation_deg=[0, 1],
            gain_db=np.zeros((3, 2)),
        )


@pytest.mark.slow
def test_ctrl_c_stops_a_long_march_within_a_second() -> None:
    # The child is started with SIGINT ignored, as a job started in the background by a
    # non-interactive shell is (it inherits SIG_IGN); it must install Python's handler itself
    # to be interruptible, and the test kills it rather than wait forever.
    script = (
        "import signal, sys\n"
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "import numpy as np\n"
        "from rainuav import pwe\n"
        "u = np.ones((512, 512), dtype=np.complex64)\n"
        "print('ready', flush=True)\n"
        "try:\n"
        "    pwe.march(u, dx_m=0.1, dy_m=0.1, dz_m=1.0, steps=10**6, freq_hz=5e9)\n"
        "except KeyboardInterrupt:\n"
        "    print('interrupted', flush=True); sys.exit(3)\n"
    )
    proc = subprocess.Popen(
        [sys.executable, "-c", script],
        stdout=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN),
    )
    try:
        assert proc.stdout is not None
        assert proc.stdout.readline().strip() == "ready"
        time.sleep(1.5)  # well into the march
        t0 = time.monotonic()
        proc.send_signal(signal.SIGINT)
        rc = proc.wait(timeout=10)
        elapsed = time.monotonic() - t0
        assert rc == 3
        assert "interrupted" in proc.stdout.read()
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.wait()
        if proc.stdout is not None:
            proc.stdout.close()
    assert elapsed < 1.0, elapsed
