"""The ray engine's building effect against Sionna RT 2.2's path solver at the pixel centres
([`rainuav.radio.reference.tracer_paths`][rainuav.radio.reference.tracer_paths]): the tracer's
exact paths, where its radio map (``tests/test_tracer.py``) is a Monte Carlo estimate that is
dark and scattered in deep shadows. Four test scenes, one mechanism each: a street canyon (walls
once and twice, corners, the corners beside the line, walls then corners), a thick building seen
over its roof at 10 m (the roof's edges), nine buildings of the shipped footprint file (their
materials), and a block over a PEC ground by images (the ground). Two more tests follow one path
each: a wall then a corner beside the line (`urban`), a wall's reflection over a roof
(`roof_wall`). Every third pixel in both directions, candidate rays a site in two seeded halves:
1 million among the nine buildings, 400 000 in the other scenes (where 1 million gives the same
paths: every figure below to 0.004 dB; among the nine buildings 400 000 reach fewer pixels).

Tolerances and why. Without a ground the engine and the path solver trace the same mechanisms (walls
once and twice, corners and walls then corners with P.526-15 section 6's wedge, roofs' edges as
wedges), so the shadow's median is held to 1 dB; its 90th percentile to the issue's 8 dB, because at
every third pixel it rests on 7-20 pixels, and those beside the thick building, whose paths cross
the side of its roof obliquely (the engine takes a roof's edge across the path), reach 6.3 dB.
Measured here (Intel Xeon, 2 cores): canyon V 0.18 / 1.21 dB (0.36 / 2.05 dB before the corners
beside the line were lit by walls), thick H 0.14 / 6.32 dB, block H 0.19 / 2.87 dB (median / p90);
at every second pixel all ten cases without ground of ``tests/test_tracer.py`` give 0.00-0.27 dB and
0.1-2.7 dB. Over the PEC ground the engine lights its corners from the site alone, not also from its
image in the ground, and is 2.7 dB darker at the median: that case is held to the issue's targets, 3
dB and 8 dB (measured 2.70 and 3.25 dB). The light is held to 0.5 dB at the median and shadow and
light to 95% agreement (measured at most 0.01 dB and 99.7% or more). The two halves of the candidate
search find the same paths here (0.00 dB apart at the median); the test holds them within 0.5 dB."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from rainuav.radio.reference.comparison import compare, reference_maps
from rainuav.radio.reference.saved import load_tracer_maps
from rainuav.radio.reference.tracer_scenes import PATH_CASES, TEST_ALTITUDE_M, case_key, scene

pytestmark = [pytest.mark.timeout(600), pytest.mark.slow]

TRUTH = Path(__file__).resolve().parent / "tracer_paths_truth.npz"
"""The path solver's maps of ``PATH_CASES``, with and without the buildings (tracing them takes
about 55 s): ``python experiments/tracer_references.py``. The last test traces one case again
and holds the file to it."""


def _saved(name: str, pol: str, ground: str) -> tuple:
    maps = load_tracer_maps(TRUTH)
    key = case_key(name, pol, ground)
    return maps[key], maps[f"{key}-open"]


@pytest.mark.parametrize("case", PATH_CASES, ids=[case_key(*c[:3]) for c in PATH_CASES])
def test_the_engine_meets_the_targets_against_the_tracers_exact_paths(case) -> None:
    name, pol, ground, samples = case
    scn = scene(name, 4.9e9, TEST_ALTITUDE_M[name], pol)
    traced = _saved(name, pol, ground)
    r = compare(
        scn, samples=samples, ground=ground, reference="paths", step=3, traced=traced
    ).rows()[0]
    assert r["pixels"] > 250 and r["shadow_pixels"] > 60, r
    assert r["light_median"] <= 0.5, r
    assert r["classes_agree"] >= 0.95, r
    med, p90 = (3.0, 8.0) if ground == "pec" else (1.0, 8.0)  # the docstring says why
    assert r["shadow_median"] <= med, r
    assert r["shadow_p90"] <= p90, r
    # Two candidate searches found the same paths: the reference is not noisy.
    assert r["noise_median"] <= 0.5, r


def test_a_reference_other_than_the_map_or_the_paths_is_refused() -> None:
    with pytest.raises(ValueError, match="reference is 'map' or 'paths'"):
        compare(scene("box"), reference="pathz")
    from rainuav.radio.reference.tracer import isotropic_scenario
    from rainuav.radio.reference.tracer_paths import path_gain

    with pytest.raises(ValueError, match="step is a whole number"):
        path_gain(isotropic_scenario(scene("box")), step=0)
    with pytest.raises(ValueError, match="runs is an even number"):
        path_gain(isotropic_scenario(scene("box")), runs=3)
    from rainuav.radio.reference.tracer_paths import path_gain_by_kind

    with pytest.raises(TypeError, match="unknown arguments"):
        path_gain_by_kind(isotropic_scenario(scene("box")), sample=10)
    with pytest.raises(ValueError, match="step is a whole number"):
        path_gain_by_kind(isotropic_scenario(scene("box")), step=0)


def test_a_wall_then_a_corner_beside_the_line_lights_a_street() -> None:
    # `urban` with the UAV 40 m below its roofs, site 3 (1000, 333.3) at 3.5 GHz, V: the
    # street pixel (785, 825) is lit by the site's image in the wall x = 800 of one block, which
    # sees the corner (840, 740) of another block beside the straight line (the site itself does
    # not see that corner). The path solver finds -26.9 dB of building effect; the engine
    # without this path gave -54.3 dB. Both trace the same single path here, so the tolerance
    # is 1 dB (measured 0.1 dB). A coarse area (20 m pixels) whose every 13th pixel down the
    # column x = 785 holds the pixel: three receivers, two of them in line of sight (0 dB).
    from rainuav.radio.reference.tracer import engine_gain, isotropic_scenario
    from rainuav.radio.reference.tracer_paths import path_gain
    from rainuav.radio.scene.scenario import Area

    scn = scene("urban", 3.5e9, 40.0, "v")
    area = Area(775.0, 1015.0, 295.0, 855.0, altitude_m=40.0, resolution_m=20.0)
    scn = scn.replace(sites=[scn.sites[3]], area=area)
    w, wo = isotropic_scenario(scn), isotropic_scenario(scn, buildings=False)
    x, y = scn.area.centres()
    i, j = int(np.argmin(abs(y - 825.0))), int(np.argmin(abs(x - 785.0)))
    assert (x[j], y[i]) == (785.0, 825.0) and i % 13 == 0 and j % 13 == 0
    kw = {"samples": 1_000_000, "step": 13}
    ref = path_gain(w, **kw).gain[0, i, j] / path_gain(wo, **kw).gain[0, i, j]
    ours = engine_gain(w)[0, i, j] / engine_gain(wo)[0, i, j]
    ref_db, ours_db = 10 * np.log10(ref), 10 * np.log10(ours)
    assert -30.0 < ref_db < -24.0, ref_db  # the tracer's path is there
    assert abs(ours_db - ref_db) <= 1.0, (ours_db, ref_db)


def test_a_wall_seen_over_a_roof_reflects_into_its_shadow() -> None:
    # The `roof_wall` scene, 4.9 GHz, V, UAV at 10 m: behind a low block (roof 34 m) the direct
    # ray from the 40 m mast is deep in the roof's shadow, and a tall building's wall 90 m
    # beyond it reflects the mast's ray over the same roof, less deep (the unfolded path is
    # longer and passes higher over the roof). The path solver finds that path (one
    # diffraction, then one reflection). Against it, every third pixel, where it sees a
    # shadow: measured 0.03 dB median, 0.16 dB p90; the engine without the reflection over
    # the roof was 2-8 dB darker behind the block (median 3.18 dB). Tolerance 0.5 / 1.0 dB:
    # both trace the same two edges' paths here (the direct ray over the block, the wall's over
    # it), so what is left is the wedge coefficients' difference near grazing.
    scn = scene("roof_wall", 4.9e9, 10.0, "v")
    (row,) = compare(scn, samples=400_000, reference="paths", step=3).rows()
    assert row["shadow_pixels"] >= 40, row
    assert row["shadow_median"] <= 0.5 and row["shadow_p90"] <= 1.0, row
    assert row["light_median"] <= 0.1 and row["classes_agree"] == 1.0, row


@pytest.mark.parametrize("pol", ["v", "h"])
def test_a_roof_edge_beside_the_line_lights_a_deep_shadow(pol: str) -> None:
    # The `eave` scene, 4.9 GHz, UAV at 20 m: a 40 m block hides the street behind it from
    # the 30 m mast, 10-55 dB deep; beside the line a low building's roof edge (18 m), seen by
    # both ends from just above, diffracts into that shadow. The path solver's strongest path
    # there is that one diffraction (at (190, 2): -30.2 dB H, -45.8 dB V, of free space).
    # Measured, every third pixel, 46 shadow pixels: V 0.46 dB median, 2.72 dB p90; H 0.06 /
    # 4.32 dB. Without the roof edges beside the line the engine was 5.4 / 15.6 dB (V) and
    # 9.0 / 27.4 dB (H) off, darker. Tolerance 1.5 dB median, 6 dB p90: the shadow is deep
    # (-30 to -55 dB), where the blocking block's corners, its roof and the edge's oblique
    # rays (the field split into the edge's soft and hard parts, each face's coefficient at
    # the incident ray's angle with it) are all a few dB apart from the tracer's treatment of
    # the same paths.
    scn = scene("eave", 4.9e9, 20.0, pol)
    (row,) = compare(scn, samples=400_000, reference="paths", step=3).rows()
    assert row["shadow_pixels"] >= 40, row
    assert row["shadow_median"] <= 1.5 and row["shadow_p90"] <= 6.0, row
    assert row["light_median"] <= 0.1 and row["classes_agree"] == 1.0, row


def test_the_saved_paths_are_what_the_tracer_gives() -> None:
    """The thick building's case (the quickest) traced again, with and without the building:
    on the machine that wrote the file, on one thread, the same paths but for the file's
    float32. On another CPU the tracer's compiled code may round a grazing ray the other way,
    so the check is held to what that can move: the same pixels covered but 0.5%, and over the
    pixels both cover a median within 0.01 dB and a 99th percentile within 0.1 dB."""
    name, pol, ground, samples = next(c for c in PATH_CASES if c[0] == "thick")
    scn = scene(name, 4.9e9, TEST_ALTITUDE_M[name], pol)
    now = reference_maps(scn, samples=samples, ground=ground, reference="paths", step=3)
    for saved, traced in zip(_saved(name, pol, ground), now, strict=True):
        assert np.mean(saved.covered != traced.covered) <= 0.005
        c = saved.covered & traced.covered
        assert c.sum() > 250
        d = np.abs(10 * np.log10(saved.gain[c] / traced.gain[c]))
        assert np.median(d) <= 0.01 and np.quantile(d, 0.99) <= 0.1, (np.median(d), d.max())


def test_the_paths_split_by_kind_sum_to_the_paths_and_name_what_lights_a_shadow() -> None:
    """The path solver's power split by the kind of path (line of sight, reflections, a
    diffraction, both) sums to its whole at every pixel (to 1e-12 relative: the same union of
    the same runs); behind the thick building, where nothing is in sight, the power comes from
    diffracted paths, and a pixel in sight holds its line of sight."""
    from rainuav.radio.reference.tracer import isotropic_scenario
    from rainuav.radio.reference.tracer_paths import PATH_KINDS, path_gain, path_gain_by_kind

    scn = isotropic_scenario(scene("thick", 4.9e9, TEST_ALTITUDE_M["thick"], "h"))
    kw = {"samples": 100_000, "step": 8}
    kinds = path_gain_by_kind(scn, **kw)
    whole = path_gain(scn, **kw).gain
    assert set(kinds) == set(PATH_KINDS)
    total = sum(kinds.values())
    np.testing.assert_allclose(total, whole, rtol=1e-12, atol=0.0)
    seen = kinds["line of sight"] > 0
    dark = (whole > 0) & ~seen
    assert seen.sum() > 30 and dark.sum() > 5, (seen.sum(), dark.sum())
    diffracted = kinds["diffraction"] + kinds["reflections and a diffraction"]
    assert np.all(diffracted[dark] > 0.5 * whole[dark])
