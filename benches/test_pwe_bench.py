"""The split-step march: rainuav.pwe.march against plain numpy/scipy.fft and FFTW (pyfftw)
marches of the same step, complex64, two threads each, in the same run.

The step in all three: ``u <- s * IFFT2[P * FFT2[u]]`` with the wide-angle propagator table
``P`` and a homogeneous-rain phase screen ``s`` (a scalar), 30 steps per round. rainuav's
time includes building its propagator table; the references' tables are built outside it.
Run: ``make bench``; results in BENCHMARKS.md.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.fft as sfft
from rainuav import medium, pwe

F_HZ = 4.9e9
K0 = 2 * np.pi * F_HZ / 299_792_458.0
D, DZ, STEPS = 0.05, 1.0, 30
SIZES = [(2048, 1024), (4096, 1024)]


def setup(nx: int, ny: int):
    u0 = pwe.gaussian_beam(
        nx, ny, D, D, freq_hz=F_HZ, height_m=ny * D / 2, elevation_deg=2.0, beamwidth_deg=4.333
    )
    n = complex(medium.effective_index(F_HZ, 25.0))
    kx = 2 * np.pi * np.fft.fftfreq(nx, D)[:, None]
    ky = 2 * np.pi * np.fft.fftfreq(ny, D)[None, :]
    k2 = kx**2 + ky**2
    kz = np.sqrt(np.maximum(K0**2 - k2, 0.0))
    prop = np.where(
        k2 <= K0**2,
        np.exp(1j * k2 / (K0 + kz) * DZ),
        np.exp(1j * K0 * DZ) * np.exp(-np.sqrt(np.maximum(k2 - K0**2, 0.0)) * DZ),
    ).astype(np.complex64)
    screen = np.complex64(np.exp(-1j * K0 * (n * n - 1) * DZ / 2))
    return u0, n, prop, screen


def scipy_march(u0, prop, screen):
    u = u0.copy()
    for _ in range(STEPS):
        u = sfft.fft2(u, workers=2, overwrite_x=True)
        u *= prop
        u = sfft.ifft2(u, workers=2, overwrite_x=True)
        u *= screen
    return u


def rainuav_march(u0, n):
    return pwe.march(u0, dx_m=D, dy_m=D, dz_m=DZ, steps=STEPS, freq_hz=F_HZ, n=n).field


@pytest.mark.parametrize(("nx", "ny"), SIZES)
def test_references_agree(nx, ny) -> None:
    u0, n, prop, screen = setup(nx, ny)
    ours = rainuav_march(u0, n)
    ref = scipy_march(u0, prop, screen)
    # Same step in complex64 both ways: 1e-4 relative L2 after 30 steps.
    assert np.linalg.norm(ours - ref) / np.linalg.norm(ref) < 1e-4


@pytest.mark.parametrize(("nx", "ny"), SIZES)
def test_bench_pe_rainuav(benchmark, nx, ny) -> None:
    u0, n, _, _ = setup(nx, ny)
    benchmark.pedantic(rainuav_march, args=(u0, n), rounds=5, iterations=1, warmup_rounds=1)


@pytest.mark.parametrize(("nx", "ny"), SIZES)
def test_bench_pe_scipy_fft(benchmark, nx, ny) -> None:
    u0, _, prop, screen = setup(nx, ny)
    benchmark.pedantic(
        scipy_march, args=(u0, prop, screen), rounds=5, iterations=1, warmup_rounds=1
    )


@pytest.mark.parametrize(("nx", "ny"), SIZES)
def test_bench_pe_fftw(benchmark, nx, ny) -> None:
    pyfftw = pytest.importorskip("pyfftw")
    u0, _, prop, screen = setup(nx, ny)
    buf = pyfftw.empty_aligned((nx, ny), dtype="complex64")
    fwd = pyfftw.FFTW(buf, buf, axes=(0, 1), threads=2, flags=("FFTW_MEASURE",))
    inv = pyfftw.FFTW(
        buf, buf, axes=(0, 1), direction="FFTW_BACKWARD", threads=2, flags=("FFTW_MEASURE",)
    )

    def run():
        buf[:] = u0
        for _ in range(STEPS):
            fwd()
            np.multiply(buf, prop, out=buf)
            inv()  # pyfftw normalises the backward transform by 1/N
            np.multiply(buf, screen, out=buf)
        return buf

    out = run().copy()
    ref = scipy_march(u0, prop, screen)
    assert np.linalg.norm(out - ref) / np.linalg.norm(ref) < 1e-4
    benchmark.pedantic(run, rounds=5, iterations=1, warmup_rounds=1)
