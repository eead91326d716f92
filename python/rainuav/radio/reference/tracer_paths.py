"""Sionna RT's path solver at the pixel centres: the tracer's exact paths, as a reference for the
building effect beside (and in the shadows in place of) its Monte Carlo radio map
([`rainuav.radio.reference.tracer`][rainuav.radio.reference.tracer], docs/physics.md section 12).

The radio map estimates each cell's power from the rays that happen to cross it; in a deep shadow
few diffracted rays do, and the estimate is dark and scattered there (on the canyon test scene,
4.9 GHz, vertical polarisation, UAV at 20 m: 3.5 dB from the path solver at the median of the
shadow pixels, 9.9 dB at the 90th percentile, 1.7 dB darker at the median, where the two halves of
the map's rays differ by about 0.9 dB). The path solver finds each path's candidates by shooting
rays too, but then solves its geometry exactly for each receiver (the image method; the diffraction
point on the edge by Keller's law), so a path once found has its exact power at the pixel's centre,
the point the ray engine evaluates. Its own uncertainty is a path it did not find: two runs with
different seeds (the two "halves") estimate it, as the radio map's halves do.

What is summed is every path's power, ``|a|^2`` over the paths (incoherent: the pixel mean of
their interference, as the engine takes it), with the same isotropic antennas, polarisation,
materials, interactions (``max_depth``, one diffraction a path) and PEC ground by images as the
radio map ([`tracer_gain()`][rainuav.radio.reference.tracer.tracer_gain]).
"""

from __future__ import annotations

import numpy as np

from rainuav.radio.reference.tracer import (
    TracerMap,
    add_transmitters,
    inside_buildings,
    interactions,
    load_sionna,
    repeatable,
    tracer_scene,
)
from rainuav.radio.scene.scenario import Scenario

__all__ = ["path_gain"]


def path_gain(
    scn: Scenario,
    *,
    samples: int = 2_000_000,
    max_depth: int = 2,
    seed: int = 0,
    step: int = 1,
    coefficient: str = "p526",
) -> TracerMap:
    """The path solver's gain (linear) of each site of ``scn`` (an
    [`isotropic_scenario()`][rainuav.radio.reference.tracer.isotropic_scenario]) at the centre of
    every ``step``-th pixel (in both directions) outside the buildings, (S, H, W); other pixels are
    0 (not covered). Two runs of ``samples // 2`` candidate rays a site, seeded ``2 seed`` and
    ``2 seed + 1``, are the two halves; on one thread
    ([`repeatable()`][rainuav.radio.reference.tracer.repeatable]), the same every run.
    ``coefficient``: the wedge coefficient, the standard's (``"p526"``) or the tracer's own as
    released (``"sionna"``; [`tracer_wedge`][rainuav.radio.reference.tracer_wedge])."""
    if step < 1:
        raise ValueError(f"step is a whole number of pixels >= 1 (got {step})")
    from rainuav.radio.reference.tracer_wedge import coefficient as using

    with repeatable(), using(coefficient):
        return _path_gain(scn, samples, max_depth, seed, step)


def _path_gain(scn: Scenario, samples: int, max_depth: int, seed: int, step: int) -> TracerMap:
    mi, rt = load_sionna()
    scene = tracer_scene(scn)
    images = add_transmitters(scene, scn)
    h, w = scn.area.shape
    x, y = scn.area.centres()
    ii, jj = np.meshgrid(np.arange(0, h, step), np.arange(0, w, step), indexing="ij")
    keep = ~inside_buildings(scn)[ii, jj]
    ii, jj = ii[keep], jj[keep]
    z = scn.area.altitude_m
    for n, (i, j) in enumerate(zip(ii, jj, strict=True)):
        scene.add(rt.Receiver(name=f"rx{n}", position=mi.Point3f(float(x[j]), float(y[i]), z)))
    solver = rt.PathSolver()
    halves = []
    for half in range(2):
        paths = solver(
            scene,
            max_num_paths_per_src=10**7,
            samples_per_src=max(1, samples // 2),
            synthetic_array=False,
            seed=2 * seed + half,
            **interactions(max_depth),
        )
        re, im = (np.asarray(v, dtype=float) for v in paths.a)
        valid = np.asarray(paths.valid.numpy(), dtype=bool)
        power = (re**2 + im**2) * valid.reshape(re.shape)
        # (receivers, rx antennas, transmitters, tx antennas, paths) -> (receivers, transmitters)
        per = power.sum(axis=(1, 3, 4)).reshape(len(ii), images, len(scn.sites)).sum(axis=1)
        g = np.zeros((len(scn.sites), h, w))
        g[:, ii, jj] = per.T
        halves.append(g)
    return TracerMap(halves[0], halves[1])
