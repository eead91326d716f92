"""Buildings from footprint files (docs/physics.md section 12): OpenStreetMap's height tags, roofs
that diffract as a profile (against an independent delta-Bullington), walls that reflect
(against the closed-form image method), boxes as footprints, order and split features,
reciprocity, the not-flyable pixels, the cache key and bad files refused in one line."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from rainuav import _core
from rainuav.errors import InvalidInputError
from rainuav.geo import Georef
from rainuav.ground.footprints import (
    DEFAULT_HEIGHT_M,
    STOREY_HEIGHT_M,
    parse_length,
    read_footprints,
)
from rainuav.radio.engines.ray_engine import ray_power, ray_terms
from rainuav.radio.engines.wall_rays import trace_walls
from rainuav.radio.scene import presets
from rainuav.radio.scene.buildings import scenario_buildings
from rainuav.radio.scene.scenario import (
    Area,
    Building,
    Cell,
    FootprintsFile,
    Origin,
    Pattern,
    Scenario,
    Site,
)
from rainuav.radio.scene.terrain import not_flyable

pytest.importorskip("shapely")

ORIGIN = Origin(lat_deg=47.37, lon_deg=8.54)
GEO = Georef(ORIGIN.lat_deg, ORIGIN.lon_deg)
C0 = 299_792_458.0
EPS0 = 8.8541878128e-12


def iso_cell() -> Cell:
    """An isotropic antenna (a flat table), so the tests see the paths alone."""
    flat = Pattern([-180.0, 180.0], [-90.0, 90.0], [[0.0, 0.0], [0.0, 0.0]])
    return Cell(azimuth_deg=0.0, tilt_deg=0.0, antenna="table", pattern=flat, tx_power_dbm=30.0)


def feature(ring: list[tuple[float, float]], holes=(), fid=None, **props) -> dict:
    """A GeoJSON Polygon feature from local (x, y) rings (metres east/north of ORIGIN)."""

    def lonlat(r):
        xs, ys = np.array([p[0] for p in r], float), np.array([p[1] for p in r], float)
        lat, lon = GEO.to_latlon(xs, ys)
        pts = [[float(a), float(b)] for a, b in zip(lon, lat, strict=True)]
        return [*pts, pts[0]]

    f = {
        "type": "Feature",
        "properties": props,
        "geometry": {"type": "Polygon", "coordinates": [lonlat(ring), *(lonlat(h) for h in holes)]},
    }
    if fid is not None:
        f["id"] = fid
    return f


def rect(x0: float, y0: float, x1: float, y1: float) -> list[tuple[float, float]]:
    return [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]


def write(path: Path, feats: list[dict], **extra) -> Path:
    path.write_text(json.dumps({"type": "FeatureCollection", "features": feats, **extra}))
    return path


def scenario(path: Path | None, sites, **kw) -> Scenario:
    area = kw.pop("area", Area(0.0, 800.0, 0.0, 800.0, altitude_m=30.0, resolution_m=10.0))
    return Scenario(
        name="buildings",
        freq_hz=kw.pop("freq_hz", 3.5e9),
        polarization=kw.pop("polarization", "v"),
        area=area,
        sites=sites,
        engine="ray",
        ground=kw.pop("ground", "none"),
        origin=ORIGIN,
        footprints=None if path is None else FootprintsFile(str(path)),
        **kw,
    )


# -- OpenStreetMap's tags ----------------------------------------------------------------------


def test_lengths_and_heights_by_openstreetmap_conventions(tmp_path: Path) -> None:
    assert parse_length("12") == 12.0 and parse_length(7) == 7.0
    assert parse_length("12 m") == 12.0 and parse_length("12.5m") == 12.5
    assert parse_length("40 ft") == pytest.approx(12.192)
    assert parse_length("40'") == pytest.approx(12.192)
    assert parse_length("12'6\"") == pytest.approx(3.81)
    for bad in ("-3", "tall", "", "12 km"):
        with pytest.raises(ValueError):
            parse_length(bad)
    feats = [
        feature(rect(0, 0, 20, 20), height="30 m", material="x"),
        feature(rect(40, 0, 60, 20), **{"building:levels": "4", "roof:height": "3"}),
        feature(rect(80, 0, 100, 20)),
        feature(rect(120, 0, 140, 20), height=20, min_height=5, **{"building:material": "glass"}),
        feature(rect(160, 0, 180, 20), height=12, **{"building:material": "steel"}),
    ]
    fp = read_footprints(write(tmp_path / "f.geojson", feats), GEO, (0.0, 800.0, 0.0, 800.0))
    got = [(b.height_m, b.min_height_m, b.eaves_m, b.material) for b in fp.buildings]
    assert got[0][:3] == pytest.approx((30.0, 0.0, 30.0))
    assert got[1][:3] == pytest.approx((4 * STOREY_HEIGHT_M + 3.0, 0.0, 4 * STOREY_HEIGHT_M))
    assert got[2][0] == DEFAULT_HEIGHT_M and fp.default_height == 1
    assert got[3] == (20.0, 5.0, 20.0, "glass")
    assert got[4][3] == "metal" and got[0][3] == "concrete"


# -- walls: the image method ---------------------------------------------------------------------


def test_one_wall_against_the_closed_form_image_method(tmp_path: Path) -> None:
    # A 60 m wall building (west face at x = 600, facing the site), a 500 m slab hiding the
    # pixels north-east of the site from it, free space, vertical polarisation, site and UAV
    # both 30 m up (horizontal rays: the field is perpendicular to the plane of incidence).
    # Where the direct ray is hidden, the one-wall rays (kind 1 of the traced rays; the slab's
    # corners and the second-order rays are the other kinds) are the reflected power: P = Pt
    # (lambda / (4 pi d))^2 |Gamma_perp|^2 with d from the site's image, Gamma from P.2040's
    # concrete written out here. Tolerance 0.1 dB (single precision nowhere; measured 5e-6 dB).
    ang = math.atan2(300.0, 250.0)  # the slab across the line site -> (450, 700)
    u = (-math.sin(ang), math.cos(ang))
    c = (400.0, 620.0)
    slab = [
        (c[0] - 60 * u[0] - 5 * u[1], c[1] - 60 * u[1] + 5 * u[0]),
        (c[0] + 60 * u[0] - 5 * u[1], c[1] + 60 * u[1] + 5 * u[0]),
        (c[0] + 60 * u[0] + 5 * u[1], c[1] + 60 * u[1] - 5 * u[0]),
        (c[0] - 60 * u[0] + 5 * u[1], c[1] - 60 * u[1] - 5 * u[0]),
    ]
    feats = [feature(rect(600, 0, 660, 800), height=60), feature(slab, height=500)]
    path = write(tmp_path / "wall.geojson", feats)
    site = Site(200.0, 400.0, 30.0, [iso_cell()])
    scn = scenario(path, [site])
    x, y = scn.area.centres()
    jobs = [(site, site.cells[0])]
    terms = ray_terms(scn, jobs, x, y)[0]
    traced = trace_walls(scn, jobs, x, y)
    assert traced is not None
    (_, pixel, _, _, factor, _, kind), _ = traced
    one = kind == 1
    walls_mw = np.bincount(pixel[one], 1000.0 * factor[one], minlength=x.size * y.size)
    power = walls_mw.reshape(1, y.size, x.size)
    hidden = (terms[..., 5] > 0) & (terms[..., 0] < 0.01 * terms[..., 5]) & (power[0] > 0)
    assert hidden.sum() >= 20, hidden.sum()
    f = 3.5e9
    lam = C0 / f
    eps = 5.24 - 1j * 0.0462 * (f / 1e9) ** 0.7822 / (2 * math.pi * f * EPS0)
    gx, gy = np.meshgrid(x, y)
    d = np.hypot(gx - 1000.0, gy - 400.0)  # from the image of (200, 400) in x = 600
    cos_t = (gx - 1000.0) / d * -1.0
    root = np.sqrt(eps - (1 - cos_t**2))
    gamma2 = np.abs((cos_t - root) / (cos_t + root)) ** 2
    want = 1000.0 * (lam / (4 * math.pi * d)) ** 2 * gamma2
    err = np.abs(10 * np.log10(power[0][hidden] / want[hidden]))
    assert err.max() < 0.1, err.max()


# -- roofs: the whole profile ------------------------------------------------------------------


def _knife_edge_db(nu: float) -> float:
    # ITU-R P.526-15 eq. (31).
    return 0.0 if nu <= -0.78 else 6.9 + 20 * math.log10(math.hypot(nu - 0.1, 1) + nu - 0.1)


def _roof_wedge_db(nu, edge, runs, a, b, lam, freq_hz, pol) -> float:
    """The loss of one building edge on a (sub-)path from ``a`` to ``b`` (docs/physics.md
    section 12), written out here: the knife edge where ``nu <= 0``, else the right-angled wedge
    of its roof (running ``runs`` = +1 on along the path, -1 back) and its wall, face 0 the face
    the path's start lights, P.2040 concrete faces, the UTD coefficient of ITU-R P.526-15
    section 6."""
    if nu <= 0:
        return float(_knife_edge_db(nu))
    (de, g), (s0, z0), (s1, z1) = edge, a, b
    # Angles from the roof over the top to the wall, in the path's vertical plane.
    phi1 = math.atan2(z0 - g, runs * (s0 - de)) % (2 * math.pi)
    phi2 = math.atan2(z1 - g, runs * (s1 - de)) % (2 * math.pi)
    n = 1.5
    if phi1 > math.pi:  # below the roof's plane the wall is the lit face
        phi1, phi2 = n * math.pi - phi1, n * math.pi - phi2
    f = freq_hz / 1e9
    eps = complex(5.24, -17.98 * 0.0462 * f**0.7822 / f)

    def fresnel(psi: float) -> complex:
        s, root = math.sin(psi), (eps - math.cos(psi) ** 2) ** 0.5
        return (eps * s - root) / (eps * s + root) if pol == "v" else (s - root) / (s + root)

    graze = lambda t: math.asin(abs(math.sin(t)))  # noqa: E731
    sp, sd = math.hypot(s0 - de, z0 - g), math.hypot(s1 - de, z1 - g)
    d = _core.utd_wedge(n, phi1, np.array([phi2]), l_m=sp * sd / (sp + sd), sin_beta0=1.0,
                        k=2 * math.pi / lam, r0=fresnel(graze(phi1)),
                        rn=fresnel(graze(n * math.pi - phi2)))[0]  # fmt: skip
    return -20 * math.log10(abs(d) * math.sqrt((sp + sd) / (sp * sd)))


def _deygout_by_hand(edges, d, h_ts, h_rs, lam, edge_db=None) -> float:
    """Deygout's principal edge and one edge on each side of it (docs/physics.md section 12),
    written out here from the construction: edges as (distance, height above sea level); each
    edge's loss ``edge_db(nu, k, edge, a, b)`` (``k`` its index in ``edges``), by default the
    knife edge."""

    def nu(e, a, b):
        (s0, z0), (s1, z1), (di, hi) = a, b, e
        g = hi + di * (d - di) / (2 * 8.5e6)
        line = z0 + (z1 - z0) * (di - s0) / (s1 - s0)
        return (g - line) * math.sqrt(2 * (s1 - s0) / (lam * (di - s0) * (s1 - di)))

    def best(a, b):
        inner = [(e, k) for k, e in enumerate(edges) if a[0] < e[0] < b[0]]
        return max(((nu(e, a, b), k) for e, k in inner), default=None)

    def bulged(k):
        dp, hp = edges[k]
        return (dp, hp + dp * (d - dp) / (2 * 8.5e6))

    loss_of = edge_db or (lambda v, k, e, a, b: float(_knife_edge_db(v)))
    t, r = (0.0, h_ts), (d, h_rs)
    top = best(t, r)
    if top is None or top[0] <= -0.78:
        return 0.0
    nu_p, kp = top
    edge = bulged(kp)
    loss = loss_of(nu_p, kp, edge, t, r)
    for a, b in ((t, edge), (edge, r)):
        side = best(a, b)
        if side is not None:
            loss += loss_of(side[0], side[1], bulged(side[1]), a, b)
    return loss


def test_a_thick_building_is_two_isolated_edges_without_the_terrain_correction(
    tmp_path: Path,
) -> None:
    # A 60 m thick, 80 m tall building between a 25 m site and the UAV at 100 m, free space.
    # Behind it, the direct ray's loss over free space (its corners' rays are apart) against
    # Deygout's construction over the two faces written out here, each face's edge the
    # right-angled wedge of the roof and the wall (ITU-R P.526-15 section 6): no empirical
    # correction (the terrain's, for real profiles, is not a building's). Tolerance 1e-3 dB:
    # the profile reads each face 1e-6 of the path inside it.
    path = write(tmp_path / "thick.geojson", [feature(rect(400, 300, 460, 500), height=80)])
    site = Site(100.0, 400.0, 25.0, [iso_cell()])
    area = Area(0.0, 1600.0, 390.0, 410.0, altitude_m=100.0, resolution_m=20.0)
    scn = scenario(path, [site], area=area, freq_hz=4.9e9)
    x, y = scn.area.centres()
    jobs = [(site, site.cells[0])]
    with_b = ray_terms(scn, jobs, x, y)[0, 0, :, 0]
    free = ray_terms(scn.replace(footprints=None), jobs, x, y)[0, 0, :, 0]
    loss = 10 * np.log10(free / with_b)
    lam = C0 / 4.9e9
    runs = (+1, -1)  # the near face's roof runs on along the path, the far face's back

    def wedge(v, k, e, a, b):
        return _roof_wedge_db(v, e, runs[k], a, b, lam, 4.9e9, "v")

    checked, apart = 0, 0.0
    for j in np.flatnonzero(x > 700):
        dist = float(x[j] - 100.0)
        edges = [(300.0, 80.0), (360.0, 80.0)]
        want = _deygout_by_hand(edges, dist, 25.0, 100.0, lam, wedge)
        assert abs(loss[j] - want) < 1e-3, (x[j], loss[j], want)
        apart = max(apart, abs(want - _deygout_by_hand(edges, dist, 25.0, 100.0, lam)))
        checked += 1
    assert checked >= 10 and loss[x > 700].min() > 10.0
    # The wedges are not the knife edges here: the check tells them apart.
    assert apart > 1.0


# -- boxes, order, split features ----------------------------------------------------------------


def _urban_footprints(path: Path, boxes: list[Building], order=None, split: int | None = None):
    feats = []
    for k, b in enumerate(boxes):
        if k == split:  # the same building in two features sharing a wall
            xm = 0.5 * (b.x0_m + b.x1_m)
            feats.append(feature(rect(b.x0_m, b.y0_m, xm, b.y1_m), height=b.height_m))
            feats.append(feature(rect(xm, b.y0_m, b.x1_m, b.y1_m), height=b.height_m))
        else:
            feats.append(feature(rect(b.x0_m, b.y0_m, b.x1_m, b.y1_m), height=b.height_m))
    if order is not None:
        feats = [feats[i] for i in order]
    return write(path, feats)


@pytest.mark.slow
def test_urban_boxes_as_footprints_in_any_order_or_split_give_the_same_map(
    tmp_path: Path,
) -> None:
    # The nine boxes of `urban` as footprints: the same prisms (to the millimetre the
    # footprints are snapped to), so the same map to rounding (1e-6 dB); reversed, or with a
    # building split in two along a shared wall (merged again: the wall is inside it).
    base = presets.urban().replace(engine="ray", origin=ORIGIN)
    boxes = base.buildings
    want = _map_db(base)
    for name, kw in {
        "same": {},
        "reversed": {"order": list(range(len(boxes)))[::-1]},
        "split": {"split": 4},
    }.items():
        path = _urban_footprints(tmp_path / f"{name}.geojson", boxes, **kw)
        got = _map_db(base.replace(buildings=[], footprints=FootprintsFile(str(path))))
        assert np.max(np.abs(got - want)) < 1e-6, (name, np.max(np.abs(got - want)))
    b = scenario_buildings(base)
    assert b is not None and len(b.footprints) == len(boxes) and b.walls.shape[0] == 4 * len(boxes)


def _map_db(scn: Scenario) -> np.ndarray:
    jobs = [(s, c) for s in scn.sites for c in s.cells]
    x, y = scn.area.centres()
    p, _ = ray_power(scn, jobs, x, y)
    return 10 * np.log10(np.maximum(p, 1e-300))


def test_a_wall_shared_by_two_buildings_does_not_reflect(tmp_path: Path) -> None:
    # Two buildings of different heights back to back: the taller one's wall against the
    # lower one is exposed above it only, the lower one's is inside the block.
    feats = [
        feature(rect(300, 300, 340, 500), height=40),
        feature(rect(340, 300, 380, 500), height=60),
    ]
    path = write(tmp_path / "pair.geojson", feats)
    scn = scenario(path, [Site(100.0, 400.0, 30.0, [iso_cell()])])
    b = scenario_buildings(scn)
    assert b is not None
    at_340 = b.walls[np.isclose(b.walls[:, 0], 340) & np.isclose(b.walls[:, 2], 340)]
    # One wall: the taller one's, facing west (a above b), from 40 m up to its 60 m roof.
    assert at_340.shape == (1, 6) and at_340[0, 1] > at_340[0, 3], at_340
    assert at_340[0, 4:] == pytest.approx([40.0, 60.0])


# -- reciprocity ---------------------------------------------------------------------------------


def test_reciprocity_swapping_the_site_and_the_point(tmp_path: Path) -> None:
    # The path loss between two points is the same either way: Bullington over the profile,
    # the ground's reflection and the walls' rays are reciprocal; isotropic antennas, no
    # pixel averaging. Tolerance 1e-6 dB (rounding).
    feats = [
        feature(rect(300, 300, 340, 500), height=45),
        feature([(500, 200), (560, 240), (520, 330), (470, 260)], height=70),
        feature(rect(200, 550, 420, 600), height=35),
    ]
    path = write(tmp_path / "rec.geojson", feats)
    scn = scenario(path, [Site(100.0, 400.0, 30.0, [iso_cell()])], ground="pec")
    b = scenario_buildings(scn)
    walls = _walls_eps(scn)
    rng = np.random.default_rng(7)
    pts = [(float(rng.uniform(0, 800)), float(rng.uniform(0, 800))) for _ in range(24)]
    tested = 0
    for k in range(0, len(pts), 2):
        (ax, ay), (bx, by) = pts[k], pts[k + 1]
        ha, hb = 20.0 + 5 * (k % 3), 60.0 + 10 * (k % 4)
        if b.prisms.height_at(np.array([ax, bx]), np.array([ay, by])).max() > 0:
            continue
        one = _path_loss(b, walls, (ax, ay, ha), (bx, by), hb)
        other = _path_loss(b, walls, (bx, by, hb), (ax, ay), ha)
        assert abs(one - other) < 1e-6, (pts[k], pts[k + 1], one, other)
        tested += 1
    assert tested >= 6


def _walls_eps(scn: Scenario):
    from rainuav.radio.scene.buildings import wall_args

    return wall_args(scn)


def _path_loss(b, walls, tx, q, alt) -> float:
    args = dict(
        freq_hz=3.5e9, buildings=np.zeros((0, 5)), heights=None,
        heights_origin_step=(0.0, 1.0, 0.0, 1.0), prisms=b.prisms,
    )  # fmt: skip
    x, y = np.array([q[0]]), np.array([q[1]])
    site = np.array([tx], dtype=float)
    _, _, _, _, factor, length, _ = _core.ray_walls(
        site, x, y, *walls, altitude_m=alt, polarization="v", **args
    )
    w = np.zeros((1, 1, 1, 2))
    if factor.size:
        w[0, 0, 0] = [factor.sum(), (factor * length).sum() / factor.sum()]
    one = np.ones((1, 1, 1))
    p = _core.ray_power(
        site, np.array([1.0]), one, one, x, y, altitude_m=alt, pixel_m=(0.0, 0.0),
        ground="pec", eps_ground=(1.0, 0.0), polarization="v", gamma_db_per_m=0.0,
        gamma_raster=None, gamma_origin_step=(0.0, 1.0, 0.0, 1.0), walls=w, **args,
    )  # fmt: skip
    return float(-10 * np.log10(p[0, 0, 0]))


# -- flying among them ---------------------------------------------------------------------------


def test_pixels_a_tall_building_overlaps_are_not_flyable(tmp_path: Path) -> None:
    # Polygons intersected with pixels: an L-shaped 120 m building under a 100 m flight
    # blocks every pixel it overlaps and none it only touches at a corner or an edge; its
    # courtyard (a hole) and the pixel in the L's notch stay flyable; a 50 m building
    # (60 m with the 10 m clearance) does not block a 100 m flight.
    ell = [(100, 100), (200, 100), (200, 150), (150, 150), (150, 200), (100, 200)]
    feats = [
        feature(ell, height=120),
        feature(rect(400, 400, 500, 500), holes=[rect(430, 430, 470, 470)], height=120),
        feature(rect(600, 600, 700, 700), height=50),
    ]
    path = write(tmp_path / "l.geojson", feats)
    area = Area(0.0, 800.0, 0.0, 800.0, altitude_m=100.0, resolution_m=10.0)
    scn = scenario(path, [Site(50.0, 50.0, 30.0, [iso_cell()])], area=area)
    mask = not_flyable(scn)
    assert mask[10:15, 10:20].all() and mask[15:20, 10:15].all()
    assert not mask[15:20, 15:20].any()  # the notch of the L
    assert not mask[9, 10:20].any() and not mask[10:20, 20].any()  # edges only touched
    assert mask[40:50, 40:50].sum() == 100 - 16  # the courtyard's 4 x 4 pixels are open
    assert not mask[60:70, 60:70].any()


def test_the_cache_key_follows_the_file_and_toml_paths_are_relative(tmp_path: Path) -> None:
    path = write(tmp_path / "a.geojson", [feature(rect(300, 300, 340, 500), height=40)])
    scn = scenario(path, [Site(100.0, 400.0, 30.0, [iso_cell()])])
    before = scn.digest()
    write(path, [feature(rect(300, 300, 340, 500), height=41)])
    assert scn.digest() != before
    (tmp_path / "sub").mkdir()
    toml = tmp_path / "sub" / "s.toml"
    text = scn.replace(footprints=FootprintsFile("../a.geojson")).to_toml(toml)
    assert Scenario.from_toml(text).footprints.file == str(tmp_path / "sub" / "../a.geojson")


def test_walls_trace_once_per_site_and_the_map_counts_them(tmp_path: Path) -> None:
    path = write(tmp_path / "w.geojson", [feature(rect(600, 0, 660, 800), height=60)])
    site = Site(200.0, 400.0, 30.0, [iso_cell(), Cell(azimuth_deg=90.0, tilt_deg=0.0)])
    scn = scenario(path, [site])
    x, y = scn.area.centres()
    traced = trace_walls(scn, [(site, c) for c in site.cells], x, y)
    assert traced is not None
    (site_k, pixel, *_), index = traced
    assert set(site_k.tolist()) == {0} and len(index) == 1 and pixel.size > 1000


# -- bad files -----------------------------------------------------------------------------------


def bad_footprint_files(d: Path) -> dict[str, tuple[Path, str]]:
    """Each bad file and a word its refusal names (shared with the hostile-input corpus)."""
    ok = rect(300, 300, 340, 500)
    return {
        "negative": (write(d / "negative.geojson", [feature(ok, fid="way/1", height=-5)]), "way/1"),
        "absurd": (write(d / "absurd.geojson", [feature(ok, height=1200)]), "1000"),
        "not_a_length": (write(d / "tall.geojson", [feature(ok, height="tall")]), "height"),
        "crs": (
            write(
                d / "crs.geojson",
                [feature(ok, height=10)],
                crs={"type": "name", "properties": {"name": "EPSG:3857"}},
            ),
            "crs",
        ),
        "empty": ((d / "empty.geojson"), "not JSON"),
        "not_json": ((d / "notjson.geojson"), "not JSON"),
        "min_above_roof": (
            write(d / "min.geojson", [feature(ok, height=10, min_height=12)]),
            "min_height",
        ),
        "off_earth": (d / "off.geojson", "longitude"),
    }


def _write_raw(d: Path) -> None:
    (d / "empty.geojson").write_text("")
    (d / "notjson.geojson").write_text("<osm version='0.6'></osm>")
    ring = [[200, 10], [201, 10], [201, 11], [200, 10]]
    geom = {"type": "Polygon", "coordinates": [ring]}
    feat = {"type": "Feature", "properties": {"height": 10}, "geometry": geom}
    write(d / "off.geojson", [feat])


def test_bad_footprint_files_are_refused_in_one_line_naming_the_file(tmp_path: Path) -> None:
    _write_raw(tmp_path)
    for name, (path, word) in bad_footprint_files(tmp_path).items():
        with pytest.raises(InvalidInputError) as err:
            read_footprints(path, GEO, (0.0, 800.0, 0.0, 800.0))
        msg = str(err.value)
        assert path.name in msg and word in msg and "\n" not in msg, (name, msg)


def test_what_is_skipped_repaired_or_clipped_is_counted(tmp_path: Path) -> None:
    bowtie = [(300, 300), (400, 400), (400, 300), (300, 400)]  # self-intersecting
    line = {"type": "Feature", "properties": {}, "geometry": {"type": "LineString",
            "coordinates": [[8.54, 47.37], [8.541, 47.371]]}}  # fmt: skip
    feats = [
        feature(bowtie, height=20),
        line,
        {"type": "Feature", "properties": {}, "geometry": None},
        feature(rect(5000, 5000, 5050, 5050), height=20),  # outside the area
        feature(rect(780, 100, 830, 150), height=20),  # across its east edge
    ]
    fp = read_footprints(write(tmp_path / "mixed.geojson", feats), GEO, (0.0, 800.0, 0.0, 800.0))
    assert (fp.repaired, fp.not_polygons, fp.outside, fp.clipped) == (1, 2, 1, 1)
    assert len(fp.buildings) == 3  # the bow-tie's two triangles and the clipped one
    assert fp.buildings[-1].polygon.bounds[2] == pytest.approx(800.0, abs=1e-6)
    assert "1 repaired" in fp.summary() and "1 outside" in fp.summary()


@pytest.mark.slow
def test_too_many_features_are_refused_before_building_them(tmp_path: Path) -> None:
    # A million features and one (null geometries: 50 MB of JSON) are refused in one line
    # before any geometry is built.
    one = '{"type":"Feature","properties":{},"geometry":null}'
    path = tmp_path / "million.geojson"
    path.write_text('{"type":"FeatureCollection","features":[' + ",".join([one] * 1_000_001) + "]}")
    with pytest.raises(InvalidInputError, match="1000001 features"):
        read_footprints(path, GEO, (0.0, 800.0, 0.0, 800.0))


# -- fly among the shipped buildings -------------------------------------------------------------

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.mark.slow
def test_fly_among_buildings_keeps_clear_and_refuses_a_start_in_a_tower(
    tmp_path: Path, capsys
) -> None:
    # `fly --footprints` over the shipped district at 100 m: the summary names what was read,
    # no vertex of the flight lies over a building that reaches within the 10 m clearance of
    # the flight (each vertex a pixel centre; the footprints as shapely polygons), and a start
    # inside the tallest tower is refused in one line, nothing written.
    import shapely
    from rainuav.fly import main
    from rainuav.ground.footprints import read_footprints

    base = ["--sites", str(EXAMPLES / "sites.csv"), "--footprints",
            str(EXAMPLES / "buildings.geojson")]  # fmt: skip
    out = tmp_path / "flight"
    capsys.readouterr()
    rc = main([*base, "--start", "47.3660,8.5380", "--goal", "47.3800,8.5560", "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 0 and "footprints" in err and "buildings from" in err, err
    summary = json.loads((out / "summary.json").read_text())
    g = Georef(summary["origin"]["lat"], summary["origin"]["lon"])
    fp = read_footprints(EXAMPLES / "buildings.geojson", g, (-5e3, 5e3, -5e3, 5e3))
    tall = [b.polygon for b in fp.buildings if b.height_m + 10.0 >= 100.0]
    assert tall, "the district has towers above the flight"
    line = json.loads((out / "flight.geojson").read_text())["features"][0]
    coords = np.array(line["geometry"]["coordinates"])
    px, py = g.to_local(coords[:, 1], coords[:, 0])
    pts = shapely.points(px, py)
    assert not any(shapely.intersects(pts, t).any() for t in tall)
    # The tallest tower's centre as the start: refused, nothing written.
    top = max(fp.buildings, key=lambda b: b.height_m)
    c = top.polygon.centroid
    lat, lon = g.to_latlon(c.x, c.y)
    out2 = tmp_path / "in_tower"
    capsys.readouterr()
    rc = main([*base, "--start", f"{lat:.6f},{lon:.6f}", "--goal", "47.3800,8.5560",
               "--out", str(out2)])  # fmt: skip
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and "--start" in err[-1] and "may not fly" in err[-1], err
    assert not (out2 / "summary.json").exists()
