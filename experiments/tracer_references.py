"""The references of the building tests, computed once and saved as data.

    python experiments/tracer_references.py [--out tests]

Writes ``tracer_maps_truth.npz`` (Sionna RT's radio map of every case of
``rainuav.radio.reference.tracer_scenes.MAP_CASES``, 4 million rays a site, with and without
the buildings) and ``tracer_paths_truth.npz`` (its path solver at every third pixel's centre,
``PATH_CASES``), as released but for the wedge coefficient of ITU-R P.526-15 section 6 (the
project's default, ``rainuav.radio.reference.tracer_wedge``). ``tests/test_tracer.py`` and
``tests/test_tracer_paths.py`` read them and hold today's engine to them; each file has a test
that traces one case again and holds the file to the tracer. And ``wedge_fdfd.npz``: ceviche's
FDFD field (over free space's) around the reference corner
(``rainuav.radio.reference.wedge_fullwave.reference_corner``) of metal and of concrete, both
polarisations, which ``tests/test_wedge_fullwave.py`` reads (one case solved again there). About
two minutes on 2 cores."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from rainuav._io import write_atomic
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
    save_fdfd(args.out / "wedge_fdfd.npz")
    print(f"wrote {len(maps)} maps, {len(paths)} path maps and 4 full-wave fields in "
          f"{time.perf_counter() - t0:.0f} s")  # fmt: skip


def save_fdfd(path: Path) -> None:
    """The FDFD's field of the reference corner, metal and concrete, soft and hard."""
    from rainuav.radio.reference.wedge_fullwave import (
        REFERENCE_PHI_DEG,
        fdfd_total,
        reference_corner,
    )

    phi = np.radians(REFERENCE_PHI_DEG)
    fields = {f"{m}_{'soft' if soft else 'hard'}": fdfd_total(reference_corner(m), phi, soft)
              for m in ("metal", "concrete") for soft in (True, False)}  # fmt: skip

    def write(tmp: Path) -> None:
        with tmp.open("wb") as fh:
            np.savez_compressed(fh, phi_deg=REFERENCE_PHI_DEG, **fields)

    write_atomic(path, write)


if __name__ == "__main__":
    main()
