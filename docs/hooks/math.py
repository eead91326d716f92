"""Formulas as MathML, written into the pages when the site is built: they render in every
current browser with no script and no network (the site opened from disk shows them too).

Pages write TeX between ``$...$`` (inline) or ``$$...$$`` (a block of its own);
``pymdownx.arithmatex`` (generic mode) marks them, and this hook turns each into MathML with
``latex2mathml`` (the docs extra). A formula it cannot read (an unknown command, unbalanced
braces) fails the build, naming the page and the formula.
"""

from __future__ import annotations

import html
import re

from latex2mathml.converter import convert

_INLINE = re.compile(r'<span class="arithmatex">\\\((.*?)\\\)</span>', re.S)
_BLOCK = re.compile(r'<div class="arithmatex">\\\[(.*?)\\\]</div>', re.S)
# A command latex2mathml passed through as text, or an alignment tab outside an array.
_UNREAD = re.compile(r">(\\[A-Za-z]+|&)<")


def mathml(tex: str, display: bool, where: str = "a page") -> str:
    """The MathML of one formula ``tex`` (TeX, as written on the page), inline or as a block
    (``display``); ``ValueError`` naming ``where`` if it cannot be read."""
    depth = 0
    for ch in re.sub(r"\\[{}]", "", tex):
        depth += {"{": 1, "}": -1}.get(ch, 0)
        if depth < 0:
            break
    if depth != 0:
        raise ValueError(f"{where}: unbalanced braces in the formula ${tex}$")
    try:
        out = convert(tex, display="block" if display else "inline")
    except Exception as err:  # latex2mathml's own errors carry no message worth more
        raise ValueError(
            f"{where}: cannot read the formula ${tex}$ ({type(err).__name__})"
        ) from err
    bad = _UNREAD.search(out)
    if bad:
        what = "an alignment & outside an array" if bad.group(1) == "&" else bad.group(1)
        raise ValueError(f"{where}: cannot read {what} in the formula ${tex}$")
    return out


_CODE = re.compile(r"<(pre|code)\b.*?</\1>", re.S)


def formulas_to_mathml(page_html: str, where: str = "a page") -> str:
    """``page_html`` with every formula arithmatex marked replaced by its MathML;
    ``ValueError`` where a ``$$`` is left that arithmatex did not read (a block in a list item
    indented less than four spaces)."""
    if "$$" in _CODE.sub("", page_html):
        raise ValueError(f"{where}: a $$ block arithmatex did not read (in a list, indent it by 4)")

    def one(display: bool):
        tag = "div" if display else "span"
        return lambda m: (
            f'<{tag} class="arithmatex">'
            + mathml(html.unescape(m.group(1)).strip(), display, where)
            + f"</{tag}>"
        )

    return _INLINE.sub(one(False), _BLOCK.sub(one(True), page_html))


def on_page_content(html_text: str, page, config, files) -> str:
    """mkdocs' hook: the page's formulas as MathML."""
    return formulas_to_mathml(html_text, page.file.src_path)
