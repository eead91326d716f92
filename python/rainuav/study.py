"""``python -m rainuav.study NAME --out DIR``: run a study (a built-in one, or a study TOML file;
the format: the Studies page of the documentation, [`rainuav.studies.spec`][rainuav.studies.spec]).

Every case runs in its own folder ``DIR/cases/<case>`` (``result.json`` written last); a rerun skips
finished cases, so an interrupted study resumes. ``--workers`` cases run at once in spawned
processes (default: the cores, at most the cases); ``--ray ADDRESS`` runs each case as a task on a
Ray cluster instead (``pip install '.[ray]' from the rainuav clone``). ``--quick`` applies the
study's ``[quick]`` changes (short trainings, the ray engine). Writes ``report.md`` and then, last,
``results.csv`` in ``DIR``: a study folder holding ``results.csv`` is complete. The study file is
checked before any work starts: an unknown field, an empty axis or a value out of range is refused
with the field named (exit 2)."""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from rainuav import _cli
from rainuav._io import check_out_dir
from rainuav.errors import InvalidInputError


@dataclass
class StudyOptions:
    """What ``python -m rainuav.study STUDY`` takes besides the study (one docstring line per
    field = one flag, generated as ``train``'s are)."""

    out: Path | None = field(default=None, metadata={"required": True})
    """The study's folder: cases/, report.md and, last, results.csv."""
    workers: int | None = None
    """Cases run at once in spawned processes (default: the cores, at most the cases)."""
    quick: bool = False
    """Apply the study's [quick] changes (short trainings, the ray engine): a check that the
    study runs, in minutes."""
    ray: str | None = field(default=None, metadata={"metavar": "ADDRESS"})
    """Run each case as a Ray task: 'auto' (the cluster this machine is in), an address
    (ray://host:10001), or 'local' (a local instance)."""


def build_parser() -> argparse.ArgumentParser:
    """The command line: the study, then a flag for each field of
    [`StudyOptions`][rainuav.study.StudyOptions]."""
    from rainuav.studies.spec import BUILT_IN

    ap = _cli.Parser(
        prog="python -m rainuav.study",
        description=_cli.plain_help(__doc__),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    names = ", ".join(f"'{n}'" for n in BUILT_IN)
    ap.add_argument("study", help=f"a built-in study ({names}) or a study TOML file")
    _cli.add_fields(ap, StudyOptions)
    return ap


def main(argv: Sequence[str] | None = None) -> int:
    from rainuav.studies import load_study, run_study

    ap = build_parser()
    args = ap.parse_args(argv)

    def body() -> int:
        study = load_study(args.study)
        if args.quick:
            study = study.with_quick()
        workers = args.workers if args.workers is not None else (os.cpu_count() or 1)
        if workers < 1:
            raise InvalidInputError(f"--workers must be >= 1 (got {workers})")
        check_out_dir(args.out)  # before any work
        rows = run_study(
            study, args.out, workers=min(workers, len(study.cases())), ray_address=args.ray
        )
        print(f"{len(rows)} cases; wrote {(args.out / 'results.csv').resolve()}", file=sys.stderr)
        return 0

    return _cli.run(body, "finished cases are kept; the same command resumes the study")


if __name__ == "__main__":
    sys.exit(main())
