"""Property-based fuzzing of everything a user writes: each bundled scenario (and the files it
includes), the bundled suite, and ``--set`` values, one field at a time given a wrong type, an
out-of-range, NaN/inf, huge, empty or unicode value, deleted, renamed or written twice.

Every outcome is exit 0, or exit 2 with exactly one line on stderr that names the file (or
``--set``) and the field; never a traceback, never another exit code. ``srr validate`` runs
in-process through :func:`harness.cli.main`; the suite through :func:`plan_suite` (what ``srr
suite`` does before it runs anything); a few short ``srr run`` s take mutated ``--set`` values
(slow). The number of examples comes from the hypothesis profile (tests/conftest.py):
``ci`` (the default, derandomized, a few seconds) or ``nightly`` (HYPOTHESIS_PROFILE=nightly).
"""

from __future__ import annotations

import contextlib
import copy
import math
import re
import shutil
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from harness import yamlio
from harness.cli import main
from harness.errors import SrrError
from harness.suite.runner import plan_suite
from tests.conftest import SCENARIOS, ModuleTmp

#: Examples of the loaded profile (ci: a few; nightly: many); each test takes its share.
BUDGET = settings.default.max_examples

Path_ = tuple[str | int, ...]

# ---------------------------------------------------------------------------------------------
# What is mutated: every bundled scenario, every file a scenario includes (validated through
# that scenario), and the bundled suite.


def _yaml_files() -> list[tuple[str, str]]:
    """(file to mutate, scenario to validate), both relative to scenarios/."""
    pairs: list[tuple[str, str]] = []
    for path in sorted([*SCENARIOS.glob("*.yaml"), *SCENARIOS.glob("regressions/*.yaml")]):
        rel = str(path.relative_to(SCENARIOS))
        pairs.append((rel, rel))
        inc = yamlio.load(path.read_text(encoding="utf-8")).get("include") or []
        for name in [inc] if isinstance(inc, str) else inc:
            included = str((path.parent / name).resolve().relative_to(SCENARIOS))
            if included not in [p for p, _ in pairs]:
                pairs.append((included, rel))
    return pairs


FILES = _yaml_files()
SUITE = "suites/nightly.yaml"
LIGHT = "forklift_warehouse.yaml"  # no cameras: the cheapest short run


def _paths(node: Any, prefix: Path_ = ()) -> list[Path_]:
    out: list[Path_] = []
    items = node.items() if isinstance(node, dict) else \
        enumerate(node) if isinstance(node, list) else ()
    for key, value in items:
        out.append((*prefix, key))
        out += _paths(value, (*prefix, key))
    return out


DOCS = {rel: yamlio.load((SCENARIOS / rel).read_text(encoding="utf-8"))
        for rel in {p for p, _ in FILES} | {SUITE}}
PATHS = {rel: _paths(doc) for rel, doc in DOCS.items()}

# ---------------------------------------------------------------------------------------------
# Values

LONG = "é" + "x" * 4999
odd_values = st.sampled_from([
    None, True, False, 0, -1, 1, 2**31, 10**30, -(10**30), 10**400, 1e308, -1e308, 5e-324,
    math.nan, math.inf, -math.inf, "", " ", "x", "ü☃日本\u202e", "\x00", LONG, [], {},
    [1, 2, 3], [[0.0, 0.0]], {"a": 1}, "1e3", "yes", "/", "//bad topic", "../..", "a:b",
])
values = st.one_of(odd_values, st.integers(), st.floats(), st.text(max_size=20),
                   st.lists(st.floats(allow_nan=True), max_size=4),
                   st.dictionaries(st.text(max_size=8), st.integers(), max_size=3))
keys = st.one_of(st.sampled_from(["", "x", "name+", "include", LONG, "ü", "1e3", "true"]),
                 st.text(min_size=1, max_size=12))
#: ``--set`` value texts: YAML snippets a user may write, broken YAML, anything.
set_texts = st.one_of(st.sampled_from([
    "1e3", "-1E-5", "1e999", ".nan", ".inf", "-.inf", "nan", "inf", "0", "-0", "1e308",
    "99999999999999999999999", "9" * 5000, "yes", "on", "~", "", "[", "{", "]", "a: b: c",
    "{a: 1, a: 2}", "[1, [2, [3]]]", "!!python/object:os.system x", "!!int x", "&a [*a]",
    "'unclosed", "\t", "ü☃", "x" * 5000, "[.nan, .inf]", "{}", "[]", "2024-01-02", "0x1F",
]), st.text(max_size=30))


@dataclass(frozen=True)
class Mutation:
    kind: str  # set | delete | rename | duplicate
    path: Path_
    value: Any = None

    def __repr__(self) -> str:
        return f"Mutation({self.kind} {'.'.join(map(str, self.path))} {self.value!r:.80})"


@st.composite
def mutations(draw: st.DrawFn, rel: str) -> Mutation:
    path = draw(st.sampled_from(PATHS[rel]))
    kinds = ["set", "set", "delete"] + (["rename", "duplicate"] if isinstance(path[-1], str)
                                        else [])
    kind = draw(st.sampled_from(kinds))
    value = draw(keys) if kind == "rename" else draw(values) if kind != "delete" else None
    return Mutation(kind, path, value)


_DUP = "__srr_fuzz_duplicate__"


def _key_text(key: str) -> str:
    return yamlio.dump(key, default_flow_style=True, allow_unicode=True).strip() \
        .removesuffix("...").strip()


def mutated_text(rel: str, m: Mutation) -> str:
    doc = copy.deepcopy(DOCS[rel])
    parent = doc
    for part in m.path[:-1]:
        parent = parent[part]
    last = m.path[-1]
    if m.kind == "set":
        parent[last] = m.value
    elif m.kind == "delete":
        del parent[last]
    elif m.kind == "rename":
        parent[m.value] = parent.pop(last)
    else:  # the key written twice: a second copy, with a new value
        assert isinstance(parent, dict)
        parent[_DUP] = m.value
        text = yamlio.dump(doc, default_flow_style=True, width=2**30, allow_unicode=True,
                           sort_keys=False)
        assert text.count(_DUP) == 1
        return text.replace(_DUP, _key_text(str(last)))
    return yamlio.dump(doc, sort_keys=False, allow_unicode=True, width=2**30)


# ---------------------------------------------------------------------------------------------
# The copy of scenarios/ the examples write into, and the checks.


@pytest.fixture(scope="module")
def tree(module_tmp: ModuleTmp) -> Path:
    root = module_tmp("fuzz") / "scenarios"
    shutil.copytree(SCENARIOS, root)
    return root


@contextlib.contextmanager
def written(tree: Path, rel: str, text: str) -> Iterator[Path]:
    path = tree / rel
    original = path.read_bytes()
    path.write_text(text, encoding="utf-8")
    try:
        yield path
    finally:
        path.write_bytes(original)


def cli(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str]:
    capsys.readouterr()
    code = main(list(argv))
    return code, capsys.readouterr().err


_LINE = re.compile(r"^srr (?P<command>\w+): (?P<where>.+?): (?P<rest>.+)$")


def one_line_naming_the_file(err: str, command: str, tree: Path, *, codes: tuple[int, ...],
                             code: int) -> str:
    """``err`` (less warnings) is nothing with exit 0 (or a code in ``codes``), else one line
    ``srr COMMAND: FILE: FIELD: ...`` with exit 2, FILE in ``tree`` or ``--set``."""
    lines = [ln for ln in err.splitlines() if ln.strip()
             and not ln.startswith(f"srr {command}: warning: ")]
    assert "Traceback" not in err, err
    if code in (0, *codes):
        return ""
    assert code == 2, (code, err)
    assert len(lines) == 1, err
    match = _LINE.match(lines[0])
    assert match and match["command"] == command, lines[0]
    assert match["where"].startswith((str(tree), "--set")), lines[0]
    return lines[0]


# Mutations left out of the short runs, with the reason (none now: the plug-in parameter ranges,
# joint names and route waypoints outside the world are refused by srr validate).
KNOWN: list[tuple[str, re.Pattern[str]]] = []
KNOWN_IN_RUNS: list[tuple[str, re.Pattern[str]]] = []


def _known(path: Path_) -> bool:
    dotted = ".".join(map(str, path))
    return any(rx.search(dotted) for _item, rx in KNOWN)


# ---------------------------------------------------------------------------------------------
# The tests


@pytest.mark.slow
@settings(max_examples=max(10, BUDGET), suppress_health_check=[
    HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(data=st.data(), pair=st.sampled_from(FILES))
def test_a_mutated_scenario_validates_or_fails_in_one_line(
        tree: Path, capsys: pytest.CaptureFixture[str], data: st.DataObject,
        pair: tuple[str, str]) -> None:
    rel, scenario = pair
    m = data.draw(mutations(rel), label="mutation")
    if _known(m.path):
        return
    with written(tree, rel, mutated_text(rel, m)):
        code, err = cli(capsys, "validate", str(tree / scenario))
    line = one_line_naming_the_file(err, "validate", tree, codes=(), code=code)
    if m.kind == "duplicate":
        assert code == 2 and "set twice" in line, (m, err)


@pytest.mark.slow
@settings(max_examples=max(10, BUDGET), suppress_health_check=[
    HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(data=st.data(), scenario=st.sampled_from([s for _, s in FILES]))
def test_a_mutated_set_value_validates_or_fails_in_one_line(
        tree: Path, capsys: pytest.CaptureFixture[str], data: st.DataObject,
        scenario: str) -> None:
    doc = DOCS.get(scenario) or yamlio.load((SCENARIOS / scenario).read_text())
    path = data.draw(st.sampled_from(_paths(doc)) | st.just(("robots", 99, "name"))
                     | st.just(("duration", "x")) | st.just(("",)), label="path")
    text = data.draw(set_texts, label="value")
    if _known(path):
        return
    code, err = cli(capsys, "validate", str(tree / scenario), "--set",
                    f"{'.'.join(map(str, path))}={text}")
    one_line_naming_the_file(err, "validate", tree, codes=(), code=code)


@pytest.mark.slow
@settings(max_examples=max(5, BUDGET // 4), suppress_health_check=[
    HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(m=mutations(SUITE))
def test_a_mutated_suite_plans_or_fails_in_one_line(tree: Path, m: Mutation) -> None:
    if _known(m.path):
        return
    with written(tree, SUITE, mutated_text(SUITE, m)) as suite:
        try:
            plan_suite([suite])
        except SrrError as err:
            assert err.exit_code == 2, (m, str(err))
            text = str(err)
            assert "\n" not in text and text.startswith(str(tree)), (m, text)
            if m.kind == "duplicate":
                assert f"{suite}: " in text and "set twice" in text, (m, text)
        else:
            assert m.kind != "duplicate", m


def _numbers(node: Any, prefix: Path_ = ()) -> list[tuple[Path_, float]]:
    """Every number in ``node`` (not true/false), with its path."""
    if isinstance(node, bool):
        return []
    if isinstance(node, int | float):
        return [(prefix, node)]
    items = node.items() if isinstance(node, dict) else \
        enumerate(node) if isinstance(node, list) else ()
    return [found for key, value in items for found in _numbers(value, (*prefix, key))]


def _scaled(number: tuple[Path_, float], factor: float, form: str) -> tuple[Path_, str]:
    path, value = number
    new = value * factor
    if isinstance(value, int):
        return path, str(round(new))
    return path, format(new, form)


#: A run is worth its time when the value gets past validation: most of the runs take a
#: number of the scenario scaled (written as YAML 1.2 reads it, 1e3 included), the rest
#: anything.
LIGHT_PATHS = PATHS[LIGHT] + PATHS["forklift/robots.yaml"]
run_settings = st.one_of(
    st.builds(_scaled, st.sampled_from(_numbers(DOCS[LIGHT]) + _numbers(
        DOCS["forklift/robots.yaml"])), st.sampled_from([0.0, 0.5, 0.9, 1.1, 2.0, 10.0, -1.0]),
        st.sampled_from(["g", "e", ".3f"])),
    st.tuples(st.sampled_from(LIGHT_PATHS), set_texts))


@pytest.mark.slow
@settings(max_examples=max(4, BUDGET // 5), suppress_health_check=[
    HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(setting=run_settings)
def test_a_short_run_with_a_mutated_set_value_ends_cleanly(
        tree: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str],
        setting: tuple[Path_, str]) -> None:
    """0 pass, 1 fail (a mutated run against the baseline), 3 invalid, or 2 in one line with
    nothing written."""
    path, text = setting
    dotted = ".".join(map(str, path))
    if _known(path) or any(rx.search(dotted) for _item, rx in KNOWN_IN_RUNS):
        return
    out = tmp_path / "run"
    shutil.rmtree(out, ignore_errors=True)  # the examples share tmp_path
    code, err = cli(capsys, "run", str(tree / LIGHT), "--duration", "0.2", "-q", "--out",
                    str(out), "--set", f"{'.'.join(map(str, path))}={text}")
    one_line_naming_the_file(err, "run", tree, codes=(1, 3), code=code)
    if code == 2:
        assert not (out / "summary.json").exists()


def test_the_nightly_workflow_fuzzes_with_the_nightly_profile() -> None:
    import yaml

    wf = yaml.safe_load((SCENARIOS.parent / ".github" / "workflows" / "nightly.yml")
                        .read_text(encoding="utf-8"))
    step = next(s for s in wf["jobs"]["fuzz"]["steps"] if "test_fuzz_inputs.py" in
                s.get("run", ""))
    assert step["env"]["HYPOTHESIS_PROFILE"] == "nightly"
    assert settings.get_profile("nightly").max_examples > 20 * settings.get_profile(
        "ci").max_examples
    assert settings.get_profile("ci").derandomize
