"""A figure shown on more than one page is the same figure on each: the results page (or the
page whose run measured it) is the source, and every other page that quotes it must quote
what the source says. Each fact gives the patterns that find its figures at the source and
where they are quoted; every figure quoted must be one the source gives (a quoted range is its
two ends)."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.timeout(60)

NUM = r"([0-9]+(?:\.[0-9]+)?)"

FACTS: dict[str, dict[str, list[tuple[str, str]]]] = {
    "10 000 footprints loaded, walls found, pixels marked (s)": {
        "source": [
            ("docs/results.md", rf"\| 10 000 footprints loaded, merged.*? \| {NUM} and {NUM} s")
        ],
        "quotes": [("docs/guide/buildings.md", rf"an 8\.8 km square at 10 m in {NUM}-{NUM} s")],
    },
    "the uma ray map among 500 footprints, with and without them (s)": {
        "source": [
            (
                "docs/results.md",
                rf"among 500 footprints: roofs.*? \| {NUM} and {NUM} s, .*?\({NUM}-{NUM} s without",
            )
        ],
        "quotes": [
            ("docs/guide/buildings.md", rf"every mechanism takes {NUM}-{NUM} s \({NUM}-{NUM} s")
        ],
    },
    "the same 21 cells among all 10 000 footprints (s)": {
        "source": [
            ("docs/results.md", rf"among all 10 000 footprints, 200 x 200.*?\*\*{NUM} and {NUM} s")
        ],
        "quotes": [
            ("docs/guide/buildings.md", rf"all 10 000 footprints \(pixels of 44 m\) {NUM}-{NUM} s")
        ],
    },
    "a storm slice among the buildings (ms)": {
        "source": [("docs/results.md", rf"\| storm slices among the same buildings \| {NUM} ms")],
        "quotes": [("docs/guide/buildings.md", rf"a storm slice among\s+the 500 about {NUM} ms")],
    },
    "one network over 50 held-out storms, fixed destination (%)": {
        "source": [
            (
                "docs/results.md",
                rf"mean excess \(worst storm\) \| 100%, \*\*{NUM}%\*\*.*?\| 100%, {NUM}%",
            ),
            ("docs/results.md", rf"arriving \(one storm 80%\), \*\*{NUM}%\*\* over the optimum"),
            ("docs/results.md", rf"destination 100%, \*\*{NUM}%\*\* \(worst storm"),
        ],
        "quotes": [
            ("docs/guide/learning.md", rf"\| the network, trained once \| 100% \| \*\*{NUM}%\*\*"),
            ("docs/guide/learning.md", rf"built on an AVX-512 CPU \| 100% \| {NUM}%"),
            ("docs/guide/learning.md", rf"all 9000 episodes after a resume \| 100% \| {NUM}%"),
            (
                "docs/guide/learning.md",
                rf"default 55-minute budget at 4544 episodes \| 99\.6% \| {NUM}%",
            ),
            ("README.md", rf"100% arrive; {NUM}-{NUM}% over the space-time optimum in three full"),
            ("README.md", rf"\(straight line 5\.90%, replanning 0\.38%\); {NUM}% where"),
        ],
    },
    "the network trained on the AMD EPYC (s of training)": {
        "source": [("docs/results.md", rf"\| training \(9000 episodes\) \| 3515 s \| {NUM} s \|")],
        "quotes": [("docs/tutorials/train_fly.md", rf"page's {NUM} s is\s+the same command")],
    },
    "uma in clear air among levels: the experiment's and the study's flights": {
        "source": [
            (
                "docs/guide/altitude.md",
                rf"\| \*\*free, the start level chosen \(exact\)\*\* \| \*\*{NUM}\*\*",
            ),
            ("docs/guide/altitude.md", rf"\| uma \| 4\.9 \| 0 \| [^|]*\| 25 m \| {NUM}, "),
        ],
        "quotes": [("docs/guide/altitude.md", rf"costs {NUM} here against {NUM} there")],
    },
}


def _found(page: str, pattern: str) -> set[float]:
    text = (ROOT / page).read_text()
    m = re.search(pattern, text, flags=re.S)
    assert m, f"{page}: the figure is no longer where the pattern finds it ({pattern!r})"
    return {float(g) for g in m.groups()}


@pytest.mark.parametrize("fact", list(FACTS))
def test_a_figure_on_several_pages_is_the_one_its_source_gives(fact: str) -> None:
    source = set().union(*(_found(page, pat) for page, pat in FACTS[fact]["source"]))
    for page, pattern in FACTS[fact]["quotes"]:
        quoted = _found(page, pattern)
        assert quoted <= source, (
            f"{page} quotes {sorted(quoted)}; the source gives {sorted(source)}"
        )


def test_a_quote_that_drifts_is_found(tmp_path, monkeypatch) -> None:
    # The check fails where a page quotes another figure than its source's.
    (tmp_path / "docs" / "guide").mkdir(parents=True)
    (tmp_path / "docs" / "results.md").write_text("| storm slices among the same buildings | 29 ms")
    (tmp_path / "docs" / "guide" / "buildings.md").write_text(
        "a storm slice among the 500 about 37 ms"
    )
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    with pytest.raises(AssertionError, match=r"quotes \[37\.0\]; the source gives \[29\.0\]"):
        test_a_figure_on_several_pages_is_the_one_its_source_gives(
            "a storm slice among the buildings (ms)"
        )
