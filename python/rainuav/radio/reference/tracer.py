"""Sionna RT, a full ray tracer, as an independent reference for the building physics
([physics reference, section 12][12-terrain-buildings-diffraction-and-reflections]).

The same scene in both: a scenario's buildings (boxes and footprints, merged as the ray engine
reads them) become closed meshes in the tracer; each site radiates from one isotropic antenna of the
scenario's polarisation, and the map is the path gain at the pixel centres of the scenario's area at
its flight altitude (the tracer's measurement plane, one cell a pixel). What is compared is the
**building effect**: the map with the buildings minus the map without them, in dB, each method
against itself, so that the antennas and the spreading cancel and what remains is what the
buildings do (shadows, diffraction, wall reflections).

- The tracer's map is a Monte Carlo estimate; it is run twice with half the rays each (two seeds)
  and their mean is the reference; their difference estimates its noise per pixel. It runs on one
  Dr.Jit thread ([`repeatable()`][rainuav.radio.reference.tracer.repeatable]: on several, the
  rays are summed in an order that changes, and two runs of one seed differed by 3.9 dB at the
  99th percentile of `district`'s pixels): the same seed, the same map, twice the time.
- A pixel counts where the tracer covers it (both halves received something, with and without
  buildings), its halves agree within ``2 MAX_NOISE_DB``, and the UAV is outside every building;
  building effects below ``FLOOR_DB`` are compared as ``FLOOR_DB``.
- The tracer's settings: specular reflections on the walls up to ``max_depth`` interactions, edge
  diffraction (one diffraction a path, at the wedges where the buildings' faces meet, with the
  coefficient of ITU-R P.526-15 section 6 in place of Sionna RT's own:
  [`rainuav.radio.reference.tracer_wedge`][rainuav.radio.reference.tracer_wedge] says why), no
  transmission through walls (the ray engine's buildings are opaque), no diffuse scattering, and no
  ground or a PEC one by images ([`tracer_gain()`][rainuav.radio.reference.tracer.tracer_gain]).
  Walls are the ITU-R P.2040 material of the footprints, as in the ray engine; the buildings are
  closed meshes whose faces share their edges
  ([`prism_arrays()`][rainuav.radio.reference.tracer.prism_arrays]).

Needs ``sionna-rt`` (the ``test`` extra). On a machine without a GPU it runs through LLVM: Debian's
``libllvm19``, found through ``DRJIT_LIBLLVM_PATH`` (set here when unset and the library is where
Debian puts it).
"""

from __future__ import annotations

import contextlib
import dataclasses
import itertools
import os
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from rainuav.radio.scene.cell import Cell, Pattern
from rainuav.radio.scene.scenario import Medium, Scenario, Site

__all__ = [
    "FLOOR_DB",
    "ISOTROPIC",
    "LLVM_PATHS",
    "MAX_NOISE_DB",
    "SHADOW_DB",
    "TracerMap",
    "add_transmitters",
    "engine_gain",
    "inside_buildings",
    "interactions",
    "isotropic_scenario",
    "load_sionna",
    "prism_arrays",
    "repeatable",
    "tracer_gain",
    "tracer_scene",
]

LLVM_PATHS = (
    "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1",
    "/usr/lib/x86_64-linux-gnu/libLLVM-19.so",
    "/usr/lib/aarch64-linux-gnu/libLLVM.so.19.1",
    "/usr/lib/llvm-19/lib/libLLVM.so.1",
)
"""Where Debian's ``libllvm19`` puts the library Dr.Jit's CPU backend loads."""

SHADOW_DB = -6.0
"""A pixel is in a building's shadow where the building effect is below this (dB)."""

FLOOR_DB = -60.0
"""Building effects below this (dB) are compared as this: both maps call such a pixel dark (no
link budget reaches it), and the tracer's paths there can be vanishing single diffractions whose
dB value means nothing."""

MAX_NOISE_DB = 3.0
"""A pixel is compared where the tracer's two halves agree within twice this (dB): its estimate
is then good to about this."""


def load_sionna() -> tuple[Any, Any]:
    """Mitsuba and Sionna RT, on a GPU where one is present, else on the CPU through LLVM.

    With P.526's wedge coefficient ([`tracer_wedge`][rainuav.radio.reference.tracer_wedge]; the
    first time: a [`coefficient()`][rainuav.radio.reference.tracer_wedge.coefficient] block keeps
    its own).

    Returns:
        `(mitsuba, sionna.rt)`.

    Raises:
        ImportError: What is missing (sionna-rt, or LLVM for the CPU), named.
    """
    if "DRJIT_LIBLLVM_PATH" not in os.environ:
        for p in LLVM_PATHS:
            if os.path.exists(p):
                os.environ["DRJIT_LIBLLVM_PATH"] = p
                break
    try:
        import mitsuba as mi
    except ImportError as err:  # pragma: no cover - depends on the machine
        raise ImportError("the tracer needs sionna-rt: pip install '.[test]'") from err
    if mi.variant() is None:
        variants = mi.variants()
        for v in ("cuda_ad_mono_polarized", "llvm_ad_mono_polarized"):
            if v in variants:
                try:
                    mi.set_variant(v)
                    break
                except (ImportError, RuntimeError, AttributeError):
                    continue
        else:  # pragma: no cover - depends on the machine
            raise ImportError(
                "Sionna RT found neither CUDA nor LLVM: install Debian's libllvm19 and set "
                "DRJIT_LIBLLVM_PATH to its libLLVM.so"
            )
    import sionna.rt as rt

    from rainuav.radio.reference.tracer_wedge import install_default

    install_default()
    return mi, rt


ISOTROPIC = Pattern(
    azimuth_deg=[-180.0, 180.0], elevation_deg=[-90.0, 90.0], gain_db=[[0.0, 0.0], [0.0, 0.0]]
)
"""A pattern of 0 dBi in every direction."""


def isotropic_scenario(scn: Scenario, *, buildings: bool = True, ground: str = "none") -> Scenario:
    """A scenario as both methods compare it: each site once, one isotropic 0 dBm cell.

    Clear air; no ground or a PEC one; the ray engine; with or without its buildings.

    Args:
        scn: The scenario.
        buildings: Keep its buildings.
        ground: "none" or "pec".

    Returns:
        The [`Scenario`][rainuav.radio.scene.scenario.Scenario].
    """
    sites, seen = [], set()
    for s in scn.sites:
        key = (s.x_m, s.y_m, s.height_m)
        if key not in seen:
            seen.add(key)
            cell = Cell(azimuth_deg=0.0, tilt_deg=0.0, pattern=ISOTROPIC, tx_power_dbm=0.0)
            sites.append(Site(x_m=s.x_m, y_m=s.y_m, height_m=s.height_m, cells=[cell]))
    out = dataclasses.replace(
        scn, sites=sites, medium=Medium(kind="clear"), ground=ground, engine="ray"
    )
    if not buildings:
        out = dataclasses.replace(out, buildings=[], footprints=None, height_map_m=None)
    return out


def engine_gain(scn: Scenario, engine: str = "ray") -> np.ndarray:
    """The path gain of each site of an isotropic scenario at every pixel, by an engine.

    With `engine` "hybrid" or "pe", by
    [`build_radio_map()`][rainuav.radio.outputs.maps.build_radio_map] with that engine (the cells
    radiate 0 dBm: the map's dBm are the path gain's dB).

    Args:
        scn: An [`isotropic_scenario()`][rainuav.radio.reference.tracer.isotropic_scenario].
        engine: "ray", "hybrid" or "pe".

    Returns:
        (S, H, W), linear.
    """
    from rainuav.radio.engines import engine_of
    from rainuav.radio.engines.ray_engine import ray_power

    if engine_of(engine).marches:  # the map with the march in it
        from rainuav.radio.outputs.maps import build_radio_map

        rm = build_radio_map(dataclasses.replace(scn, engine=engine), cache=False)
        return np.asarray(10.0 ** (rm.rss_dbm / 10.0), dtype=float)
    x, y = scn.area.centres()
    jobs = [(s, s.cells[0]) for s in scn.sites]
    power_mw, _ = ray_power(scn, jobs, x, y)
    return power_mw


def prism_arrays(polygon: Any, base: float, top: float) -> tuple[np.ndarray, np.ndarray]:
    """The closed mesh of a polygon (holes included) extruded between two heights.

    Faces point outward (counter-clockwise seen from outside), and faces that meet share their
    vertices. The tracer finds a wedge where two faces share an edge and takes an edge of one face
    alone for a free edge (a half-plane): a mesh whose faces did not share their vertices would make
    every corner two half-planes and every seam between two triangles of a wall or a roof a
    diffracting edge.

    Args:
        polygon: The footprint (a shapely polygon).
        base: The bottom, m.
        top: The roof, m.

    Returns:
        `(vertices (V, 3), triangles (F, 3))`.
    """
    import shapely

    index: dict[tuple[float, float, float], int] = {}

    def vertex(x: float, y: float, z: float) -> int:
        return index.setdefault((round(float(x), 6), round(float(y), 6), float(z)), len(index))

    faces: list[list[int]] = []
    for t in shapely.get_parts(shapely.constrained_delaunay_triangles(polygon)):
        c = np.asarray(t.exterior.coords)[:3, :2]
        e1, e2 = c[1] - c[0], c[2] - c[0]
        if e1[0] * e2[1] - e1[1] * e2[0] < 0:
            c = c[::-1]
        faces.append([vertex(*c[k], top) for k in (0, 1, 2)])
        faces.append([vertex(*c[k], base) for k in (0, 2, 1)])
    for ring, outer in [(polygon.exterior, True)] + [(r, False) for r in polygon.interiors]:
        c = np.asarray(ring.coords)[:, :2]
        if ring.is_ccw != outer:
            c = c[::-1]
        for a, b in itertools.pairwise(c):
            q = [vertex(*a, base), vertex(*b, base), vertex(*b, top), vertex(*a, top)]
            faces += [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
    return np.asarray(list(index), float), np.asarray(faces, np.int64)


def _prism_mesh(mi: Any, name: str, polygon: Any, base: float, top: float) -> Any:
    """[`prism_arrays()`][rainuav.radio.reference.tracer.prism_arrays] as a Mitsuba mesh."""
    v, f = prism_arrays(polygon, base, top)
    mesh = mi.Mesh(name, len(v), len(f))
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float(v.astype(np.float32).ravel())
    params["faces"] = mi.UInt32(f.astype(np.uint32).ravel())
    params.update()
    return mesh


@dataclass(frozen=True)
class TracerMap:
    """The tracer's gain (linear) of each site at every pixel, (S, H, W), from two ray halves."""

    half_a: np.ndarray
    half_b: np.ndarray
    whole: np.ndarray | None = None  # the estimate, where not the halves' mean (a union of paths)

    @property
    def gain(self) -> np.ndarray:
        """The estimate: the mean of the halves (or ``whole``)."""
        return 0.5 * (self.half_a + self.half_b) if self.whole is None else self.whole

    @property
    def covered(self) -> np.ndarray:
        """Where both halves received something."""
        return (self.half_a > 0) & (self.half_b > 0)


def tracer_scene(scn: Scenario, material: str | None = None) -> Any:
    """Sionna RT's scene of a scenario: its buildings as closed meshes, and its antennas.

    Each building of its footprints' P.2040 material (0.3 m thick walls), one isotropic antenna of
    the scenario's polarisation on each side, no transmitters. Over a PEC ground every building
    extends as deep below the ground as it stands above it (the image method).

    Args:
        scn: The scenario (ground "none" or "pec").
        material: An ITU material name for every building; None: each footprint's own.

    Returns:
        The tracer's scene.

    Raises:
        ValueError: A ground other than "none" or "pec".
    """
    if scn.ground not in ("none", "pec"):
        raise ValueError(f"the tracer's ground is none or pec (got {scn.ground!r})")
    from rainuav.radio.scene.buildings import scenario_buildings

    mi, rt = load_sionna()
    scene = rt.load_scene()
    scene.frequency = scn.freq_hz
    found = scenario_buildings(scn)
    objects = []
    for k, f in enumerate(found.footprints if found is not None else ()):
        mat = rt.ITURadioMaterial(name=f"wall-{k}", itu_type=material or f.material, thickness=0.3)
        base = -f.height_m if scn.ground == "pec" else f.min_height_m
        mesh = _prism_mesh(mi, f"b{k}", f.polygon, base, f.height_m)
        objects.append(rt.SceneObject(mi_mesh=mesh, name=f"b{k}", radio_material=mat))
    if objects:
        scene.edit(add=objects)
    pol = scn.polarization.upper()
    scene.tx_array = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization=pol)
    scene.rx_array = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization=pol)
    return scene


def add_transmitters(scene: Any, scn: Scenario) -> int:
    """Adds one transmitter a site to the tracer's scene (and each one's image over PEC).

    The images come after the sites (the image method;
    [`tracer_scene()`][rainuav.radio.reference.tracer.tracer_scene] extends the buildings below the
    ground).

    Args:
        scene: The tracer's scene.
        scn: The scenario.

    Returns:
        How many sets of sites there are (1, or 2 with the images).
    """
    mi, rt = load_sionna()
    images = (1.0, -1.0) if scn.ground == "pec" else (1.0,)
    for sign in images:
        for k, s in enumerate(scn.sites):
            at = mi.Point3f(s.x_m, s.y_m, sign * s.height_m)
            scene.add(rt.Transmitter(name=f"tx{k}{'i' if sign < 0 else ''}", position=at))
    return len(images)


def interactions(max_depth: int, diffraction: bool = True) -> dict[str, Any]:
    """The interactions both of the tracer's solvers trace (the module's docstring).

    Line of sight, specular reflections up to `max_depth`, edge diffraction where asked; no diffuse
    scattering, no transmission through walls.

    Args:
        max_depth: The most interactions of a path.
        diffraction: Trace edge diffraction.

    Returns:
        The solvers' keyword arguments.
    """
    return {
        "max_depth": max_depth,
        "los": True,
        "specular_reflection": max_depth > 0,
        "diffuse_reflection": False,
        "refraction": False,
        "diffraction": diffraction,
        "edge_diffraction": diffraction,
    }


@contextlib.contextmanager
def repeatable() -> Iterator[None]:
    """A context in which the tracer runs on one thread (the count restored after).

    On several threads the same seed gives a different map each run (the module's docstring).

    Yields:
        Nothing.
    """
    load_sionna()
    import drjit as dr

    before = dr.thread_count()
    dr.set_thread_count(1)
    try:
        yield
    finally:
        dr.set_thread_count(before)


def tracer_gain(
    scn: Scenario,
    *,
    samples: int = 2_000_000,
    max_depth: int = 2,
    diffraction: bool = True,
    seed: int = 0,
    coefficient: str = "p526",
) -> TracerMap:
    """Sionna RT's path gain of each site of an isotropic scenario at every pixel.

    Over a PEC ground by the image method: every building extends as deep below the ground as it
    stands above it, each site has its image below the ground, and a pixel's gain is the sum of both
    (incoherent: the pixel mean of the ground's fringes, as the ray engine takes it). On one thread
    ([`repeatable()`][rainuav.radio.reference.tracer.repeatable]): the same seed, the same map.

    Args:
        scn: An [`isotropic_scenario()`][rainuav.radio.reference.tracer.isotropic_scenario].
        samples: Rays a site in all, in two halves seeded `2 seed` and `2 seed + 1`.
        max_depth: The most interactions of a path.
        diffraction: Trace edge diffraction.
        seed: The seed.
        coefficient: The wedge coefficient it diffracts with: the standard's ("p526") or its own as
            released ("sionna"; [`tracer_wedge`][rainuav.radio.reference.tracer_wedge]).

    Returns:
        The [`TracerMap`][rainuav.radio.reference.tracer.TracerMap]: the two halves of the rays.
    """
    from rainuav.radio.reference.tracer_wedge import coefficient as using

    mi, rt = load_sionna()
    scene = tracer_scene(scn)
    images = add_transmitters(scene, scn)
    a = scn.area
    h, w = a.shape
    res = ((a.x_max_m - a.x_min_m) / w, (a.y_max_m - a.y_min_m) / h)
    solver = rt.RadioMapSolver()
    centre = (0.5 * (a.x_min_m + a.x_max_m), 0.5 * (a.y_min_m + a.y_max_m), a.altitude_m)
    halves = []
    for half in range(2):
        with repeatable(), using(coefficient):
            rm = solver(
                scene, center=mi.Point3f(*centre), orientation=mi.Point3f(0.0, 0.0, 0.0),
                size=mi.Point2f(a.x_max_m - a.x_min_m, a.y_max_m - a.y_min_m),
                cell_size=mi.Point2f(*res), samples_per_tx=max(1, samples // 2),
                seed=2 * seed + half, **interactions(max_depth, diffraction),
            )  # fmt: skip
            g = np.asarray(rm.path_gain.numpy(), dtype=float)
        halves.append(g.reshape(images, len(scn.sites), h, w).sum(axis=0))
    return TracerMap(halves[0], halves[1])


def inside_buildings(scn: Scenario) -> np.ndarray:
    """The pixels whose centre lies in a building at least as tall as the flight altitude.

    Args:
        scn: The scenario.

    Returns:
        (H, W) bool.
    """
    from rainuav.radio.scene.buildings import scenario_buildings

    found = scenario_buildings(scn)
    x, y = scn.area.centres()
    if found is None:
        return np.zeros((y.size, x.size), bool)
    xx, yy = np.meshgrid(x, y)
    h = found.prisms.height_at(xx.ravel(), yy.ravel()).reshape(xx.shape)
    return h >= scn.area.altitude_m
