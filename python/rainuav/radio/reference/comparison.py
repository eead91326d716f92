"""The ray engine's building effect against Sionna RT's, on one scene: the tracer's radio map
([`rainuav.radio.reference.tracer`][rainuav.radio.reference.tracer]) or its path solver at the
pixel centres ([`rainuav.radio.reference.tracer_paths`][rainuav.radio.reference.tracer_paths]) as
the reference ([physics reference, section
12][12-terrain-buildings-diffraction-and-reflections])."""

from __future__ import annotations

from typing import Any

from rainuav.radio.reference.agreement import Agreement, agreement
from rainuav.radio.reference.tracer import (
    TracerMap,
    engine_gain,
    inside_buildings,
    isotropic_scenario,
    tracer_gain,
)
from rainuav.radio.reference.tracer_paths import path_gain
from rainuav.radio.scene.scenario import Scenario

__all__ = ["compare", "reference_maps"]


def reference_maps(
    scn: Scenario,
    *,
    samples: int = 2_000_000,
    seed: int = 0,
    max_depth: int = 2,
    ground: str = "none",
    reference: str = "map",
    step: int = 1,
    coefficient: str = "p526",
    runs: int = 2,
) -> tuple[TracerMap, TracerMap]:
    """The tracer's maps of a scene with and without its buildings, as
    [`compare()`][rainuav.radio.reference.comparison.compare] traces them (its arguments).

    Args:
        scn: The scene's scenario.
        samples: The tracer's rays a site (its radio map), or candidate rays (its paths).
        seed: The tracer's seed.
        max_depth: The interactions a path may have.
        ground: "none" or "pec".
        reference: "map" or "paths".
        step: With "paths", every how many pixels a centre is traced.
        coefficient: The tracer's wedge coefficient, "p526" or "sionna".
        runs: The path solver's runs.

    Returns:
        The maps with the buildings and without.

    Raises:
        ValueError: A reference other than "map" or "paths", or a coefficient other than
            these.
    """
    if reference not in ("map", "paths"):
        raise ValueError(f"reference is 'map' or 'paths' (got {reference!r})")
    from rainuav.radio.reference.tracer_wedge import checked

    checked(coefficient)
    kw: dict[str, Any] = {
        "samples": samples, "seed": seed, "max_depth": max_depth, "coefficient": coefficient,
    }  # fmt: skip
    gain: Any = tracer_gain
    if reference == "paths":
        gain = path_gain
        kw["step"] = step
        kw["runs"] = runs
    with_b = isotropic_scenario(scn, ground=ground)
    without = isotropic_scenario(scn, buildings=False, ground=ground)
    return gain(with_b, **kw), gain(without, **kw)


def compare(
    scn: Scenario,
    *,
    samples: int = 2_000_000,
    seed: int = 0,
    max_depth: int = 2,
    ground: str = "none",
    engine: str = "ray",
    reference: str = "map",
    step: int = 1,
    coefficient: str = "p526",
    runs: int = 2,
    traced: tuple[TracerMap, TracerMap] | None = None,
) -> Agreement:
    """The building effect of the ray engine (or another) against the tracer's on a scene.

    Each site once, isotropic
    ([`isotropic_scenario()`][rainuav.radio.reference.tracer.isotropic_scenario]), over no ground or
    a PEC one.

    Args:
        scn: The scene's scenario.
        samples: The tracer's rays a site (its radio map).
        seed: The tracer's seed.
        max_depth: The interactions a path may have.
        ground: "none" or "pec".
        engine: The engine compared ([`engine_gain()`][rainuav.radio.reference.tracer.engine_gain]).
        reference: "map", the tracer's radio map
            ([`tracer_gain()`][rainuav.radio.reference.tracer.tracer_gain]), or "paths", its path
            solver at every `step`-th pixel's centre
            ([`path_gain()`][rainuav.radio.reference.tracer_paths.path_gain]).
        step: With "paths", every how many pixels a centre is traced.
        coefficient: The tracer's wedge coefficient: the standard's ("p526") or its own as released
            ("sionna"; [`tracer_wedge`][rainuav.radio.reference.tracer_wedge]).
        runs: The path solver's runs, combined as the union of their paths.
        traced: The tracer's maps with and without the buildings, traced already
            ([`reference_maps()`][rainuav.radio.reference.comparison.reference_maps] with the
            same arguments, or read back by
            [`load_tracer_maps()`][rainuav.radio.reference.saved.load_tracer_maps]); None:
            traced here.

    Returns:
        The [`Agreement`][rainuav.radio.reference.agreement.Agreement], site by site.

    Raises:
        ValueError: A reference other than "map" or "paths".
    """
    if traced is None:  # traced before the engine's maps: a bad argument is refused first
        traced = reference_maps(
            scn, samples=samples, seed=seed, max_depth=max_depth, ground=ground,
            reference=reference, step=step, coefficient=coefficient, runs=runs,
        )  # fmt: skip
    with_b = isotropic_scenario(scn, ground=ground)
    without = isotropic_scenario(scn, buildings=False, ground=ground)
    return agreement(
        engine_gain(with_b, engine),
        engine_gain(without, engine),
        traced[0],
        traced[1],
        inside_buildings(with_b),
    )
