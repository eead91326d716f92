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
from pathlib import Path

from rainuav import _cli
from rainuav._io import check_out_dir
from rainuav.errors import InvalidInputError


def main(argv: Sequence[str] | None = None) -> int:
    from rainuav.studies import load_study, run_study
    from rainuav.studies.spec import BUILT_IN

    ap = argparse.ArgumentParser(
        prog="python -m rainuav.study",
        description=_cli.plain_help(__doc__),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    names = ", ".join(f"'{n}'" for n in BUILT_IN)
    ap.add_argument("study", help=f"a built-in study ({names}) or a study TOML file")
    ap.add_argument(
        "--out", type=Path, required=True,
        help="the study's folder: cases/, report.md and, last, results.csv",
    )  # fmt: skip
    ap.add_argument(
        "--workers", type=int, default=None,
        help="cases run at once in spawned processes (default: the cores, at most the cases)",
    )  # fmt: skip
    ap.add_argument(
        "--quick", action="store_true",
        help="apply the study's [quick] changes (short trainings, the ray engine): a check "
        "that the study runs, in minutes",
    )  # fmt: skip
    ap.add_argument(
        "--ray",
        default=None,
        metavar="ADDRESS",
        help="run each case as a Ray task: 'auto' (the cluster this machine is in), an "
        "address (ray://host:10001), or 'local' (a local instance)",
    )
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
