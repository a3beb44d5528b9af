"""The small error hierarchy of srr.

Every error a user can cause derives from :class:`SrrError`; the CLI turns it into one line and
its ``exit_code``. Library code raises these and never calls ``sys.exit`` or prints. Errors
narrow per package: a package's own live in its ``errors.py`` (:mod:`harness.recording.errors`,
:mod:`harness.graph.errors`, :mod:`harness.video.errors`, :mod:`harness.live.errors`,
:mod:`harness.sut.errors`); those kept here are raised from more than one layer
(:class:`ScenarioError` from the validator up, :class:`SimulationError` from the scenario's
prims up, :class:`RunStopped` from the ROS 2 bridge, the systems under test and the run).
"""

from __future__ import annotations

__all__ = [
    "VALUE_LIMIT",
    "DiskSpaceError",
    "RunInUseError",
    "RunStopped",
    "ScenarioError",
    "SimulationError",
    "SrrError",
    "reason",
    "shorten",
]

#: The longest value (a quoted string, a list, a mapping) an error message repeats whole; a
#: longer one is cut to this many characters and "…". Bare words (file names, field paths)
#: may be twice as long.
VALUE_LIMIT = 60

_OPENERS = {"'": "'", '"': '"', "[": "]", "{": "}"}
_VALUE_START = " ([{,:=\t"


def _span_end(text: str, start: int) -> int:
    """The index just past the quoted string or bracketed value that starts at ``start``
    (nested brackets and quotes inside skipped), or -1 if it does not end."""
    close = _OPENERS[text[start]]
    if text[start] in "'\"":
        i = start + 1
        while i < len(text):
            if text[i] == "\\":
                i += 2
                continue
            if text[i] == close:
                return i + 1
            i += 1
        return -1
    depth, i = 0, start
    while i < len(text):
        c = text[i]
        if c in "'\"" and i > start and text[i - 1] in _VALUE_START:
            end = _span_end(text, i)
            if end > 0:
                i = end
                continue
        if c == text[start]:
            depth += 1
        elif c == close:
            depth -= 1
            if depth == 0:
                return i + 1
        i += 1
    return -1


def printable(text: str) -> str:
    """``text`` on one line: a character that is not printable (a newline in a key, a NUL in
    a file name) written as Python writes it in a string (``\\n``, ``\\x00``)."""
    return text if text.isprintable() else "".join(
        c if c.isprintable() else repr(c)[1:-1] for c in text)


def shorten(text: str, limit: int = VALUE_LIMIT) -> str:
    """``text`` with every value longer than ``limit`` cut (see :data:`VALUE_LIMIT`): a
    quoted string or a bracketed list or mapping to ``limit`` characters, "…" and its closing
    character; a run of more than ``2 * limit`` characters without a space to ``2 * limit``
    and "…". A text cut once comes back the same."""
    out: list[str] = []
    i = 0
    while i < len(text):
        c = text[i]
        if c.isspace():
            out.append(c)
            i += 1
            continue
        if c in _OPENERS and (i == 0 or text[i - 1] in _VALUE_START):
            end = _span_end(text, i)
            if end > 0:
                span = text[i:end]
                out.append(span if len(span) <= limit + 2
                           else f"{span[:limit + 1]}…{_OPENERS[c]}")
                i = end
                continue
        j = i + 1
        while j < len(text) and not text[j].isspace() and text[j] != "…" and not (
                text[j] in _OPENERS and text[j - 1] in _VALUE_START):
            j += 1
        word = text[i:j]
        out.append(word if len(word) <= 2 * limit + 1 else f"{word[:2 * limit]}…")
        i = j
    return "".join(out)


class SrrError(Exception):
    """Base of every error srr raises on purpose."""

    exit_code: int = 2


class ScenarioError(SrrError):
    """A scenario file (or an override of it) is not acceptable.

    ``file`` is the file the offending value came from, ``field`` a dotted path inside it.
    """

    def __init__(self, file: str, field: str, message: str) -> None:
        self.file = file
        self.field = field
        self.message = shorten(printable(message))
        where = (f"{shorten(printable(file))}: {shorten(printable(field))}" if field
                 else shorten(printable(file)))
        super().__init__(f"{where}: {self.message}")




class SimulationError(SrrError):
    """The simulated world could not be built or stepped."""

    exit_code = 3




class DiskSpaceError(SrrError):
    """Not enough free disk space to start a run (its estimated bag size plus the margin)."""






class RunInUseError(SrrError):
    """A run directory is owned by a live process (harness.runlock): it is still being
    written, so it can be neither read nor changed yet."""


class RunStopped(SrrError):
    """Raised from inside a tick to stop the run at that tick boundary, INVALID: the health
    gate ``gate`` trips with this message (e.g. an external ROS 2 output that never came).
    ``details`` (a traceback, say) is kept beside the recording, too long for the message."""

    exit_code = 3

    def __init__(self, gate: str, message: str, details: str | None = None) -> None:
        self.gate = gate
        self.details = details
        super().__init__(message)


def reason(err: BaseException) -> str:
    """What went wrong, for a one-line message: the exception's text (its first line, with
    characters that are not printable written as escapes, :func:`printable`: an ANSI colour
    code or a NUL from a plug-in reaches no terminal, page or file as it is), or its kind
    when it has none (some readers raise bare ``EndOfFile()``)."""
    text = printable(next((line.strip() for line in str(err).splitlines() if line.strip()),
                          ""))
    name = type(err).__name__
    if not text:
        return {"EndOfFile": "unexpected end of file (truncated)"}.get(name, name)
    return text if len(text) < 200 else text[:197] + "..."
