"""The per-cell loop on threads (`rainuav._threads.each`): every round runs once, an error is
raised to the caller, and a ray map built through it is the map of its cells built one at a
time (bit for bit)."""

from __future__ import annotations

import numpy as np
import pytest
from rainuav._threads import each
from rainuav.radio.engines.ray_engine import ray_gains
from rainuav.radio.scene import presets
from rainuav.radio.scene.cell import gain_linear


def test_every_round_runs_once_and_errors_reach_the_caller() -> None:
    out = np.zeros(50)

    def body(k: int) -> None:
        out[k] += k + 1

    each(50, body)
    assert np.array_equal(out, np.arange(1, 51))

    def bad(k: int) -> None:
        if k == 7:
            raise ValueError("round 7")

    with pytest.raises(ValueError, match="round 7"):
        each(10, bad)


def test_gains_on_threads_are_the_gains_cell_by_cell() -> None:
    scn = presets.uma(engine="ray")
    jobs = [(s, c) for s in scn.sites for c in s.cells]
    x, y = scn.area.centres()
    rng = np.random.default_rng(0)
    dirs = [
        (rng.uniform(-180, 180, (y.size, x.size)), rng.uniform(-90, 90, (y.size, x.size)),
         rng.uniform(-90, 90, (y.size, x.size)))
        for _ in jobs
    ]  # fmt: skip
    gd, gr = ray_gains(scn, jobs, x, y, dirs)
    for m, ((_, cell), (az, el_d, el_r)) in enumerate(zip(jobs, dirs, strict=True)):
        assert np.array_equal(gd[m], gain_linear(cell, az, el_d))
        assert np.array_equal(gr[m], gain_linear(cell, az, el_r))
