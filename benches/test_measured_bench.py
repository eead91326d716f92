"""A 200 x 200 map corrected by 5 000 and by 20 000 measurements (the target: at most 10 s on 2
cores).

The prior is ``uma`` at 28 GHz in clear air (ray engine, no ground, 10 m pixels); the truth the
``rain_cell`` preset over sites whose powers, tilts and azimuths are off by drawn amounts; the
log 2.5% of the pixels on five flight lines, the 5 strongest cells at each (5 000 rows, 2 dB
noise); and a log of 20 000 rows (ten lines, two samples a pixel, so the sample spread is seen).
Timed in the same run: the correction without and with its cross-validation, and, as the
reference doing the same work the plain way, the fitted residual fields evaluated by
scikit-learn at every pixel (``predict(..., return_std=True)``), which the correction replaces by
nodes every half length scale and bilinear between.

Run: ``python -m pytest benches/test_measured_bench.py --benchmark-enable --benchmark-only``
(or ``make bench``). Results go to BENCHMARKS.md."""

from __future__ import annotations

import numpy as np
import pytest
from rainuav.radio import Area, build_radio_map, presets
from rainuav.radio.measured import correct_map
from rainuav.radio.measured.calibrate import calibrate, calibrated_at
from rainuav.radio.measured.fitting import _fields
from rainuav.radio.measured.levels import prior_at
from rainuav.radio.measured.synthetic import perturbed_sites, sample_log

SHARE = 0.025  # 5 lines of 200 pixels x 5 cells = 5 000 rows


@pytest.fixture(scope="module")
def maps():
    """The prior and the truth (wrong sites in a rain cell) the logs are drawn from."""
    scn = presets.uma(0.0, 28e9, engine="ray", ground="none", area=Area(resolution_m=10.0))
    sites, _ = perturbed_sites(scn.sites, 1)
    truth = presets.rain_cell(5.0, 28e9, engine="ray", ground="none", area=scn.area, sites=sites)
    return build_radio_map(scn), build_radio_map(truth)


@pytest.fixture(scope="module")
def case(maps):
    prior, truth = maps
    log = sample_log(truth, SHARE, cells=5, seed=7)
    assert prior.rss_dbm.shape[1:] == (200, 200) and len(log) == 5000
    return prior, log


@pytest.fixture(scope="module")
def long_case(maps):
    prior, truth = maps
    log = sample_log(truth, 0.05, cells=5, seed=7, repeat=2)
    assert len(log) == 20000
    return prior, log


def test_correct_200x200_20000_rows(benchmark, long_case) -> None:
    prior, log = long_case
    benchmark.pedantic(lambda: correct_map(prior, log, cross_validate=False), rounds=2)


def test_correct_200x200_20000_rows_cross_validated(benchmark, long_case) -> None:
    prior, log = long_case
    benchmark.pedantic(lambda: correct_map(prior, log), rounds=1)


def test_correct_200x200_5000_rows(benchmark, case) -> None:
    prior, log = case
    benchmark.pedantic(lambda: correct_map(prior, log, cross_validate=False), rounds=3)


def test_correct_200x200_5000_rows_cross_validated(benchmark, case) -> None:
    prior, log = case
    benchmark.pedantic(lambda: correct_map(prior, log), rounds=2)


def test_reference_sklearn_every_pixel(benchmark, case) -> None:
    prior, log = case
    p = prior_at(prior, log)
    fits = calibrate(prior.scenario, log, p)
    fields = _fields(prior, log, log.rss_dbm - calibrated_at(prior.scenario, log, p, fits), 10, 0)
    gx, gy = np.meshgrid(prior.x_m, prior.y_m)
    pts = np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, prior.altitude_m)])

    def every_pixel() -> None:
        for f in fields.values():
            f.gp.predict(f._x(pts), return_std=True)

    benchmark.pedantic(every_pixel, rounds=2)
