"""What a resumed run may change: its configuration against the one its checkpoint saved."""

from __future__ import annotations

from typing import Any

from rainuav.rl.config import TrainConfig, flat, flat_fields

__all__ = ["RESUME_MAY_DIFFER", "config_diff"]

RESUME_MAY_DIFFER = ("device", "out", "time_budget_s")
"""Fields a resumed run may change (the rest must equal the checkpoint's): the device, the
folder's path (a run folder moved or copied elsewhere resumes where it now is; its results do
not depend on where it lives) and the wall-clock budget (a run its budget stopped, on a slower
machine, continues with a larger one to the episodes it was given, as if it had never
stopped)."""


def config_diff(saved: dict[str, Any], cfg: TrainConfig, ignore: tuple[str, ...] = ()) -> list[str]:
    """The fields where a configuration differs from a run's saved one.

    Args:
        saved: The run's saved configuration, in any form
            [`flat_fields()`][rainuav.rl.config.flat_fields] reads.
        cfg: The configuration given.
        ignore: Fields allowed to differ.

    Returns:
        One `"name: saved -> given"` line a field (`task.x`, `dqn.x` for the task's and the
        learner's).
    """

    def same_form(d: dict[str, Any]) -> dict[str, Any]:  # a point read back is a list
        return {k: tuple(v) if isinstance(v, list) else v for k, v in d.items()}

    old = same_form(flat_fields(saved, "saved configuration"))
    new = same_form(flat(cfg))
    return [
        f"{key}: {old.get(key)!r} -> {new.get(key)!r}"
        for key in sorted(set(old) | set(new))
        if key not in ignore and old.get(key) != new.get(key)
    ]
