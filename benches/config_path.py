"""How often a configuration's path through ``python -m rainuav.train`` goes back up a layer.

The path: every call of a rainuav function that is handed the configuration or a part of it
(an argument that is a ``TrainConfig``, ``WorldSpec``, ``DQNConfig`` or ``NavConfig``), in order,
from the entry point until the training loop starts (``rainuav.rl.loop.run_loop``): where a
configuration becomes a world, an environment and an agent. Each call is labelled with its
module's layer (``tests/test_layout.py``:
base < medium, antenna < pwe < radio, nav < world < rl < studies < entry; base modules, the
errors and the checks, are left out), and the path "goes back up" at each call into a higher
layer than the call before it: control returned from below and came down again, or a lower
layer called up. Round trips between ``rl`` and ``nav`` are the calls up from ``nav`` into
``rl``.

    python benches/config_path.py            # a tiny run of the uma preset (ray engine)

Prints the count, the round trips and the layer sequence (consecutive calls in one group
merged). ``tests/test_layout.py`` asserts the count stays under 10.
"""

from __future__ import annotations

import itertools
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from test_layout import LAYERS, group  # noqa: E402


def trace_config_path(argv: list[str]) -> list[tuple[str, str]]:
    """(group, function) of every rainuav call from ``rainuav.train.main(argv)`` until the
    training loop starts, base modules left out."""
    import rainuav
    from rainuav import train
    from rainuav.nav.task import NavConfig
    from rainuav.rl.config import DQNConfig, TrainConfig
    from rainuav.world import WorldSpec

    pkg = str(Path(rainuav.__file__).parent)
    config_types = (TrainConfig, WorldSpec, DQNConfig, NavConfig)
    calls: list[tuple[str, str]] = []

    class Stop(Exception):
        pass

    def profile(frame: Any, event: str, arg: Any) -> None:
        if event != "call":
            return
        code = frame.f_code
        if not code.co_filename.startswith(pkg):
            return
        rel = Path(code.co_filename).relative_to(Path(pkg).parent).with_suffix("")
        parts = rel.parts[:-1] if rel.parts[-1] == "__init__" else rel.parts
        name = ".".join(parts)
        if code.co_name == "run_loop" and name == "rainuav.rl.loop":
            raise Stop
        g = group(name)
        args = [frame.f_locals.get(v) for v in code.co_varnames[: code.co_argcount]]
        if g != "base" and any(isinstance(a, config_types) for a in args):
            calls.append((g, f"{name}.{code.co_name}"))

    sys.setprofile(profile)
    try:
        train.main(argv)
    except Stop:
        pass
    finally:
        sys.setprofile(None)
    return calls


def ups(calls: list[tuple[str, str]]) -> tuple[int, int]:
    """(calls into a higher layer than the call before, of them from nav into rl), each
    distinct pair of functions counted once."""
    seen = set()
    for (a, f), (b, g) in itertools.pairwise(calls):
        if LAYERS[b] > LAYERS[a]:
            seen.add((a, f, b, g))
    return len(seen), sum((a, b) == ("nav", "rl") for a, _, b, _ in seen)


def measure() -> tuple[int, int, list[str]]:
    with tempfile.TemporaryDirectory() as tmp:
        argv = [
            "--scenario", "uma", "--engine", "ray", "--episodes", "2", "--lanes", "2",
            "--eval-starts", "2", "--validate-every", "0", "--out", str(Path(tmp) / "run"),
        ]  # fmt: skip
        calls = trace_config_path(argv)
    up, trips = ups(calls)
    merged = [g for i, (g, _) in enumerate(calls) if i == 0 or calls[i - 1][0] != g]
    return up, trips, merged


if __name__ == "__main__":
    up, trips, merged = measure()
    print(f"back up a layer: {up} times, {trips} of them from nav into rl")
    print(" -> ".join(merged))
