"""Shared test settings: deterministic property tests, and one radio-map cache per test
session (so a map several tests need, such as the paper preset's, is built once, and no test
writes into the user's own cache)."""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from hypothesis import settings


def _share_the_cores() -> None:
    """Under pytest-xdist, each worker's native thread pools get its share of the cores (the
    Rust core's rayon pool, read when first used, and the linear algebra's, through
    threadpoolctl), and the commands the tests start inherit it. Two workers that each spun
    two threads on two cores spent CPU on waiting: the Gaussian-process tests took 27 s of CPU
    with the default pools against 17 s with one thread, in the same wall time."""
    workers = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1"))
    if workers <= 1:
        return
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    share = str(max(1, (cores or 1) // workers))
    for var in ("RAYON_NUM_THREADS", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, share)
    from threadpoolctl import threadpool_limits

    threadpool_limits(int(os.environ["OPENBLAS_NUM_THREADS"]))


_share_the_cores()

# Property tests call into Rust: keep them deterministic and quick in CI.
settings.register_profile("rainuav", max_examples=60, deadline=None, derandomize=True)
settings.load_profile("rainuav")


# The test files that take longest, longest first (seconds of a whole run, `python -m pytest
# -n 2 --dist loadfile --junitxml=...`, summed per file, 2026-12-04; the tracer's three files
# count as the one unit they run as): the rest follow in pytest's order. Each worker takes whole
# files in the order collected (the Makefile's `--no-loadscope-reorder`: by default
# pytest-xdist sends the files with the most tests first, which left a few long end-to-end
# files to the end, one worker running them while the other idled). A list out of date costs
# only that balance.
LONGEST_FIRST = (
    "test_study.py", "test_tutorials.py", "test_agent_train.py", "test_measured.py",
    "test_hostile_inputs.py", "test_tracer_paths.py", "test_tracer.py", "test_tracer_wedge.py",
    "test_terrain.py", "test_levels_learner.py", "test_engines.py", "test_wedge_fullwave.py",
    "test_levels.py", "test_spread.py", "test_buildings.py", "test_one_network.py",
    "test_radiomap.py", "test_levels_storms.py", "test_readme.py", "test_places.py",
    "test_timemap.py", "test_two_scale.py", "test_geotiff.py",
)  # fmt: skip


# Files that share an expensive start run on one worker: the reference ray tracer's (its LLVM
# backend starts once a process: the two main tracer files took 67 s in one process, 76 s in two).
TOGETHER = dict.fromkeys(
    ("test_tracer.py", "test_tracer_paths.py", "test_tracer_wedge.py"), "tracer"
)


def pytest_xdist_make_scheduler(config: pytest.Config, log: object) -> object:
    """Under ``--dist loadfile``, whole files to a worker as before, with the files of
    [`TOGETHER`] as one unit."""
    if config.getvalue("dist") != "loadfile":
        return None
    from xdist.scheduler import LoadFileScheduling

    class _Together(LoadFileScheduling):
        def _split_scope(self, nodeid: str) -> str:
            scope = super()._split_scope(nodeid)
            return TOGETHER.get(Path(scope).name, scope)

    return _Together(config, log)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """The longest files first (a stable sort: each file's tests keep their order)."""
    rank = {name: i for i, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))


@pytest.fixture(scope="session")
def session_cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The session's radio-map cache directory."""
    return tmp_path_factory.mktemp("rainuav-cache")


@pytest.fixture(autouse=True)
def _session_cache_dir(session_cache: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("RAINUAV_CACHE_DIR", str(session_cache))


@pytest.fixture(autouse=True)
def _one_torch_thread() -> Iterator[None]:
    """The tests' networks are tiny: one torch thread is several times faster than two (no
    synchronisation; the tests that fly untrained networks took 15-20 s with two threads on a
    busy 2-core machine against under 1 s with one) and keeps results bit-reproducible.
    (rainuav.rl.loop.train sets this itself for a run and restores it afterwards.) Only where a
    test module has imported torch (before each test, and after it for a test that imported it
    itself): the physics tests run without it."""

    def one() -> None:
        torch = sys.modules.get("torch")
        if torch is not None and torch.get_num_threads() != 1:
            torch.set_num_threads(1)

    one()
    yield
    one()


def _best_return_of_every_sequence(env, start, horizon: int) -> float:
    """The best return over every sequence of ``horizon`` moves from ``start`` (4^horizon of
    them), each flown through the environment's own transitions (an independent route to the
    optimum: no dynamic programme). The sequences fly side by side through ``step_batch``, the
    stepper ``step()`` calls with one UAV; the best sequence is flown again through ``step()``
    and must earn the same return exactly."""
    import itertools

    import numpy as np

    seqs = np.array(list(itertools.product(range(4), repeat=horizon)), dtype=np.int64)
    n = len(seqs)
    starts = np.repeat(np.asarray(start, dtype=np.float64).reshape(1, 2), n, axis=0)
    offset, t = np.zeros((n, 2), dtype=np.int64), np.zeros(n, dtype=np.int64)
    level = np.zeros(n, dtype=np.int64)
    ret, alive = np.zeros(n), np.ones(n, dtype=bool)
    for k in range(horizon):
        r = env.step_batch(starts, offset, level, t, seqs[:, k])
        ret += np.where(alive, r["reward"], 0.0)
        alive &= ~(r["terminated"] | r["truncated"])
        offset, t = r["offset"], r["t"]
    best = int(np.argmax(ret))
    env.reset(options={"start_m": np.asarray(start, dtype=np.float64)})
    again = 0.0
    for a in seqs[best]:
        _, r1, term, trunc, _ = env.step(int(a))
        again += r1
        if term or trunc:
            break
    assert again == ret[best]
    return float(ret[best])


@pytest.fixture
def best_return_of_every_sequence():
    """[`_best_return_of_every_sequence`]: the brute-force optimum of a small task."""
    return _best_return_of_every_sequence
