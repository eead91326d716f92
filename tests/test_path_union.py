"""Runs of the tracer's path solver combine as the union of the paths they found
([`rainuav.radio.reference.tracer_paths`][rainuav.radio.reference.tracer_paths], "Runs, and their
union"): brute force on small made-up runs, without the tracer."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

pytestmark = pytest.mark.timeout(60)


def test_a_path_found_by_two_runs_counts_once_and_one_found_by_either_counts() -> None:
    """Two runs of two links: a path both found (its delays a hundredth of ``DELAY_KEY_S``
    apart) counts once, a path only one run found counts, an invalid path (power 0) does not,
    and a link neither reached has no power (exact sums)."""
    from rainuav.radio.reference.tracer_paths import DELAY_KEY_S, union_power

    a = (np.array([[1e-6, 2e-6, 0.0], [0.0, 0.0, 0.0]]), np.array([[1.0, 0.5, 0.0], [0, 0, 0.0]]))
    b = (np.array([[1e-6 + DELAY_KEY_S / 100, 3e-6], [0.0, 0.0]]),
         np.array([[1.0, 0.25], [0.0, 0.0]]))  # fmt: skip
    got = union_power([a, b])
    assert got.tolist() == [1.75, 0.0]
    assert union_power([a]).tolist() == [1.5, 0.0]


def test_the_union_of_many_random_runs_is_the_power_of_the_distinct_paths_drawn() -> None:
    """Forty paths of one link, each found by each of eight runs with probability 0.3: the
    union's power is the sum over the paths any run found (brute force, to 1e-12), never less
    than one run's, and grows with the runs."""
    from rainuav.radio.reference.tracer_paths import union_power

    rng = np.random.default_rng(3)
    tau = np.sort(rng.uniform(1e-6, 5e-6, 40))
    power = rng.exponential(1.0, 40)
    found = rng.random((8, 40)) < 0.3
    runs = [(tau[None, f], power[None, f]) for f in found]
    union = union_power(runs)[0]
    assert union == pytest.approx(power[found.any(axis=0)].sum(), rel=1e-12)
    growing = [union_power(runs[:k])[0] for k in range(1, 9)]
    assert all(x <= y for x, y in itertools.pairwise(growing))
    assert min(union_power([r])[0] for r in runs) < union
