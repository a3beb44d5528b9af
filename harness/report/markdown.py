"""GitHub-flavoured Markdown: table cells that cannot break a table, links under a
configurable base, and a size cap that cuts at a line and says so.

The pieces the pull-request summaries (``srr suite`` and ``srr run --summary-md``) are built
from; what goes into them is decided by the result that sets the exit code
(:mod:`harness.suite.markdown`, :mod:`harness.run.markdown`).
"""

from __future__ import annotations

from collections.abc import Sequence
from urllib.parse import quote

__all__ = ["COMMENT_LIMIT", "STEP_SUMMARY_LIMIT", "VERDICT_MARK", "cap", "cell", "code",
           "join_link", "link", "num", "table", "verdict_mark"]

#: GitHub's limits: a job's step summary (bytes), and a pull-request comment (65,536
#: characters) less 1,024 left for what the action that posts it adds (the sticky-comment
#: action of the pull-request workflow adds a hidden marker line of about 40).
STEP_SUMMARY_LIMIT = 1024 * 1024
COMMENT_LIMIT = 65536 - 1024

#: A verdict's mark in a headline or a table row (anything else: ❌).
VERDICT_MARK = {"PASS": "✅", "RECORDED": "✅", "INVALID": "💥", "FLAKY": "🎲",
                "INTERRUPTED": "⏹️"}


def verdict_mark(verdict: str) -> str:
    """The mark of a run's or a suite's verdict (:data:`VERDICT_MARK`)."""
    return VERDICT_MARK.get(verdict, "❌")


_ESCAPES = str.maketrans({"|": "\\|", "`": "\\`", "<": "&lt;", ">": "&gt;", "*": "\\*",
                          "_": "\\_", "[": "\\[", "]": "\\]", "\\": "\\\\"})


def cell(text: object, limit: int = 300) -> str:
    """``text`` as one table cell: on one line, at most ``limit`` characters, with the
    characters Markdown would read escaped (``|``, backticks, emphasis, brackets, HTML; a
    leading ``#``, ``-``, ``+`` or ``>``)."""
    flat = " ".join(str(text).split())
    if len(flat) > limit:
        flat = flat[: limit - 1] + "…"
    out = flat.translate(_ESCAPES)
    return "\\" + out if out.startswith(("#", "-", "+", ">")) else out  # not a heading or list


def code(text: object, *, in_table: bool = True) -> str:
    """``text`` as inline code that a backtick inside it cannot end; in a table, a ``|`` in
    it cannot end the cell either (GitHub reads ``\\|`` as ``|`` in a table's code span)."""
    flat = " ".join(str(text).split())
    flat = flat.replace("|", "\\|") if in_table else flat
    fence = "`"
    while fence in flat:
        fence += "`"
    pad = " " if flat.startswith("`") or flat.endswith("`") else ""
    return f"{fence}{pad}{flat}{pad}{fence}"


def num(value: object, unit: str = "") -> str:
    """A number with four significant digits (``—`` for none)."""
    if value is None or isinstance(value, bool) or not isinstance(value, (int, float)):
        return "—" if value is None else cell(value)
    text = f"{value:.4g}"
    return f"{text} {cell(unit)}" if unit else text


def join_link(base: str, path: str) -> str:
    """``path`` (POSIX, relative; percent-encoded here) under ``base`` (used as given):
    joined with ``/`` unless ``base`` is empty or already ends with ``/`` or ``#``."""
    quoted = quote(path, safe="/=,@")
    if not base:
        return quoted
    return base + quoted if base.endswith(("/", "#")) else f"{base}/{quoted}"


def link(text: str, base: str, path: str | None) -> str:
    """``[text](base/path)``, or ``—`` when there is no ``path``."""
    if path is None:
        return "—"
    label = " ".join(str(text).split()).translate(_ESCAPES)
    target = join_link(base, path).replace(" ", "%20").replace("(", "%28").replace(")", "%29")
    target = target.replace("|", "%7C")
    return f"[{label}]({target})"


def table(headers: Sequence[str], rows: Sequence[Sequence[str]]) -> list[str]:
    """A table's lines; the cells are given already escaped (:func:`cell`, :func:`num`)."""
    out = ["| " + " | ".join(headers) + " |", "|" + "|".join("---" for _ in headers) + "|"]
    out += ["| " + " | ".join(r) + " |" for r in rows]
    return out


def cap(lines: Sequence[str], limit: int, *, last: str | None = None) -> str:
    """The lines (then ``last``, if given) as one document of at most ``limit`` UTF-8 bytes
    (so within as many characters too): cut before the first line that does not fit, with a
    line saying how many lines were left out. A folded block (``<details>``) open where the
    cut falls is closed first, so the note is not folded away; ``last`` (the links to the
    whole results) is kept whatever is cut."""
    ending = [] if last is None else [last]
    text = "\n".join([*lines, *ending]) + "\n"
    if len(text.encode("utf-8")) <= limit:
        return text
    tail = "" if last is None else f"\n{last}\n"
    kept: list[str] = []
    size = 0
    for i, line in enumerate(lines):
        opened = sum(k.startswith("<details>") for k in kept) > sum(
            k.startswith("</details>") for k in kept)
        close = "\n</details>\n" if opened else ""
        note = (f"{close}\n*… truncated: {len(lines) - i} more line(s) left out to stay within "
                f"{limit} bytes (the full results are in the suite's summary.json and "
                "reports).*\n")
        n = len(line.encode("utf-8")) + 1
        if size + n + len((note + tail).encode("utf-8")) > limit:
            # a table cut in the middle ends where it was cut: the note starts after a blank
            return "\n".join(kept) + "\n" + note + tail
        kept.append(line)
        size += n
    return "\n".join(kept) + "\n"  # pragma: no cover - the whole text fitted
