"""The front end of ``specs:`` formulas: signal temporal logic over srr's signals.

A formula is STL as `rtamt <https://github.com/nickovic/rtamt>`_ reads it (``always``,
``eventually[a, b]``, ``until``, ``historically``, ``once``, ``since``, ``prev``, ``next``,
``not``, ``and``, ``or``, ``->``, ``<->``, ``xor``, ``rise``, ``fall``, comparisons,
arithmetic, ``abs``/``sqrt``/``exp``/``pow``) whose atoms are srr's signals
(:data:`SIGNALS`): ``clearance(forklift, worker)``, ``speed(forklift)``,
``in_zone(worker, loading_roi)``, ``tracking_error(forklift)``, ``alarm``, ``muted``,
``topic('/odom', 'twist.twist.linear.x')``.

:func:`parse_formula` tokenizes the formula, checks every signal's name, arity and arguments
against the scenario (:class:`SignalContext`), turns each into an rtamt variable (``s0``,
``s1``...; the same call twice is one variable), turns interval bounds from seconds into
ticks (they must be whole ticks) and lets rtamt parse the result, so a formula that loads
also evaluates. Time in rtamt is the tick index (sampling period 1): discrete time on the
simulation's tick grid. Every error is a :class:`SpecError` naming the token.

rtamt is imported only here, and only when a scenario has specs (it is the ``stl`` extra).
"""

from __future__ import annotations

import contextlib
import io
import logging
import math
import re
import warnings
from collections.abc import Collection, Mapping
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

from harness.validation import close_match

__all__ = ["KEYWORDS", "SIGNALS", "Formula", "SignalContext", "SignalRef", "SpecError",
           "parse_formula", "rtamt_spec"]


class SpecError(ValueError):
    """A formula that cannot be evaluated; the message names the token."""


@dataclass(frozen=True)
class SignalDef:
    """A signal srr computes: its argument kinds and the unit of its values."""

    args: tuple[str, ...]  # "object" | "zone" | "robot" | "robot_routed" | "string"
    unit: str  # "bool": +1 true, -1 false
    what: str


#: Every signal a formula may use, by name.
SIGNALS: dict[str, SignalDef] = {
    "clearance": SignalDef(("object", "object"), "m", "centre distance minus both footprint "
                           "radii, ground truth"),
    "distance": SignalDef(("object", "object"), "m", "centre distance, ground truth"),
    "speed": SignalDef(("object",), "m/s", "planar ground-truth speed"),
    "in_zone": SignalDef(("object", "zone"), "bool", "ground-truth position inside the zone"),
    "tracking_error": SignalDef(("robot_routed",), "m", "ground-truth distance to the route "
                                "of the robot's scoring.control block"),
    "alarm": SignalDef((), "bool", "/safety/alarm, held"),
    "muted": SignalDef((), "bool", "the safety scoring's muted topic, held"),
    "topic": SignalDef(("string", "string"), "", "a numeric field of a recorded topic, held"),
}

#: rtamt's operator and function words (and its one-letter operator aliases).
KEYWORDS = frozenset({
    "always", "eventually", "historically", "once", "since", "until", "unless", "next",
    "prev", "not", "and", "or", "implies", "iff", "xor", "rise", "fall", "abs", "sqrt", "exp",
    "pow", "G", "F", "H", "O", "S", "U", "X"})
#: Operators that take an interval ``[a, b]`` (seconds).
_TIMED = frozenset({"always", "eventually", "historically", "once", "since", "until", "unless",
                    "G", "F", "H", "O", "S", "U"})
#: Words rtamt reads but a formula has no use for (declarations, units outside intervals).
_RESERVED = frozenset({"topic", "import", "input", "output", "internal", "const", "real",
                       "float", "long", "complex", "int", "bool", "assertion",
                       "specification", "from", "true", "false", "TRUE", "FALSE", "s", "ms",
                       "us", "ns", "ps"})
ZONES = ("loading_roi", "trailer")

_TOKEN = re.compile(r"""
    (?P<ws>\s+)
  | (?P<num>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)
  | (?P<ident>[A-Za-z_][A-Za-z0-9_]*)
  | (?P<str>'[^']*'|"[^"]*")
  | (?P<op><->|->|>=|<=|==|!==|[-+*/()\[\],:<>!])
""", re.VERBOSE)


@dataclass(frozen=True)
class _Tok:
    kind: str
    text: str
    pos: int


def _tokens(formula: str) -> list[_Tok]:
    out: list[_Tok] = []
    i = 0
    while i < len(formula):
        m = _TOKEN.match(formula, i)
        if m is None:
            ch = formula[i]
            hint = " (write 'and', 'or', 'not')" if ch in "&|" else \
                " (write '!==' for 'not equal')" if formula[i - 1:i + 1] == "!=" else \
                " (a formula is one expression)" if ch in ";=" else ""
            raise SpecError(f"unexpected character {ch!r} at column {i + 1}{hint}")
        kind = m.lastgroup or ""
        if kind != "ws":
            out.append(_Tok(kind, m.group(), i))
        i = m.end()
    return out


@dataclass(frozen=True)
class SignalContext:
    """What the scenario offers the signals: objects with ground truth (enabled robots and
    workers, by name and as ``character_<i>``), its zones, the robots a control block routes
    and the tick rate (interval bounds must be whole ticks)."""

    objects: Collection[str]
    zones: Collection[str]
    routed: Collection[str]
    tick_hz: int


@dataclass(frozen=True)
class SignalRef:
    """One signal of a formula: its name, its arguments and the rtamt variable it became."""

    name: str
    args: tuple[str, ...]
    var: str

    @property
    def text(self) -> str:
        kinds = SIGNALS[self.name].args
        if not kinds:
            return self.name
        shown = (repr(a) if k == "string" else a for k, a in zip(kinds, self.args, strict=True))
        return f"{self.name}({', '.join(shown)})"

    @property
    def unit(self) -> str:
        return SIGNALS[self.name].unit


@dataclass(frozen=True)
class Formula:
    """A parsed formula: rtamt's text over the signals' variables (bounds in ticks).

    ``body``: for a formula ``always φ`` (unbounded), the text of ``φ``. Its robustness is the
    minimum of ``φ``'s trace, and its violation windows are where ``φ`` is negative (the
    trace of ``always φ`` itself is negative from the start up to the last violation)."""

    source: str
    text: str
    signals: tuple[SignalRef, ...]
    body: str | None

    @property
    def unit(self) -> str:
        """The robustness's unit: its signals' one physical unit (``m``, ``m/s``), else
        empty (boolean signals, whose robustness is ±1; mixed units; a ``topic`` field)."""
        units = {s.unit for s in self.signals}
        return units.pop() if len(units) == 1 and units != {"bool"} else ""


def _args(toks: list[_Tok], i: int, name: str) -> tuple[tuple[str, ...], int]:
    """The arguments of the call ``name(`` at ``toks[i]`` (the parenthesis) and the index
    after its ``)``."""
    args: list[str] = []
    j = i + 1
    while True:
        if j >= len(toks):
            raise SpecError(f"{name}(: missing ')'")
        t = toks[j]
        if t.text == ")" and not args:
            return (), j + 1
        if t.kind == "ident":
            args.append(t.text)
        elif t.kind == "str":
            args.append(t.text[1:-1])
        else:
            raise SpecError(f"{name}(: expected a name or a quoted string, got {t.text!r}")
        if j + 1 >= len(toks):
            raise SpecError(f"{name}(: missing ')'")
        sep = toks[j + 1].text
        if sep == ")":
            return tuple(args), j + 2
        if sep != ",":
            raise SpecError(f"{name}(: expected ',' or ')', got {sep!r}")
        j += 2


def _check_args(name: str, args: tuple[str, ...], ctx: SignalContext) -> None:
    d = SIGNALS[name]
    if len(args) != len(d.args):
        shown = f"{name}({', '.join(args)})"
        want = ", ".join(d.args) or "no arguments"
        raise SpecError(f"{shown}: {name} takes {len(d.args)} argument"
                        f"{'' if len(d.args) == 1 else 's'} ({want}), got {len(args)}")
    for kind, arg in zip(d.args, args, strict=True):
        names: Collection[str] = {"object": ctx.objects, "zone": ctx.zones,
                                  "robot_routed": ctx.routed}.get(kind, ())
        if kind == "string":
            continue
        if arg not in names:
            what = {"object": "robot or worker", "zone": "zone",
                    "robot_routed": "robot with a scoring.control route"}[kind]
            near = close_match(arg, names)
            hint = f" (did you mean {near!r}?)" if near else \
                f" (known: {', '.join(sorted(names)) or 'none'})"
            raise SpecError(f"{name}(...): unknown {what} {arg!r}{hint}")
    if name == "topic":
        topic, path = args
        if not re.fullmatch(r"/?[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*", topic):
            raise SpecError(f"topic(...): {topic!r} is not a topic name")
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*(\[\d+\])*(\.[A-Za-z_][A-Za-z0-9_]*"
                            r"(\[\d+\])*)*", path):
            raise SpecError(f"topic(...): {path!r} is not a field path "
                            "(fields separated by '.', list items as [i])")


def _ticks(text: str, unit: str, tick_hz: int) -> str:
    """An interval bound (``text`` in ``unit``) as a whole number of ticks."""
    try:
        sec = Fraction(text) / (1000 if unit == "ms" else 1)
    except (ValueError, ZeroDivisionError) as err:  # pragma: no cover - the regex's numbers
        raise SpecError(f"interval bound {text!r} is not a number") from err
    ticks = sec * tick_hz
    if ticks.denominator != 1:
        raise SpecError(f"interval bound {text}{unit or ' s'} is not a whole number of ticks "
                        f"(the tick is 1/{tick_hz} s)")
    return str(ticks.numerator)


def _interval(toks: list[_Tok], i: int, op: str, tick_hz: int) -> tuple[str, int]:
    """``[a, b]`` at ``toks[i]`` in ticks, rtamt's ``[a:b]``, and the index after it."""
    parts: list[tuple[str, str]] = []
    j = i + 1
    for _ in range(2):
        if j < len(toks) and toks[j].kind == "num":
            num = toks[j].text
            unit = toks[j + 1].text if j + 1 < len(toks) and toks[j + 1].text in ("s", "ms") \
                else ""
            parts.append((num, unit))
            j += 2 if unit else 1
        else:
            got = toks[j].text if j < len(toks) else "the end"
            raise SpecError(f"{op}[...]: expected a bound in seconds, got {got!r}")
        if len(parts) == 1:
            if j >= len(toks) or toks[j].text not in (",", ":"):
                raise SpecError(f"{op}[...]: expected '[a, b]'")
            j += 1
    if j >= len(toks) or toks[j].text != "]":
        raise SpecError(f"{op}[...]: missing ']'")
    lo, hi = (_ticks(n, u, tick_hz) for n, u in parts)
    if int(lo) > int(hi):
        raise SpecError(f"{op}[{parts[0][0]}, {parts[1][0]}]: the lower bound is above the "
                        "upper one")
    return f"[{lo}:{hi}]", j + 1


def parse_formula(formula: str, ctx: SignalContext) -> Formula:
    """Check ``formula`` against the scenario and parse it with rtamt (:class:`SpecError`
    naming the token, else the :class:`Formula`)."""
    if not formula.strip():
        raise SpecError("empty formula")
    toks = _tokens(formula)
    out: list[str] = []
    signals: dict[tuple[str, tuple[str, ...]], SignalRef] = {}
    i = 0
    while i < len(toks):
        t = toks[i]
        if t.kind == "str":
            raise SpecError(f"unexpected string {t.text} (strings are topic() arguments)")
        if t.kind != "ident":
            out.append(t.text)
            i += 1
            continue
        word = t.text
        if word in KEYWORDS:
            out.append(word)
            i += 1
            if word in _TIMED and i < len(toks) and toks[i].text == "[":
                text, i = _interval(toks, i, word, ctx.tick_hz)
                out.append(text)
            continue
        if word not in SIGNALS:
            near = close_match(word, SIGNALS) or close_match(word, KEYWORDS)
            hint = f" (did you mean {near!r}?)" if near else \
                f" (signals: {', '.join(sorted(SIGNALS))})"
            kind = "reserved word" if word in _RESERVED else "signal"
            raise SpecError(f"unknown {kind} {word!r}{hint}")
        if SIGNALS[word].args:
            if i + 1 >= len(toks) or toks[i + 1].text != "(":
                raise SpecError(f"{word}: a call, {word}(...), expected")
            args, i = _args(toks, i + 1, word)
        else:
            args = ()
            i += 1
            if i < len(toks) and toks[i].text == "(" and i + 1 < len(toks) \
                    and toks[i + 1].text == ")":
                i += 2
        _check_args(word, args, ctx)
        ref = signals.setdefault((word, args), SignalRef(word, args, f"s{len(signals)}"))
        out.append(ref.var)
    if not signals:
        raise SpecError(f"the formula reads no signal (signals: {', '.join(sorted(SIGNALS))})")
    text = " ".join(out)
    refs = tuple(signals.values())
    spec = rtamt_spec(text, [r.var for r in refs])
    body = _always_body(spec, out)
    if body is not None:
        rtamt_spec(body, [r.var for r in refs])
    return Formula(formula, text, refs, body)


def _always_body(spec: Any, out: list[str]) -> str | None:
    """The operand's text when the formula is ``always φ`` with no interval."""
    top = spec.ast.specs[0]
    if type(top).__name__ != "Always":
        return None
    words = list(out)
    while words and words[0] == "(" and words[-1] == ")" and _balanced(words[1:-1]):
        words = words[1:-1]
    if not words or words[0] not in ("always", "G"):
        return None  # pragma: no cover - the top node is Always
    return " ".join(words[1:])


def _balanced(words: list[str]) -> bool:
    depth = 0
    for w in words:
        depth += {"(": 1, ")": -1}.get(w, 0)
        if depth < 0:
            return False
    return depth == 0


def _rtamt() -> Any:
    try:
        with warnings.catch_warnings():  # its ANTLR 4.7 runtime imports typing.io
            warnings.simplefilter("ignore", DeprecationWarning)
            import rtamt  # the `stl` extra; imported only for scenarios that have specs
    except ImportError as err:
        raise SpecError("specs need the 'stl' extra (rtamt): pip install -e '.[stl]'") from err
    return rtamt


def rtamt_spec(text: str, variables: Collection[str]) -> Any:
    """rtamt's discrete-time specification of ``text`` over float ``variables``, parsed,
    time in ticks (sampling period 1). rtamt reports syntax errors by printing them and by an
    exception: both become one :class:`SpecError` line."""
    rtamt = _rtamt()
    spec = rtamt.StlDiscreteTimeSpecification()
    for name in variables:
        spec.declare_var(name, "float")
    spec.spec = text
    spec.set_sampling_period(1, "s", 0.1)
    sink = io.StringIO()
    log = logging.getLogger()
    level = log.level
    try:
        log.setLevel(logging.ERROR)  # rtamt warns on the root logger about implicit variables
        with contextlib.redirect_stdout(sink), contextlib.redirect_stderr(sink):
            spec.parse()
    except RecursionError as err:
        raise SpecError("not a formula rtamt can parse: it nests too deeply") from err
    except Exception as err:  # rtamt raises RTAMTException, KeyError, ... for bad input
        msg = str(err).replace("RTAMT Exception: ", "").strip().splitlines()
        first = msg[0] if msg else type(err).__name__
        raise SpecError(f"not a formula: {_untranslate(first)}") from err
    finally:
        log.setLevel(level)
    return spec


def _untranslate(message: str) -> str:
    """rtamt's message without the column of the translated text (which is not the
    user's), shortened."""
    message = re.sub(r"^\d+:\d+:\s*", "", message)
    message = re.sub(r"expecting \{.*", "", message).strip().rstrip(",")
    message = message.replace("'<EOF>'", "the end of the formula")
    return message[:160]


def evaluate(formula: Formula, columns: Mapping[str, list[float]], n: int
             ) -> tuple[list[float], bool]:
    """rtamt's robustness trace over ``n`` ticks: of ``φ`` for a formula ``always φ`` (and
    True), else of the whole formula (and False). :class:`SpecError` when the values make
    its arithmetic fail (a division by zero, the root of a negative number)."""
    text = formula.body if formula.body is not None else formula.text
    spec = rtamt_spec(text, [s.var for s in formula.signals])
    data: dict[str, list[Any]] = {"time": list(range(n))}
    data.update(columns)
    sink = io.StringIO()
    try:
        with contextlib.redirect_stdout(sink), contextlib.redirect_stderr(sink):
            trace = spec.evaluate(data)
    except RecursionError as err:
        raise SpecError("rtamt cannot evaluate it: it nests too deeply") from err
    except (ArithmeticError, ValueError) as err:  # x / 0, sqrt(-1), ...: Python's math
        raise SpecError(f"rtamt cannot evaluate it on this run: {err}") from err
    values = [float(v) if not isinstance(v, bool) else (1.0 if v else -1.0) for _, v in trace]
    return [v if not math.isnan(v) else -math.inf for v in values], formula.body is not None
