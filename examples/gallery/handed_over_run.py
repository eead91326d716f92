"""A run folder handed over: what rainuav refuses, and why.

A tiny training run (the ``paper`` preset, ray engine, 30 episodes), then copies of its folder
spoiled the ways a file from someone else can be: a checkpoint whose pickle would run code, a
map that needs a pickle, a map from another run swapped in, an edited ``config.toml``, a
truncated checkpoint. Each copy is given to ``python -m rainuav.evaluate``: the figure shows its
exit status and the one line it printed (the untouched copy flies). The code of the planted
checkpoint never runs: the marker file it would write is checked. About 20 s on 2 cores.
"""

import contextlib
import io
import re
import shutil
import sys
import tempfile
import textwrap
from pathlib import Path

import numpy as np
import torch
from _common import out_dir, stamp
from matplotlib.figure import Figure
from rainuav import evaluate, train


class Planted:
    """What a hostile pickle carries: unpickling it would write a file (the marker)."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return (Path.write_text, (self.marker, "the pickle ran"))


def quietly(main, argv: list[str]) -> tuple[int, str]:
    """A command's exit status and the last line it printed on standard error."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            rc = main(argv)
        except SystemExit as stop:  # argparse and the commands' own exits
            rc = stop.code
    lines = [ln for ln in err.getvalue().splitlines() if ln.strip()]
    return int(rc or 0), (lines[-1] if lines else "")


out = out_dir(__doc__, sys.argv[1:])
tiny = ["--scenario", "paper", "--engine", "ray", "--dqn.episodes", "30", "--eval-starts", "5",
        "--validate-starts", "5"]  # fmt: skip
rows = []
with tempfile.TemporaryDirectory() as tmp:
    tmp = Path(tmp)
    marker = tmp / "PWNED"
    quietly(train.main, [*tiny, "--out", str(tmp / "run")])
    quietly(train.main, [*tiny, "--rain-rate-mm-h", "100", "--out", str(tmp / "other")])

    def handed_over(name: str) -> Path:
        dst = tmp / name
        shutil.copytree(tmp / "run", dst, ignore=shutil.ignore_patterns(".lock"))
        cfg = (dst / "config.toml").read_text().replace(str(tmp / "run"), str(dst))
        (dst / "config.toml").write_text(cfg)
        return dst

    def planted_checkpoint(run: Path) -> None:
        torch.save({"agent": Planted(marker), "returns": []}, run / "checkpoint.pt")

    def pickled_map(run: Path) -> None:
        with np.load(run / "radiomap.npz") as z:
            data = {k: z[k] for k in z.files}
        data["sinr_db"] = np.array([Planted(marker)], dtype=object)
        with (run / "radiomap.npz").open("wb") as fh:
            np.savez(fh, **data)

    def swapped_map(run: Path) -> None:
        shutil.copy(tmp / "other" / "radiomap.npz", run / "radiomap.npz")

    def edited_config(run: Path) -> None:
        text = (run / "config.toml").read_text()
        (run / "config.toml").write_text(re.sub(r"(?m)^seed = 0$", "seed = 7", text))

    def truncated_checkpoint(run: Path) -> None:
        data = (run / "checkpoint.pt").read_bytes()
        (run / "checkpoint.pt").write_bytes(data[: len(data) // 2])

    spoils = {
        "as it was written": lambda run: None,
        "a checkpoint whose pickle would run code": planted_checkpoint,
        "a map that needs a pickle": pickled_map,
        "another run's map swapped in": swapped_map,
        "config.toml edited (seed 0 -> 7)": edited_config,
        "checkpoint.pt cut in half": truncated_checkpoint,
    }
    for k, (what, spoil) in enumerate(spoils.items()):
        run = handed_over(f"copy{k}")
        spoil(run)
        rc, line = quietly(evaluate.main, [str(run), "--out", str(tmp / f"eval{k}")])
        line = line.replace(str(run), "RUN")
        rows.append((what, rc, line))
        print(f"{what}: exit {rc}: {line}")
    assert not marker.exists(), "the planted pickle ran"

fig = Figure(figsize=(10.0, 4.6), layout="constrained")
ax = fig.subplots()
ax.set_axis_off()
ax.set_xlim(0, 1)
ax.set_ylim(len(rows) + 0.5, -0.8)
ax.text(0.0, -0.4, "the run folder handed over", weight="bold", fontsize=9)
ax.text(0.33, -0.4, "python -m rainuav.evaluate RUN", weight="bold", fontsize=9, family="monospace")
for i, (what, rc, line) in enumerate(rows):
    ok = rc == 0
    ax.text(0.0, i + 0.5, what, fontsize=8.5, va="center")
    said = "flies (exit 0)" if ok else "\n".join(textwrap.wrap(f"exit {rc}: {line}", 84)[:3])
    ax.text(0.33, i + 0.5, said, fontsize=7, va="center", family="monospace",
            color="tab:green" if ok else "tab:red")  # fmt: skip
stamp(fig, "handed_over_run.py")
fig.savefig(out / "handed_over_run.png", dpi=100)
print(f"wrote {out / 'handed_over_run.png'}")
