"""Milliseconds per step of a march at the `paper` preset's largest grid (2500 x 1296, pec-h,
wide-angle, 20 steps, best of 3), for A/B comparisons of two builds of the extension module
in one run of the machine: ``python benches/pe_step.py`` under each (BENCHMARKS.md, "PE step"). Two
lines: the general step (the lateral window every step) and the uniform-medium path with the
lateral window every 7 steps, as the radio-map engine runs that grid."""

from __future__ import annotations

import time

import numpy as np
from rainuav import pwe


def main() -> None:
    nx, ny, steps = 2500, 1296, 20
    rng = np.random.default_rng(0)
    u0 = (rng.standard_normal((nx, ny)) + 1j * rng.standard_normal((nx, ny))).astype(np.complex64)
    for every in (1, 7):
        best = float("inf")
        for _ in range(3):
            t = time.perf_counter()
            pwe.march(
                u0.copy(), dx_m=0.22, dy_m=0.137, dz_m=10.0, steps=steps, freq_hz=4.9e9,
                propagator="wide", ground="pec-h", absorber=0.15, record_rows=[700, 701],
                x_absorber_every=every,
            )  # fmt: skip
            best = min(best, time.perf_counter() - t)
        print(f"{nx} x {ny}, pec-h, x_absorber_every={every}: {best / steps * 1e3:.1f} ms per step")


if __name__ == "__main__":
    main()
