"""Storms of the distribution as a training run needs them
([`StormPool`][rainuav.world.pool.StormPool]): the worlds of a network that learns to fly any storm
(``python -m rainuav.train --preset storms``).

Seeds: training storms are drawn in [`TRAINING_SEEDS`][rainuav.world.pool.TRAINING_SEEDS];
[`VALIDATION_SEEDS`][rainuav.world.pool.VALIDATION_SEEDS] are for choices made while building a
learner; from 1 000 000 the evaluation storms
([`rainuav.radio.scene.storms.EVAL_SEEDS_FROM`][rainuav.radio.scene.storms.EVAL_SEEDS_FROM]), never
trained or tuned on."""

from __future__ import annotations

import dataclasses
import time
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any

import numpy as np

from rainuav._checks import check_fits
from rainuav.errors import InvalidInputError
from rainuav.nav.field import SignalField
from rainuav.radio.outputs.levelmaps import LevelStack
from rainuav.radio.outputs.timemap import build_radio_map_series
from rainuav.radio.scene.scenario import Scenario
from rainuav.world import (
    World,
    check_spec,
    level_field,
    make_scenario,
    series_instants,
    spec_of,
    task_of,
    world_from,
)

__all__ = ["TRAINING_SEEDS", "VALIDATION_SEEDS", "StormPool", "calm", "is_calm"]


TRAINING_SEEDS = (0, 900_000)
"""A storm pool draws its storms' seeds uniformly in [lo, hi): the training storms."""
VALIDATION_SEEDS = (900_000, 1_000_000)
"""Storms for choices made while building a learner (validation); never drawn for training. The
evaluation storms start at 1 000 000
([`rainuav.radio.scene.storms.EVAL_SEEDS_FROM`][rainuav.radio.scene.storms.EVAL_SEEDS_FROM])."""


CALM_STREAM = 0xCA1A
"""The second key of the random stream that says whether a pool's storm is flown calm."""


def is_calm(storm_seed: int, share: float) -> bool:
    """Whether a storm pool flies a storm calm (a function of the seed: a resumed pool rebuilds it).

    One uniform draw of `numpy.random.default_rng([storm_seed, CALM_STREAM])` below `share`.

    Args:
        storm_seed: The storm.
        share: The pool's `calm_share`.

    Returns:
        True for a calm storm.
    """
    if share <= 0:
        return False
    return bool(np.random.default_rng([storm_seed, CALM_STREAM]).random() < share)


def calm(scn: Scenario) -> Scenario:
    """A storm scenario with its cells left out: its uniform background rain alone.

    U(0, 10) mm/h in the storm distribution, the same over the whole flight.

    Args:
        scn: The storm's scenario.

    Returns:
        The calm scenario.
    """
    medium = dataclasses.replace(scn.medium, kind="homogeneous", cells=[])
    return dataclasses.replace(scn, medium=medium)


class StormPool:
    """Storms of the distribution as a training run needs them: ``spec.storm_pool`` storms in one
    bank ([`SignalField.bank`][rainuav.nav.fieldmakers.FieldMakers.bank]; world ``k``'s slot is
    renewed with [`renew()`][rainuav.world.pool.StormPool.renew]), their seeds drawn from
    ``numpy.random.default_rng(seed)`` in [`TRAINING_SEEDS`][rainuav.world.pool.TRAINING_SEEDS] (a
    share ``spec.calm_share`` of them flown calm: [`is_calm()`][rainuav.world.pool.is_calm],
    [`calm()`][rainuav.world.pool.calm]). The next storm is mapped in a background thread while
    training goes on (the engine releases the GIL); the maps are not cached on disk (each storm is
    flown once). ``map_seconds``: the time spent mapping storms, and ``wait_seconds``: the part
    training waited for; ``flown``: the seeds of the storms put in a slot, in order (not the one
    being mapped next).

    Among flight levels (``spec.altitudes_m``) a storm is the maps of every level in time
    ([`rainuav.radio.outputs.levelmaps.LevelStack`][rainuav.radio.outputs.levelmaps.LevelStack]) and
    the bank a [`SignalField.bank()`][rainuav.nav.fieldmakers.FieldMakers.bank] with their
    altitudes; the pool's memory (the slots, the storm being mapped and the one being put) is
    checked once the first storm is mapped."""

    def __init__(self, spec: Any, seed: int, *, progress: bool = False) -> None:
        """A pool of training storms, the first mapped at once and the next in a background thread.

        Args:
            spec: The run's spec (its `storm_pool`, `calm_share`, levels and task).
            seed: The run's seed (the storms' seed stream).
            progress: A line on standard error per storm mapped.

        Raises:
            InvalidInputError: `storm_pool` below 1.
        """
        check_spec(spec)
        if spec.storm_pool < 1:
            raise InvalidInputError("a storm pool needs storm_pool >= 1")
        self.spec = spec
        self.rng = np.random.default_rng(seed)
        self.map_seconds = self.wait_seconds = 0.0
        self.seeds: list[int] = []
        self.flown: list[int] = []
        first = [self._build(self._draw())]
        one = _maps(first[0][1])
        check_fits(f"storm_pool = {spec.storm_pool}", 3 * (spec.storm_pool + 2) * one.nbytes,
                   "lower storm_pool")  # fmt: skip
        first += [self._build(self._draw()) for _ in range(spec.storm_pool - 1)]
        field = first[0][1].field
        self.task = first[0][1].task
        self.bank: SignalField
        if field.altitudes_m is not None:
            stacks = np.stack([_maps(w) for _, w in first])
            self.bank = SignalField.bank(stacks, field.t_s, field.extent, field.altitudes_m)
        else:
            assert isinstance(field, SignalField) and field.varies  # a storm moves
            self.bank = SignalField.bank([w.field.db for _, w in first], field.t_s, field.extent)
        self.seeds = [k for k, _ in first]
        self.flown.extend(self.seeds)
        self._executor = ThreadPoolExecutor(1)
        self._next_seed = self._draw()
        self._next: Future[Any] = self._executor.submit(self._build, self._next_seed)

    def _draw(self) -> int:
        return int(self.rng.integers(*TRAINING_SEEDS))

    def _build(self, storm_seed: int) -> tuple[int, World]:
        t0 = time.perf_counter()
        spec = dataclasses.replace(spec_of(self.spec), storm_seed=storm_seed, storm_pool=0)
        scn = make_scenario(spec)
        if is_calm(storm_seed, self.spec.calm_share):
            scn = calm(scn)
        if spec.altitudes_m:  # in time even where calm: every slot holds one instants' series
            source = LevelStack.of(level_field(scn, series_instants(spec), cache=False)[1], scn)
        else:
            source = build_radio_map_series(scn, series_instants(spec), cache=False)
        world = world_from(source, task_of(spec))
        self.map_seconds += time.perf_counter() - t0
        return storm_seed, world

    def world(self) -> World:
        """The pool as one world: its field the bank.

        Returns:
            The [`World`][rainuav.world.World], with the spec's `observation` and `random_goal`.
        """
        return World(
            None, self.bank, self.task, self.spec.observation, self.spec.random_goal, pool=self
        )

    def renew(self, slot: int) -> int:
        """Puts the next storm in a slot, waiting for its maps, and starts mapping the one after.

        Args:
            slot: The world's slot in the bank.

        Returns:
            The new storm's seed.
        """
        t0 = time.perf_counter()
        storm_seed, world = self._next.result()
        self.wait_seconds += time.perf_counter() - t0
        self.bank.put(slot, _maps(world))
        self.seeds[slot] = storm_seed
        self.flown.append(storm_seed)
        self._next_seed = self._draw()
        self._next = self._executor.submit(self._build, self._next_seed)
        return self.seeds[slot]

    def state_dict(self) -> dict[str, Any]:
        """Plain data that restores the pool (`load_state_dict()`).

        Returns:
            The storms in the slots, the one being mapped next, the seed stream's state and the
            storms flown.
        """
        return {
            "seeds": list(self.seeds),
            "next_seed": self._next_seed,
            "rng": self.rng.bit_generator.state,
            "flown": list(self.flown),
        }

    def load_state_dict(self, d: dict[str, Any]) -> None:
        """Restores a [`state_dict()`][rainuav.world.pool.StormPool.state_dict].

        The storms of the slots that differ are mapped again (maps are a function of their seed),
        and the next one.

        Args:
            d: The saved state.

        Raises:
            ValueError: Anything malformed (seeds that are not training storms, lists of another
                length).
        """
        seeds, nxt = d["seeds"], d["next_seed"]
        ok = isinstance(seeds, list) and len(seeds) == len(self.seeds)
        if not ok or not all(isinstance(k, int) and 0 <= k < TRAINING_SEEDS[1] for k in seeds):
            raise ValueError(f"pool.seeds must be {len(self.seeds)} training storm seeds")
        if not (isinstance(nxt, int) and 0 <= nxt < TRAINING_SEEDS[1]):
            raise ValueError("pool.next_seed must be a training storm seed")
        if not self._next.cancel():
            self._next.result()  # the storm being mapped finishes; the state says what follows
        for slot, k in enumerate(seeds):
            if k != self.seeds[slot]:
                self.bank.put(slot, _maps(self._build(k)[1]))
                self.seeds[slot] = k
        self.rng.bit_generator.state = d["rng"]
        self.flown = [int(k) for k in d["flown"]]
        self._next_seed = nxt
        self._next = self._executor.submit(self._build, nxt)

    def close(self) -> None:
        """Stops the background mapping (the storm being mapped is finished first)."""
        self._executor.shutdown(wait=True, cancel_futures=True)


def _maps(world: World) -> np.ndarray:
    """What a storm puts in a bank's slot: its maps in time (T, H, W), or among levels every
    level's (T, L, H, W)."""
    if world.field.altitudes_m is not None:
        return np.asarray(world.source.sinr_db)  # type: ignore[union-attr]
    return np.asarray(world.field.db)  # type: ignore[union-attr]
