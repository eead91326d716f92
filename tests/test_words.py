"""The repository speaks of the software alone: no words about how it was developed and no
references to this repository's issue tracker in prose (Markdown, docstrings, comments) under
the folders users read. Identifiers such as ``start_new_session=True`` are code, not prose:
the word pattern needs a word boundary on both sides, which an identifier's underscores do not
give. The patterns themselves must name the words they look for; this file is outside the
folders it checks."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
WHERE = ["python", "crates", "docs", "benches", "experiments", "README.md", "BENCHMARKS.md",
         "CONTRIBUTING.md", "CHANGELOG.md"]  # fmt: skip
SUFFIXES = {".py", ".pyi", ".rs", ".md", ".toml", ".sh", ".txt", ".cff", ".yml"}
PROCESS_WORDS = re.compile(r"\bsessions?\b", re.IGNORECASE)
ISSUE = re.compile(r"\b(issues?|tickets?|PRs?|pull requests?)\s*#?\d+|(?<![\w&/])#\d{1,4}\b",
                   re.IGNORECASE)  # fmt: skip


def _files() -> list[Path]:
    out: list[Path] = []
    for name in WHERE:
        p = ROOT / name
        if p.is_file():
            out.append(p)
        elif p.is_dir():
            out += [f for f in p.rglob("*") if f.is_file() and f.suffix in SUFFIXES
                    and "target" not in f.parts]  # fmt: skip
    return sorted(out)


def _hits(pattern: re.Pattern[str]) -> list[str]:
    hits = []
    for f in _files():
        for k, line in enumerate(f.read_text(errors="replace").splitlines(), start=1):
            if pattern.search(line):
                hits.append(f"{f.relative_to(ROOT)}:{k}: {line.strip()[:120]}")
    return hits


def test_the_files_are_found() -> None:
    names = {f.name for f in _files()}
    assert {"README.md", "BENCHMARKS.md", "place.py", "lib.rs", "index.md"} <= names


@pytest.mark.parametrize(
    ("what", "pattern"),
    [("process word", PROCESS_WORDS), ("issue number", ISSUE)],
    ids=["process", "tracker"],
)
def test_no_process_words(what: str, pattern: re.Pattern[str]) -> None:
    hits = _hits(pattern)
    assert not hits, f"{len(hits)} lines speak of a {what}:\n" + "\n".join(hits)


def test_the_patterns_catch_what_they_should() -> None:
    # The checks above could not fail if the patterns matched nothing.
    assert PROCESS_WORDS.search("the seventh session's machine")
    assert not PROCESS_WORDS.search("subprocess.run(start_new_session=True)")
    assert ISSUE.search("(issue #29; python -m rainuav.fly)") and ISSUE.search("see #12")
    assert not ISSUE.search("colour '#1f77b4'") and not ISSUE.search("&#8212;")
