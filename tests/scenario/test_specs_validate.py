"""``specs:`` formulas are checked when the scenario loads: a bad formula, an unknown signal,
object or zone, a wrong arity or a bound that is no whole tick is one line naming the file,
``specs[i].formula``, the spec and the token, exit 2, in ``srr validate`` and ``srr run``."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from harness import api
from harness.cli import main
from harness.scenario.specs import SignalContext, SpecError, parse_formula
from harness.scoring import check_scoring

BASE = """\
format_version: 1
name: t
duration: 2
srr_gt: true
robots:
  - name: forklift
    model: forklift
routes:
  r: {waypoints: [[0.0, 0.0], [5.0, 0.0]]}
workers:
  - name: worker
    route: [[3.0, -3.0], [3.0, 3.0]]
zones:
  loading_roi: [[2.0, -1.0], [4.0, -1.0], [4.0, 1.0], [2.0, 1.0]]
scoring:
  control: {robot: forklift, route: r}
"""


def _specs(*formulas: str, extra: str = "") -> str:
    items = "".join(f"  - name: s{i}\n    formula: {json.dumps(f)}\n{extra}"
                    for i, f in enumerate(formulas))
    return BASE + "specs:\n" + items


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str]:
    code = main(list(argv))
    _out, err = capsys.readouterr()
    return code, err.strip()


GOOD = [
    "always (clearance(forklift, worker) >= 0.5)",
    "always (in_zone(worker, loading_roi) -> eventually[0, 0.5] alarm)",
    "always (speed(forklift) <= 2.0 and distance(forklift, character_0) > 0)",
    "always[0, 1] tracking_error(forklift) < 0.3",
    "eventually[0s:500ms] (topic('/odom', 'twist.twist.linear.x') > 0.1)",
    "historically (not muted) or once[0, 0.25] alarm",
    "G (abs(topic(\"/odom\", 'pose.pose.position.y')) < 1)",
]


def test_good_formulas_load(tmp_path: Path) -> None:
    """Loading runs every check of a formula (``srr validate`` loads first; building the
    world, which it does next, is left out here: the bundled example validates whole in
    tests/wiring/test_validate.py)."""
    path = tmp_path / "s.yaml"
    path.write_text(_specs(*GOOD))
    sc = api.load(path)
    check_scoring(sc, srr_gt=sc.srr_gt, source=str(path))
    assert [s.formula for s in sc.specs] == GOOD


BAD = [
    ("always (clearence(forklift, worker) >= 0.5)",
     "unknown signal 'clearence' (did you mean 'clearance'?)"),
    ("always (clearance(forklift) >= 0.5)",
     "clearance(forklift): clearance takes 2 arguments (object, object), got 1"),
    ("always (speed(forklift, worker) >= 0.5)", "speed takes 1 argument"),
    ("always (clearance(forklift, wroker) >= 0.5)",
     "unknown robot or worker 'wroker' (did you mean 'worker'?)"),
    ("always (in_zone(worker, trailer) -> alarm)", "unknown zone 'trailer' (known: loading_roi)"),
    ("always (tracking_error(worker) < 1)", "unknown robot with a scoring.control route 'worker'"),
    ("always (in_zone(worker, loading_roi) -> eventually[0, 0.51] alarm)",
     "interval bound 0.51 s is not a whole number of ticks (the tick is 1/60 s)"),
    ("eventually[1, 0.5] alarm", "the lower bound is above the upper one"),
    ("always (clearance(forklift, worker) >= ", "not a formula: Syntax ERROR"),
    ("always (alarm && muted)", "unexpected character '&' at column 15 (write 'and'"),
    ("speed(forklift) != 1", "write '!==' for 'not equal'"),
    ("alarm; muted", "(a formula is one expression)"),
    ("always (speed >= 1)", "speed: a call, speed(...), expected"),
    ("always (topic('/odom') > 1)", "topic takes 2 arguments"),
    ("always (topic('odom//x', 'data') > 1)", "'odom//x' is not a topic name"),
    ("always (topic('/odom', 'twist..x') > 1)", "'twist..x' is not a field path"),
    ("always ('alarm')", "unexpected string 'alarm'"),
    ("always (1 > 0)", "the formula reads no signal"),
    ("   ", "empty formula"),
    ("always (float > 0)", "unknown reserved word 'float'"),
]


@pytest.mark.parametrize(("formula", "words"), BAD)
def test_bad_formula_is_one_line_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                        formula: str, words: str) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(_specs("always (alarm)", formula))
    for argv in (["validate", str(path)], ["run", str(path), "--out", str(tmp_path / "o")]):
        code, err = _run(capsys, *argv)
        assert code == 2, err
        assert len(err.splitlines()) == 1, err
        assert f"{path}: specs[1].formula: spec 's1': " in err, err
        assert words in err, err
        assert "Traceback" not in err
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(("text", "field", "words"), [
    (_specs("alarm", "muted").replace("name: s1", "name: s0"), "specs[1].name",
     "duplicate spec name 's0' (also specs[0]"),
    (_specs("alarm").replace("name: s0", "name: 'a.b'"), "specs[0].name", "must be letters"),
    (_specs("alarm").replace("    formula: ", "    formular: "), "specs[0].formular",
     "did you mean 'formula'"),
    (_specs("alarm", extra="    required: maybe\n"), "specs[0].required",
     "expected true or false"),
    (_specs("always (clearance(forklift, worker) > 0)").replace("srr_gt: true", "srr_gt: false")
     .replace("  control: {robot: forklift, route: r}\n", "  health: {}\n"), "specs[0].formula",
     "clearance(forklift, worker) needs ground truth"),
    (_specs("alarm").replace("  control: {robot: forklift, route: r}\n",
                             "  record_only: true\n"), "specs[0]",
     "a record-only scenario scores nothing"),
])
def test_bad_spec_entry_is_one_line_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                           text: str, field: str, words: str) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(text)
    code, err = _run(capsys, "validate", str(path))
    assert code == 2, err
    assert err.startswith(f"srr validate: {path}: {field}: "), err
    assert words in err and len(err.splitlines()) == 1, err


def test_a_disabled_spec_is_not_parsed(tmp_path: Path, capsys: pytest.CaptureFixture[str]
                                       ) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(_specs("always (nonsense(x) > 0)", extra="    enabled: false\n"))
    code, err = _run(capsys, "validate", str(path))
    assert code == 0, err
    code, err = _run(capsys, "validate", str(path), "--set", "specs.0.enabled=true")
    assert code == 2 and "unknown signal 'nonsense'" in err, err


CTX = SignalContext(objects={"forklift", "worker"}, zones={"loading_roi"},
                    routed={"forklift"}, tick_hz=60)


def test_parse_gives_rtamt_text_in_ticks_and_one_variable_per_signal() -> None:
    f = parse_formula("always (in_zone(worker, loading_roi) -> eventually[0, 0.5] alarm) "
                      "and always (in_zone(worker, loading_roi) -> not muted)", CTX)
    assert [s.text for s in f.signals] == ["in_zone(worker, loading_roi)", "alarm", "muted"]
    assert f.text == ("always ( s0 -> eventually [0:30] s1 ) and always ( s0 -> not s2 )")
    assert f.body is None  # the top operator is `and`, not `always`
    g = parse_formula("(always (clearance(forklift, worker) >= 0.5))", CTX)
    assert g.body == "( s0 >= 0.5 )" and g.unit == "m"
    assert parse_formula("always[0, 1] alarm", CTX).body is None  # bounded: its own trace
    assert parse_formula("always (alarm -> speed(forklift) < 1)", CTX).unit == ""
    with pytest.raises(SpecError, match="whole number of ticks"):
        parse_formula("eventually[0, 0.5] alarm", SignalContext({}, {}, {}, tick_hz=7))


def test_the_schema_has_the_specs_block(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["schema"]) == 0
    schema = json.loads(capsys.readouterr().out)
    assert schema["properties"]["specs"]["items"] == {"$ref": "#/$defs/StlSpec"}
    spec = schema["$defs"]["StlSpec"]
    assert spec["required"] == ["name", "formula"]
    assert set(spec["properties"]) == {"name", "formula", "required", "enabled"}
    assert spec["additionalProperties"] is False


_PIECES = st.sampled_from([
    "always", "eventually", "[0, 0.5]", "[0:1]", "[1,", "]", "(", ")", "->", "<->", "and",
    "or", "not", ">=", "<", "!==", "==", "=", "!", "&", "1", "0.5", "-", "+", "*", "/",
    "clearance(forklift, worker)", "clearance(", "speed(forklift)", "alarm", "muted",
    "in_zone(worker, loading_roi)", "tracking_error(forklift)", "topic('/odom', 'a.b[0]')",
    "'x'", ",", "until", "since", "prev", "next", "rise", "abs", "pow(", "G", "X", "é", "٣",
    "\u00a0", "\n", "s", "ms", "@", "{", ";", "1e999", "nan", "inf"])


@settings(max_examples=40, deadline=None)
@given(st.lists(_PIECES, max_size=12).map(" ".join) | st.text(max_size=40))
def test_any_text_parses_or_is_one_spec_error(text: str) -> None:
    try:
        f = parse_formula(text, CTX)
    except SpecError as err:
        assert str(err) and "\n" not in str(err)
    else:
        assert f.signals and f.text


def test_rtamt_is_imported_only_for_specs_and_its_absence_is_one_line() -> None:
    """A scenario without specs never imports rtamt (the ``stl`` extra); without the extra,
    one with specs is refused in one line naming the field."""
    root = Path(__file__).resolve().parents[2]
    code = (
        "import sys\n"
        "from harness.errors import ScenarioError\n"
        "from harness.scenario import load_scenario\n"
        f"load_scenario({str(root / 'scenarios' / 'dock_worker_crossing.yaml')!r})\n"
        "print('rtamt' in sys.modules)\n"
        "sys.modules['rtamt'] = None  # as if the extra were not installed\n"
        "try:\n"
        f"    load_scenario({str(root / 'scenarios' / 'dock_worker_crossing_specs.yaml')!r})\n"
        "except ScenarioError as err:\n"
        "    print(err)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env={**os.environ, "PYTHONPATH": str(root)}).stdout
    first, second = out.splitlines()
    assert first == "False"
    assert second.endswith("dock_worker_crossing_specs.yaml: specs[0].formula: spec "
                           "'keep_clear': specs need the 'stl' extra (rtamt): "
                           "pip install -e '.[stl]'"), second
