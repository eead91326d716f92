"""A griffe extension for the API reference: each docstring's first sentence on its first line.

The reference's summary tables show a member's first docstring line; a docstring wrapped at
100 columns cuts its first sentence there ("...among a bank's (0"). This extension joins the
first paragraph's lines up to the end of its first sentence and leaves the rest as it was: a
summary is then a whole sentence, however long. A page renders the same either way: Markdown
joins a paragraph's lines.
"""

from __future__ import annotations

import importlib.util
from typing import Any

_NOT_AN_END = ("e.g.", "i.e.", "vs.", "cf.", "et al.", "Fig.", "eq.")


def first_sentence(paragraph: str) -> str:
    """The first sentence of ``paragraph`` (its lines joined): to the first full stop outside
    brackets and code, or the whole paragraph."""
    text = " ".join(line.strip() for line in paragraph.splitlines())
    depth, code, end = 0, False, None
    for i, ch in enumerate(text):  # the first full stop outside brackets and code
        if ch == "`":
            code = not code
        elif not code and ch in "([":
            depth += 1
        elif not code and ch in ")]":
            depth -= 1
        elif (
            not code and depth <= 0 and ch in ".!?"
            and (i + 1 == len(text) or text[i + 1].isspace())
            and not text[: i + 1].endswith(_NOT_AN_END)
        ):  # fmt: skip
            end = i + 1
            break
    return text if end is None else text[:end]


def with_summary_line(doc: str) -> str:
    """``doc`` with its first sentence on the first line (module docstring)."""
    head, sep, rest = doc.partition("\n\n")
    first = first_sentence(head)
    joined = " ".join(line.strip() for line in head.splitlines())
    not_prose = head.lstrip().startswith(("- ", "* ", "|", "```"))  # a list, a table, code
    if head.split("\n", 1)[0].strip() == first or not_prose:
        return doc  # the first line is the sentence already, or the paragraph is no prose
    rest_of_head = joined[len(first) :].strip()
    return first + ("\n" + rest_of_head if rest_of_head else "") + sep + rest


# The extension itself needs griffe (the docs extra); the rule above does not, so the test
# suite checks it with the test extra alone.
if importlib.util.find_spec("griffe") is not None:
    import griffe

    class FirstSentence(griffe.Extension):
        """Puts every docstring's first sentence on its first line (module docstring)."""

        def on_object(self, *, obj: Any, **kwargs: Any) -> None:
            """Griffe's hook, once an object is loaded."""
            if obj.docstring is not None and obj.docstring.value:
                obj.docstring.value = with_summary_line(obj.docstring.value)
