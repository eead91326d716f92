"""The ray engine's building physics against Sionna RT 2.2, a full ray tracer
([`rainuav.radio.tracer`][rainuav.radio.tracer]), on small scenes
([`rainuav.radio.tracer_scenes`][rainuav.radio.tracer_scenes]: one block, a thick building, a
street canyon of two rows, an L-shaped building, nine buildings from the shipped footprint
file): the building effect (the map with the buildings
minus the map without, dB, each method against itself) on the pixels the tracer covers, isotropic
antennas on both sides, vertical and horizontal polarisation, no ground and a PEC ground by the
image method. The tracer runs 4 million rays a site on the CPU (LLVM), seeded; its own Monte Carlo
noise, from two halves of its rays, is 0.2-1.0 dB (median over the shadows), and pixels where its
halves differ by more than 6 dB are left out.

Tolerances and why:

- **Light** (the tracer's building effect above -6 dB): within 0.5 dB median, and shadow and
  light agree on 95% of the pixels or more (the targets).
- **Shadow**, horizontal polarisation: within 4 dB median and 11 dB at the 90th percentile
  (measured 1.8-3.8 dB and 5.8-10.7 dB: the targets are 3 and 8 dB; the canyon's and the PEC
  ground's cases are the farthest, with 1 dB of margin for the tracer's noise).
- **Shadow**, vertical polarisation: within 6 dB median (box, thick, corner, the footprints) and
  11 dB (the canyon), 90th percentile within 13 and 19 dB (measured 1.9-5.5 dB median and
  5.8-11.2 dB p90; the canyon 8.7 and 14.5 dB). The engine's shadows are deeper: the field along
  a vertical edge is soft, and near a wall the UTD coefficient of ITU-R P.526 vanishes as the exact
  wedge solution does (``tests/test_wedge_exact.py``, 0.1 dB), where the tracer's does not (a
  perfectly conducting block, 1.3 degrees off its wall: the tracer -123.7 dB, the exact soft wedge
  -143.2 dB; the tracer gives vertical and horizontal polarisation within 2 dB of each other where
  the exact solutions differ by 25 dB). A side street seen only along its walls is where this shows
  most (the canyon). Before corners diffracted, the box's shadows were 13.8 dB too deep (median).
"""

from __future__ import annotations

import pytest
from rainuav.radio.tracer import compare
from rainuav.radio.tracer_scenes import TEST_SCENES, scene

pytestmark = [pytest.mark.timeout(600), pytest.mark.slow]

SAMPLES = 4_000_000
ALTITUDE = {"box": 20.0, "thick": 10.0, "canyon": 20.0, "corner": 20.0, "block": 8.0}
CASES = [(s, pol, "none") for s in TEST_SCENES for pol in ("v", "h")] + [
    ("box", "v", "pec"),
    ("canyon", "h", "pec"),
]


@pytest.fixture(scope="module")
def agreements() -> dict[tuple[str, str, str], dict[str, float]]:
    out = {}
    for name, pol, ground in CASES:
        a = compare(scene(name, 4.9e9, ALTITUDE[name], pol), samples=SAMPLES, ground=ground)
        out[(name, pol, ground)] = a.rows()[0]
    return out


@pytest.mark.parametrize("case", CASES, ids=["-".join(c) for c in CASES])
def test_where_the_tracer_sees_light_the_engine_does(agreements, case) -> None:
    r = agreements[case]
    assert r["pixels"] > 1000 and r["shadow_pixels"] > 300, r
    assert r["light_median"] <= 0.5, r
    assert r["classes_agree"] >= 0.95, r


SHADOW_TOLERANCE = {  # (median, p90), dB: the module docstring says why
    "h": {s: (4.0, 11.0) for s in TEST_SCENES},
    "v": {**{s: (6.0, 13.0) for s in TEST_SCENES}, "canyon": (11.0, 19.0)},
}


@pytest.mark.parametrize("case", CASES, ids=["-".join(c) for c in CASES])
def test_where_the_tracer_sees_a_shadow_the_engine_is_within_tolerance(agreements, case) -> None:
    name, pol, _ = case
    r = agreements[case]
    med, p90 = SHADOW_TOLERANCE[pol][name]
    assert r["shadow_median"] <= med, r
    assert r["shadow_p90"] <= p90, r
    # The tracer's own noise is well below the tolerance it is held to.
    assert r["noise_median"] <= 1.5, r
