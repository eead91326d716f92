"""What every built page must be, or the build fails naming the page:

- it opens offline: it loads no script, style sheet or font from the network (links to other
  sites are fine: they are followed only when clicked);
- its links work from disk and from any server path: none is root-absolute (``href="/..."``),
  but on the 404 page, which a server shows at any path and which takes its links from
  ``site_url``;
- its tables and formulas rendered: no paragraph that starts with a table's ``|`` (a table
  broken by a blank line or a missing header), no column without a heading, and no TeX left
  as text outside code.
"""

from __future__ import annotations

import re

_FETCHED = re.compile(
    r"<(?:script[^>]*\bsrc|link[^>]*\brel=\"?(?:stylesheet|preconnect|preload)\"?[^>]*\bhref)"
    r"=\"?(https?:)?//([^\"' >]+)",
    re.I,
)
_ROOTED = re.compile(r"\b(?:href|src)=\"(/[^/\"][^\"]*)\"")
_CODE = re.compile(r"<(pre|code)\b.*?</\1>", re.S)
_BROKEN_TABLE = re.compile(r"<p>\s*\|[^<]*\|")
_EMPTY_HEADING = re.compile(r"<tr>(?:(?!</tr>).)*?<th\b[^>]*>\s*</th>.*?</tr>", re.S)
_TAG = re.compile(r"<[^>]+>")
_RAW_TEX = re.compile(r"\$[^$<>]{0,200}?\\[A-Za-z]+")


def network_fetches(page_html: str) -> list[str]:
    """The addresses on the network that ``page_html`` loads as it opens."""
    return [m.group(2) for m in _FETCHED.finditer(page_html)]


def problems(page_html: str, is_404: bool = False) -> list[str]:
    """What is wrong with a built page (module docstring), one line each."""
    out = [f"loads {a} from the network" for a in network_fetches(page_html)]
    if not is_404:
        out += [f"links to {a} from the root of the server" for a in _ROOTED.findall(page_html)]
    text = _CODE.sub("", page_html)
    out += [
        f"a table that did not render: {m.group(0)[3:60]!r}" for m in _BROKEN_TABLE.finditer(text)
    ]
    out += [
        f"a table column without a heading: {' '.join(_TAG.sub(' ', m[0]).split())[:80]!r}"
        for m in _EMPTY_HEADING.finditer(page_html)
    ]
    out += [f"a formula left as text: {m[0][:60]!r}" for m in _RAW_TEX.finditer(text)]
    return out


def on_post_page(output: str, page, config) -> str:
    """mkdocs' hook: refuse a page that breaks one of the rules above."""
    found = problems(output, is_404=page.file.src_uri == "404.html")
    if found:
        raise ValueError(f"{page.file.src_path}: {found[0]} (and {len(found) - 1} more)")
    return output
