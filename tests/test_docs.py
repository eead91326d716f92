"""The documentation as a reader meets it: every public module has an API page in the
navigation, no reference leaves the repository, no docstring carries markup the site prints
raw, lists render as lists, the gallery page is current and its examples write outside
``docs/``, the version is the package's, and figures shared between pages agree."""

from __future__ import annotations

import ast
import importlib.util
import re
from pathlib import Path

import pytest
import tomllib

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
PACKAGE = ROOT / "python" / "rainuav"


def _load(name: str):
    spec = importlib.util.spec_from_file_location(name, DOCS / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)  # type: ignore[union-attr]
    return mod


def test_every_public_module_has_an_api_page_in_the_navigation() -> None:
    api = _load("api_pages")
    names = api.public_modules()
    assert {"rainuav.radio.scene.cell", "rainuav.radio.scene.storms", "rainuav.radio.scene.radar",
            "rainuav.radio.scene.rategrid", "rainuav.nav.views", "rainuav.rl.networks",
            "rainuav.world.pool"} <= set(names)  # fmt: skip
    pages = {p.stem for p in (DOCS / "api").glob("*.md")}
    assert pages == set(names), "run python docs/api_pages.py"
    yml = (ROOT / "mkdocs.yml").read_text()
    assert api.nav(names) in yml, "run python docs/api_pages.py"
    for n in names:
        assert (DOCS / "api" / f"{n}.md").read_text() == api.page(n)


def _texts() -> list[tuple[Path, str]]:
    """Every file a user of the repository reads: code, docstrings, pages, examples."""
    out = []
    for pattern in ("python/**/*.py", "python/**/*.pyi", "python/**/*.toml", "crates/**/*.rs",
                    "docs/**/*.md", "docs/**/*.py", "examples/**/*.py", "tests/**/*.py",
                    "benches/**/*.py", "experiments/**/*.py", "*.md", "mkdocs.yml",
                    "pyproject.toml"):  # fmt: skip
        for p in ROOT.glob(pattern):
            if "target" not in p.parts and p.name != "test_docs.py":
                out.append((p, p.read_text(errors="replace")))
    return out


def test_no_reference_leaves_the_repository() -> None:
    # The physics reference and the learner's notes are pages of the site (docs/physics.md,
    # docs/guide/learning.md): nothing cites a file outside the repository or one deleted.
    bad = re.compile(r"PHYSICS\.md|shared/paper|\.\./shared|docs/learner\.md")
    hits = [f"{p.relative_to(ROOT)}:{t[:m.start()].count(chr(10)) + 1}"
            for p, t in _texts() for m in bad.finditer(t)]  # fmt: skip
    assert not hits, hits
    # Every relative link of a page names a file of the repository.
    link = re.compile(r"\]\((?!https?:|mailto:|#)([^)#\s]+)")
    for p in DOCS.rglob("*.md"):
        for m in link.finditer(p.read_text()):
            target = m.group(1)
            if p.name == "gallery.md" and target.startswith("gallery/"):
                # A figure `make docs` draws: the example that draws it exists.
                target = f"../examples/gallery/{Path(target).stem}.py"
            elif target.startswith("../gallery/"):
                # A figure `make docs` draws: by a gallery example, or by a tutorial's script.
                stem = Path(target).stem
                tutorial = DOCS / "tutorials" / f"{stem}.py"
                example = ROOT / "examples" / "gallery" / f"{stem}.py"
                target = str(tutorial if tutorial.exists() else example)
            assert (p.parent / target).resolve().exists(), (p.name, target)


def _docstrings() -> list[tuple[str, str]]:
    out = []
    for p in PACKAGE.rglob("*.py"):
        tree = ast.parse(p.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
                doc = ast.get_docstring(node, clean=True)
                if doc:
                    out.append((f"{p.relative_to(ROOT)}:{getattr(node, 'name', '')}", doc))
    return out


def test_no_docstring_carries_markup_the_site_prints_raw() -> None:
    # reStructuredText's roles (:func:`x`) print raw on the site: cross-references are
    # MkDocs' [`x`][rainuav.module.x] (resolved, or the strict build fails).
    role = re.compile(r"(?<!`):(mod|func|class|meth|attr|data|exc|obj):`")
    hits = [where for where, doc in _docstrings() if role.search(doc)]
    assert not hits, hits


ITEM = re.compile(r"^(\s*)([-*+]|\d+\.)\s")


def run_on_lists(text: str) -> list[int]:
    """Lines that start a list right under a paragraph line (Markdown renders them as one
    run-on paragraph)."""
    lines, fence, out = text.split("\n"), False, []
    for i, line in enumerate(lines):
        if line.lstrip().startswith("```"):
            fence = not fence
        if fence or i == 0 or not ITEM.match(line):
            continue
        prev = lines[i - 1]
        if not prev.strip() or ITEM.match(prev) or prev.lstrip().startswith("|"):
            continue
        j = i - 1
        while j >= 0 and lines[j].strip() and not ITEM.match(lines[j]):
            j -= 1
        if j >= 0 and lines[j].strip():
            continue  # a continuation line inside a list
        out.append(i + 1)
    return out


def test_every_list_renders_as_a_list() -> None:
    assert run_on_lists("Para:\n- a\n- b\n") == [2]  # the check catches one
    assert run_on_lists("Para:\n\n- a\n  more\n- b\n") == []
    hits = [(p.name, run_on_lists(p.read_text())) for p in DOCS.rglob("*.md")]
    hits += [(where, run_on_lists(doc)) for where, doc in _docstrings()]
    assert not [h for h in hits if h[1]], [h for h in hits if h[1]]


def test_the_gallery_page_is_current_and_examples_write_outside_docs() -> None:
    gallery = _load("gallery")
    assert (DOCS / "gallery.md").read_text() == gallery.page(), "run python docs/gallery.py --page"
    common = (ROOT / "examples" / "gallery" / "_common.py").read_text()
    assert 'default=Path("gallery")' in common
    for script in [*DOCS.glob("*_example.py"), *(DOCS / "tutorials").glob("*.py")]:
        text = script.read_text()
        assert not re.search(r"default=ROOT / \"docs\"", text), script.name


def test_the_site_shows_the_package_version() -> None:
    # The site takes the package's version when it is built (docs/hooks/version.py): the footer
    # and the home page's {{ version }}; the citation files say the same.
    version = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    hook = _load("hooks/version")
    assert hook.version() == version
    assert hook.on_page_markdown("rainuav {{ version }}", None, None, None) == f"rainuav {version}"
    assert "rainuav {{ version }}" in (DOCS / "index.md").read_text()
    assert f"version: {version}" in (ROOT / "CITATION.cff").read_text()
    assert f'version = "{version}"' in (ROOT / "Cargo.toml").read_text()


def test_shared_figures_agree_between_pages() -> None:
    # The quasi-static model against P.838-3 (H, 4.9 GHz, 25 mm/h), as computed and as three
    # pages state it (to the two decimals they print).
    from rainuav import medium

    ratio = medium.itu_p838(4.9e9, 25.0, polarization="h") / medium.specific_attenuation(
        4.9e9, 25.0, model="quasi-static", polarization="h"
    )
    stated = f"{ratio:.2f} times low at 4.9 GHz"
    for page in ("conventions.md", "physics.md", "guide/rain.md"):
        text = " ".join((DOCS / page).read_text().split())
        assert stated in text, (page, stated)
    # Timings live on the results page: the guide cites it for the terrain map's.
    terrain = (DOCS / "guide" / "terrain.md").read_text()
    assert "results.md#terrain" in terrain and not re.search(r"\d+\.\d+ s against", terrain)


def documented_summary_fields() -> set[str]:
    """The ``summary.json`` fields the troubleshooting page explains (its table)."""
    text = (DOCS / "faq.md").read_text()
    rows = [line for line in text.splitlines() if line.startswith("| `")]
    return {name for row in rows for name in re.findall(r"`([a-z_]+)`", row.split("|")[1])}


@pytest.mark.parametrize("name", ["index.md", "install.md", "faq.md", "physics.md"])
def test_the_new_pages_are_in_the_navigation(name: str) -> None:
    assert f": {name}" in (ROOT / "mkdocs.yml").read_text()
