"""The documentation site's checks of every built page (``docs/hooks/pages.py``: a page that
loads from the network, links from the server's root, or shows a broken table or raw TeX fails
the build), and its formulas
(``docs/hooks/math.py``): TeX on the pages becomes MathML when the site is built, so they render
with no script and no network. Every formula of the physics
and conventions pages converts; a formula the converter cannot read fails with the page named;
and no formula is left as ASCII in a code span there (a code span holds a name, a command or a
value: the test lists the spans that look like formulas)."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[1] / "docs"
PAGES = ("physics.md", "conventions.md")

pytestmark = pytest.mark.timeout(60)


def _hook(name: str = "math"):
    spec = importlib.util.spec_from_file_location(f"docs_{name}", DOCS / "hooks" / f"{name}.py")
    assert spec and spec.loader
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _formulas(text: str) -> list[tuple[str, bool]]:
    """The page's ``$$...$$`` blocks and ``$...$`` inline formulas, as arithmatex finds them
    (outside code spans and fences)."""
    text = re.sub(r"```.*?```", "", text, flags=re.S)
    text = re.sub(r"`[^`]*`", "", text)
    blocks = re.findall(r"^\s*\$\$\n(.*?)\n\s*\$\$\s*$", text, flags=re.S | re.M)
    text = re.sub(r"^\s*\$\$\n.*?\n\s*\$\$\s*$", "", text, flags=re.S | re.M)
    inline = re.findall(r"(?<![\\$])\$(?!\$)(.+?)(?<![\\$])\$", text, flags=re.S)
    return [(b, True) for b in blocks] + [(i, False) for i in inline]


@pytest.mark.parametrize("page", PAGES)
def test_every_formula_on_the_page_becomes_mathml(page: str) -> None:
    hook = _hook()
    found = _formulas((DOCS / page).read_text())
    assert len(found) > (100 if page == "physics.md" else 10), len(found)
    for tex, display in found:
        out = hook.mathml(tex, display, page)
        assert out.startswith("<math") and out.endswith("</math>"), tex
        assert f'display="{"block" if display else "inline"}"' in out


def test_arithmatex_marks_become_mathml_in_the_built_page() -> None:
    hook = _hook()
    page = (
        '<p>A <span class="arithmatex">\\(k_0 = 2\\pi f / c\\)</span> and</p>\n'
        '<div class="arithmatex">\\[\\gamma = k R^\\alpha &lt; 1\\]</div>'
    )
    out = hook.formulas_to_mathml(page, "p.md")
    assert out.count("<math") == 2 and 'arithmatex">\\(' not in out
    assert '<span class="arithmatex"><math' in out and '<div class="arithmatex"><math' in out
    assert "&#x0003C;" in out or "&lt;" in out  # the escaped "<" is read as the operator


@pytest.mark.parametrize(
    ("tex", "says"),
    [
        (r"\frac{a}{b", "unbalanced braces"),
        (r"a = \notacommand b", r"cannot read \notacommand"),
        (r"\begin{aligned} a &= b \end{aligned}", "cannot read an alignment & outside an array"),
    ],
)
def test_a_formula_it_cannot_read_fails_naming_the_page(tex: str, says: str) -> None:
    hook = _hook()
    with pytest.raises(ValueError, match=re.escape(f"guide/x.md: {says}")):
        hook.mathml(tex, False, "guide/x.md")


@pytest.mark.parametrize("page", PAGES)
def test_no_formula_is_left_as_ascii_in_a_code_span(page: str) -> None:
    text = re.sub(r"```.*?```", "", (DOCS / page).read_text(), flags=re.S)
    spans = re.findall(r"`([^`]+)`", text)
    # A name (`rss_std_db`, `--ground`, `rainuav.radio...`), a command, an assignment of an
    # option or a value (`roughness_m = 0`, `-10`, `74.319 - 19.932j`) is not a formula.
    name = re.compile(r"^(python |-)?[\w.:/=\"\- ,]*$")
    looks = [s for s in spans if not name.match(s) and re.search(r"[\^*]|\bsqrt|\bexp\(", s)]
    assert not looks, looks


def test_a_block_arithmatex_did_not_read_fails_the_build() -> None:
    # A $$ block in a list item indented by two spaces stays text: the hook refuses the page,
    # where $$ inside code (a shell's variable) is left alone.
    hook = _hook()
    assert hook.formulas_to_mathml("<pre><code>echo $$</code></pre>", "p.md")
    with pytest.raises(ValueError, match=r"p\.md: a \$\$ block arithmatex did not read"):
        hook.formulas_to_mathml("<li>the field\n$$\nD = 1\n$$</li>", "p.md")


def test_a_page_that_loads_from_the_network_is_found() -> None:
    # What the theme wrote before the site was made to open offline: Google's fonts and the
    # offline plugin's worker polyfill from a CDN; links to other sites are not fetched.
    hook = _hook("pages")
    page = (
        '<link rel="preconnect" href="https://fonts.gstatic.com" crossorigin>'
        '<link rel="stylesheet" href="https://fonts.googleapis.com/css?family=Roboto">'
        '<script src="https://unpkg.com/iframe-worker/shim"></script>'
        '<script src="../javascripts/iframe-worker.js"></script>'
        '<a href="https://github.com/rainuav/rainuav">GitHub</a>'
    )
    assert hook.network_fetches(page) == [
        "fonts.gstatic.com",
        "fonts.googleapis.com/css?family=Roboto",
        "unpkg.com/iframe-worker/shim",
    ]
    assert hook.network_fetches('<link rel="stylesheet" href="../assets/main.css">') == []


def test_root_links_broken_tables_and_raw_tex_are_found() -> None:
    # What the site showed before: a table cut by a blank line (raw "|" text), a formula in
    # a list item that arithmatex did not read, root-absolute links; code is left alone.
    hook = _hook("pages")
    page = (
        '<a href="/assets/x.css">x</a><p>| test | within 0.01 dB | yes |</p>'
        "<p>the field $F(X) = 2j \\sqrt{X}$ here</p><pre><code>echo $HOME \\n</code></pre>"
        '<a href="../physics.html">ok</a><a href="https://github.com/x">ok</a>'
    )
    found = hook.problems(page)
    assert len(found) == 3, found
    assert "links to /assets/x.css from the root" in found[0]
    assert found[1].startswith("a table that did not render") and "formula left as text" in found[2]
    assert hook.problems('<a href="/assets/x.css">x</a>', is_404=True) == []
    assert hook.problems("<table><tr><th></th><th>why</th></tr></table>") == [
        "a table column without a heading: 'why'"
    ]
    assert hook.problems("<table><tr><th><code>rain_cell</code></th></tr></table>") == []


def test_a_summary_is_the_whole_first_sentence() -> None:
    # The API reference's summary tables show a docstring's first line: the griffe extension
    # puts the whole first sentence there (brackets, code and "e.g." do not end it).
    hook = _hook("summaries")
    doc = (
        "The field a task flies on: the ``signal`` map (e.g. a preset's. map) of ``radio_map``,\n"
        "or the one raw array given (``sinr_db``. or ``sir_db``). Then more.\n\nArgs:\n    x: y."
    )
    out = hook.with_summary_line(doc)
    first = out.split("\n")[0]
    assert first.endswith("(``sinr_db``. or ``sir_db``).") and first.startswith("The field")
    assert out.split("\n")[1] == "Then more." and out.endswith("Args:\n    x: y.")
    one = "One line.\nThen another line."
    assert hook.with_summary_line(one) == one  # the first line is the sentence already
    assert hook.with_summary_line("One line. Then another\nline.") == one
    # A sentence that starts with a code span is prose too; a list or a table is not.
    code = "``action`` as an int if it is one\ninteger (a Python one). More."
    assert hook.with_summary_line(code).split("\n")[0] == (
        "``action`` as an int if it is one integer (a Python one)."
    )
    listed = "- one item\n  goes on. Here."
    assert hook.with_summary_line(listed) == listed


def test_a_gallery_notebook_runs_as_a_kernel_would_run_it(tmp_path) -> None:
    # docs/gallery.py writes each example as a notebook too: run its code cells one by one in
    # one namespace, from the clone's root, as a notebook's kernel does (here writing into a
    # folder of the test's: the script's --out).
    import json
    import subprocess
    import sys

    spec = importlib.util.spec_from_file_location("docs_gallery", DOCS / "gallery.py")
    assert spec and spec.loader
    gallery = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gallery)
    nb = gallery.notebook(DOCS.parent / "examples" / "gallery" / "rain_against_p838.py")
    (tmp_path / "nb.ipynb").write_text(json.dumps(nb))
    assert [c["cell_type"] for c in nb["cells"]] == ["markdown", "code", "code"]
    kernel = (
        "import json, sys\n"
        f"cells = json.load(open({str(tmp_path / 'nb.ipynb')!r}))['cells']\n"
        "ns = {'__name__': '__main__'}\n"
        "for k, c in enumerate(cells):\n"
        "    if c['cell_type'] == 'code':\n"
        "        exec(compile(''.join(c['source']), f'<cell {k}>', 'exec'), ns)\n"
        f"        sys.argv[1:] = ['--out', {str(tmp_path / 'out')!r}]\n"
    )
    run = subprocess.run([sys.executable, "-c", kernel], cwd=DOCS.parent, capture_output=True,
                         text=True, timeout=120)  # fmt: skip
    assert run.returncode == 0, run.stderr[-2000:]
    assert (tmp_path / "out" / "rain_against_p838.png").stat().st_size > 10_000
