"""One helper: a loop whose rounds write to their own slices, run on threads (numpy releases
the GIL inside its array operations, so the per-cell loops of a map share the machine's cores
where the Rust core has finished)."""

from __future__ import annotations

import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

__all__ = ["each"]


def each(n: int, body: Callable[[int], None]) -> None:
    """Calls ``body(k)`` for every ``k < n``, on up to as many threads as this process may use cores
    (one: in order, on this thread). The rounds must not share what they write; any error is
    raised here."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    threads = min(n, cores or 1)
    if threads <= 1:
        for k in range(n):
            body(k)
        return
    with ThreadPoolExecutor(threads) as pool:
        for done in [pool.submit(body, k) for k in range(n)]:
            done.result()
