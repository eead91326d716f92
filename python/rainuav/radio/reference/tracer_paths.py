"""Sionna RT's path solver at the pixel centres: the tracer's exact paths, as a reference for the
building effect beside (and in the shadows in place of) its Monte Carlo radio map
([`rainuav.radio.reference.tracer`][rainuav.radio.reference.tracer], [physics reference, section
12][12-terrain-buildings-diffraction-and-reflections]).

The radio map estimates each cell's power from the rays that happen to cross it; in a deep shadow
few diffracted rays do, and the estimate is dark and scattered there (on the canyon test scene,
4.9 GHz, vertical polarisation, UAV at 20 m: 3.5 dB from the path solver at the median of the
shadow pixels, 9.9 dB at the 90th percentile, 1.7 dB darker at the median, where the two halves of
the map's rays differ by about 0.9 dB). The path solver finds each path's candidates by shooting
rays too, but then solves its geometry exactly for each receiver (the image method; the diffraction
point on the edge by Keller's law), so a path once found has its exact power at the pixel's centre,
the point the ray engine evaluates. Its own uncertainty is a path it did not find.

**Runs, and their union.** Which paths a run finds depends on its rays: a diffraction is a
candidate only where a ray hits a face near the edge, the point it projects to on the edge is
sampled, and the path is kept for a receiver only where that point sees it. One run of many rays
misses some diffracted paths in deep shadows, and a run of other rays finds them: on the real
square `helsinki_b` (site 0, 3.5 GHz, 20 m), 3% of the receivers gain more than 10 dB from 1e6 to
16e6 candidate rays and 2% from 4e6 to 16e6. A path once found is exact, so runs combine as the
union of the distinct paths they found, not as a mean: ``runs`` runs of ``samples // runs`` rays,
seeded apart, each path known by its delay (to ``DELAY_KEY_S``: two distinct paths of one link
do not have the same length to a tenth of a millimetre). The two halves are the unions of the
even and of the odd runs; where they differ, a path was found by one half alone (the estimate's
noise, as the radio map's halves say theirs); the estimate is the union of all the runs.

What is summed is every path's power, ``|a|^2`` over the paths (incoherent: the pixel mean of
their interference, as the engine takes it), with the same isotropic antennas, polarisation,
materials, interactions (``max_depth``, one diffraction a path) and PEC ground by images as the
radio map ([`tracer_gain()`][rainuav.radio.reference.tracer.tracer_gain]).
"""

from __future__ import annotations

import inspect
from typing import Any

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

__all__ = ["DELAY_KEY_S", "PATH_KINDS", "path_gain", "path_gain_by_kind", "union_power"]

PATH_KINDS = ("line of sight", "reflections", "diffraction", "reflections and a diffraction")
"""The kinds of path [`path_gain_by_kind()`][rainuav.radio.reference.tracer_paths.path_gain_by_kind]
splits the power into, by the interactions along each path."""

DELAY_KEY_S = 3e-13
"""How close two paths' delays are for them to be one path (module docstring): 0.09 mm."""


def path_gain(
    scn: Scenario,
    *,
    samples: int = 2_000_000,
    max_depth: int = 2,
    seed: int = 0,
    step: int = 1,
    coefficient: str = "p526",
    runs: int = 2,
) -> TracerMap:
    """The tracer's path solver's gain of each site at pixel centres outside the buildings.

    Other pixels are 0 (not covered). The runs are combined as the union of their paths (the
    module's docstring: the halves the unions of the even and of the odd runs, the estimate that of
    all); on one thread ([`repeatable()`][rainuav.radio.reference.tracer.repeatable]), the same
    every run.

    Args:
        scn: An [`isotropic_scenario()`][rainuav.radio.reference.tracer.isotropic_scenario].
        samples: Candidate rays a site in all, `samples // runs` a run.
        max_depth: The most interactions of a path.
        seed: Runs are seeded `runs seed` to `runs seed + runs - 1`.
        step: Every how many pixels a centre is traced, in both directions.
        coefficient: The wedge coefficient: the standard's ("p526") or the tracer's own as released
            ("sionna").
        runs: The runs, even, at least 2.

    Returns:
        The [`TracerMap`][rainuav.radio.reference.tracer.TracerMap] (S, H, W), linear: the halves
        and the whole.

    Raises:
        ValueError: `runs` odd or below 2, or `step` below 1.
    """
    found, gain = _solved(scn, samples=samples, max_depth=max_depth, seed=seed, step=step,
                          coefficient=coefficient, runs=runs)  # fmt: skip
    return TracerMap(gain(found, list(range(0, runs, 2))), gain(found, list(range(1, runs, 2))),
                     whole=gain(found, list(range(runs))))  # fmt: skip


def path_gain_by_kind(scn: Scenario, **solver: Any) -> dict[str, np.ndarray]:
    """The path solver's gain at pixel centres split by the kind of path that carries it.

    The union of all the runs' paths (as the estimate of
    [`path_gain()`][rainuav.radio.reference.tracer_paths.path_gain]), each path counted in one
    of [`PATH_KINDS`][rainuav.radio.reference.tracer_paths.PATH_KINDS] by its interactions:
    none, specular reflections alone, one diffraction alone, or reflections and a diffraction.
    The kinds sum to ``path_gain``'s ``whole``.

    Args:
        scn: An [`isotropic_scenario()`][rainuav.radio.reference.tracer.isotropic_scenario].
        **solver: ``path_gain``'s keyword arguments (``samples``, ``max_depth``, ``seed``,
            ``step``, ``coefficient``, ``runs``), with its defaults.

    Returns:
        Each kind's gain (S, H, W), linear (0 where not traced).

    Raises:
        ValueError: `runs` odd or below 2, or `step` below 1.
    """
    opts = {k: v.default for k, v in inspect.signature(path_gain).parameters.items() if k != "scn"}
    unknown = sorted(set(solver) - set(opts))
    if unknown:
        raise TypeError(f"path_gain_by_kind got unknown arguments {unknown}")
    opts |= solver
    found, gain = _solved(scn, **opts)
    runs = list(range(opts["runs"]))
    return {kind: gain(found, runs, k) for k, kind in enumerate(PATH_KINDS)}


def _solved(
    scn: Scenario, *, samples: int, max_depth: int, seed: int, step: int, coefficient: str,
    runs: int,
) -> tuple[list, Any]:  # fmt: skip
    """The runs' paths and their gain by union, on one thread, with the coefficient asked for."""
    if step < 1:
        raise ValueError(f"step is a whole number of pixels >= 1 (got {step})")
    if runs < 2 or runs % 2:
        raise ValueError(f"runs is an even number >= 2 (got {runs})")
    from rainuav.radio.reference.tracer_wedge import coefficient as using

    with repeatable(), using(coefficient):
        return _path_runs(scn, samples, max_depth, seed, step, runs)


def union_power(found: list[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """The power of the union of the distinct paths of several runs (the module's docstring).

    Per link, the sum of one power per distinct delay (to `DELAY_KEY_S`).

    Args:
        found: Each run's paths' delays and powers, (L, P) each for its L links (an invalid path's
            power 0).

    Returns:
        (L,) powers.
    """
    tau = np.concatenate([t for t, _ in found], axis=1)
    power = np.concatenate([p for _, p in found], axis=1)
    link, k = np.nonzero(power > 0)
    key = np.column_stack([link, np.round(tau[link, k] / DELAY_KEY_S).astype(np.int64)])
    _, first = np.unique(key, axis=0, return_index=True)  # one path per (link, delay)
    return np.bincount(link[first], weights=power[link, k][first], minlength=len(tau))


def _kinds(codes: np.ndarray) -> np.ndarray:
    """Each path's index in ``PATH_KINDS`` from its interaction codes (depth first, Sionna RT's
    ``InteractionType``: 0 none, 1 specular, 8 diffraction)."""
    specular = np.any(codes == 1, axis=0)
    diffracted = np.any(codes == 8, axis=0)
    return np.where(diffracted, np.where(specular, 3, 2), np.where(specular, 1, 0))


def _path_runs(
    scn: Scenario, samples: int, max_depth: int, seed: int, step: int, runs: int
) -> tuple[list, Any]:
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
    found = []
    for run in range(runs):
        paths = solver(
            scene,
            max_num_paths_per_src=10**7,
            samples_per_src=max(1, samples // runs),
            synthetic_array=False,
            seed=runs * seed + run,
            **interactions(max_depth),
        )
        re, im = (np.asarray(v, dtype=float) for v in paths.a)
        valid = np.asarray(paths.valid.numpy(), dtype=bool).reshape(re.shape)
        # (receivers, rx antennas, transmitters, tx antennas, paths): one antenna each side
        power = ((re**2 + im**2) * valid)[:, 0, :, 0, :]
        tau = np.asarray(paths.tau, dtype=float).reshape(re.shape)[:, 0, :, 0, :]
        codes = np.asarray(paths.interactions.numpy()).reshape(-1, *re.shape)[:, :, 0, :, 0, :]
        found.append((tau.reshape(-1, tau.shape[-1]), power.reshape(-1, power.shape[-1]),
                      _kinds(codes).reshape(-1, power.shape[-1])))  # fmt: skip

    def gain(found: list, which: list[int], kind: int | None = None) -> np.ndarray:
        runs = [(found[k][0], found[k][1] if kind is None else found[k][1] * (found[k][2] == kind))
                for k in which]  # fmt: skip
        per = union_power(runs)
        # (receivers, transmitters: each site's images) -> (sites, receivers)
        per = per.reshape(len(ii), images, len(scn.sites)).sum(axis=1)
        g = np.zeros((len(scn.sites), h, w))
        g[:, ii, jj] = per.T
        return g

    return found, gain
