"""A training run's record: ``log.csv`` (one row per finished episode; cut back to the last
checkpoint when a run resumes), TensorBoard scalars and the progress bar."""

from __future__ import annotations

import csv
from pathlib import Path

from rainuav._io import write_atomic
from rainuav.errors import InvalidInputError

__all__ = ["RunLog", "cut_log"]


def cut_log(path: Path, done: int) -> None:
    """Cuts `log.csv` back to the episodes a checkpoint holds (`finished <= done`).

    The rows an interrupted run logged after its last checkpoint are logged again on resume. It is
    rewritten atomically; a row that does not parse ends the kept part.

    Args:
        path: The run's `log.csv`.
        done: The episodes the checkpoint holds.

    Raises:
        InvalidInputError: A log that is not a readable text file.
    """
    if not path.is_file():
        raise InvalidInputError(f"--resume: {path} is not a file (the run's log.csv)")
    try:
        with path.open(newline="", encoding="utf-8") as fh:
            rows = list(csv.reader(fh))
    except (UnicodeDecodeError, csv.Error) as err:
        raise InvalidInputError(
            f"--resume: {path} is not the run's log (not CSV text: {type(err).__name__}); "
            "move it away to start a new log"
        ) from None
    keep = rows[:1]
    for row in rows[1:]:
        try:
            finished = int(row[0])
        except (ValueError, IndexError):
            break
        if finished > done:
            break
        keep.append(row)

    def write(tmp: Path) -> None:
        with tmp.open("w", newline="") as fh:
            csv.writer(fh).writerows(keep)

    write_atomic(path, write)


class RunLog:
    """``log.csv`` (one row per finished episode), TensorBoard scalars and the progress bar."""

    def __init__(self, out: Path, resume: bool, total: int, done: int, progress: bool) -> None:
        """Opens the run's log, its TensorBoard scalars and the progress bar.

        Args:
            out: The run's folder.
            resume: Continue the log (cut back to `done`); False: a new one.
            total: The run's episodes (the bar's total).
            done: The episodes done so far.
            progress: A progress bar.

        Raises:
            InvalidInputError: A `log.csv` that is a folder or a `tb` that is a file (named).
        """
        from torch.utils.tensorboard import SummaryWriter

        tb, path = out / "tb", out / "log.csv"
        for p, folder, what in ((tb, True, "TensorBoard scalars"), (path, False, "log")):
            if p.exists() and p.is_dir() != folder:
                kind = "folder" if folder else "file"
                raise InvalidInputError(f"{p} must be a {kind} (the run's {what}); move it away")
        self.tb = SummaryWriter(str(tb))
        new = not (resume and path.exists())
        if not new:
            cut_log(path, done)
        self.fh = path.open("w" if new else "a", newline="")
        self.csv = csv.writer(self.fh)
        if new:
            self.csv.writerow(
                ["finished", "episode", "return", "steps", "reached", "epsilon", "seconds"]
            )
        self.bar = None
        if progress:
            from tqdm.auto import tqdm

            self.bar = tqdm(total=total, initial=done, desc="train", unit="ep")

    def episode(self, n_done: int, row: tuple[int, float, int, bool, float, float]) -> None:
        """Logs one finished episode.

        Args:
            n_done: The episodes finished, this one included.
            row: `(episode index, return, steps, reached, epsilon, seconds)`.
        """
        episode, ret, steps, reached, eps, seconds = row
        self.csv.writerow(
            [n_done, episode, f"{ret:.4f}", steps, int(reached), f"{eps:.5f}", f"{seconds:.2f}"]
        )
        self.tb.add_scalar("return", ret, n_done)
        self.tb.add_scalar("epsilon", eps, n_done)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
        self.fh.close()
        self.tb.close()
