"""The tracer's references of the building tests, traced once and saved as data.

    python experiments/tracer_references.py [--out tests]

Writes ``tracer_maps_truth.npz`` (Sionna RT's radio map of every case of
``rainuav.radio.reference.tracer_scenes.MAP_CASES``, 4 million rays a site, with and without
the buildings) and ``tracer_paths_truth.npz`` (its path solver at every third pixel's centre,
``PATH_CASES``), as released but for the wedge coefficient of ITU-R P.526-15 section 6 (the
project's default, ``rainuav.radio.reference.tracer_wedge``). ``tests/test_tracer.py`` and
``tests/test_tracer_paths.py`` read them and hold today's engine to them; each file has a test
that traces one case again and holds the file to the tracer. About 80 s on 2 cores."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from rainuav.radio.reference.comparison import reference_maps
from rainuav.radio.reference.saved import save_tracer_maps
from rainuav.radio.reference.tracer_scenes import (
    MAP_CASES,
    MAP_SAMPLES,
    PATH_CASES,
    TEST_ALTITUDE_M,
    case_key,
    scene,
)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=Path("tests"), help="the folder written to")
    args = ap.parse_args()
    t0 = time.perf_counter()
    maps = {}
    for name, pol, ground in MAP_CASES:
        scn = scene(name, 4.9e9, TEST_ALTITUDE_M[name], pol)
        with_b, without = reference_maps(scn, samples=MAP_SAMPLES, ground=ground)
        key = case_key(name, pol, ground)
        maps[key], maps[f"{key}-open"] = with_b, without
    save_tracer_maps(args.out / "tracer_maps_truth.npz", maps)
    paths = {}
    for name, pol, ground, samples in PATH_CASES:
        scn = scene(name, 4.9e9, TEST_ALTITUDE_M[name], pol)
        with_b, without = reference_maps(
            scn, samples=samples, ground=ground, reference="paths", step=3
        )
        key = case_key(name, pol, ground)
        paths[key], paths[f"{key}-open"] = with_b, without
    save_tracer_maps(args.out / "tracer_paths_truth.npz", paths)
    print(f"wrote {len(maps)} maps and {len(paths)} path maps in {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
