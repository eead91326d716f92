"""The ray engine's building effect against Sionna RT 2.2's path solver at the pixel centres
([`rainuav.radio.reference.tracer_paths`][rainuav.radio.reference.tracer_paths]): the tracer's
exact paths, where its radio map (``tests/test_tracer.py``) is a Monte Carlo estimate that is dark
and scattered in deep shadows. Three test scenes, one mechanism each: a street canyon (walls
once and twice, corners, the corners beside the line), a thick building seen over its roof at
10 m (the roof's edges), and a block over a PEC ground by images (the ground). Every third pixel
in both directions, 1 million candidate rays a site in two seeded halves.

Tolerances and why: the issue's targets, unloosened: where the tracer sees a shadow, within 3 dB
at the median and 8 dB at the 90th percentile; where it sees light, 0.5 dB at the median; shadow
and light agree on 95% of the pixels. Measured on these cases (Intel Xeon, 2 cores): canyon V
0.46 / 2.03 dB, thick H 2.60 / 6.97 dB, block V over PEC 2.65 / 3.29 dB (shadow median / p90);
light at most 0.005 dB; all pixels agree. The two halves of the candidate search find the same
paths here (their difference is 0.00 dB at the median); the test holds it under 0.5 dB. What
remains is known: the thick building's roof edges are knife edges in the engine and right-angled
wedges in the tracer (the engine 1.9 dB brighter), and over the PEC ground the engine's corners
are lit by the site alone, not by its image in the ground as well (2.5 dB darker).
"""

from __future__ import annotations

import pytest
from rainuav.radio.reference.comparison import compare
from rainuav.radio.reference.tracer_scenes import scene

pytestmark = [pytest.mark.timeout(600), pytest.mark.slow]

CASES = [("canyon", "v", 20.0, "none"), ("thick", "h", 10.0, "none"), ("box", "v", 20.0, "pec")]


@pytest.mark.parametrize("case", CASES, ids=[f"{n}-{p}-{g}" for n, p, _, g in CASES])
def test_the_engine_meets_the_targets_against_the_tracers_exact_paths(case) -> None:
    name, pol, alt, ground = case
    r = compare(
        scene(name, 4.9e9, alt, pol), samples=1_000_000, ground=ground, reference="paths", step=3
    ).rows()[0]
    assert r["pixels"] > 250 and r["shadow_pixels"] > 60, r
    assert r["light_median"] <= 0.5, r
    assert r["classes_agree"] >= 0.95, r
    assert r["shadow_median"] <= 3.0, r
    assert r["shadow_p90"] <= 8.0, r
    # Two candidate searches found the same paths: the reference is not noisy.
    assert r["noise_median"] <= 0.5, r


def test_a_reference_other_than_the_map_or_the_paths_is_refused() -> None:
    with pytest.raises(ValueError, match="reference is 'map' or 'paths'"):
        compare(scene("box"), reference="pathz")
    from rainuav.radio.reference.tracer import isotropic_scenario
    from rainuav.radio.reference.tracer_paths import path_gain

    with pytest.raises(ValueError, match="step is a whole number"):
        path_gain(isotropic_scenario(scene("box")), step=0)
