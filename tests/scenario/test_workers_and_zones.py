"""The ``workers:`` and ``zones:`` blocks: defaults, and errors naming the file and the field."""

from __future__ import annotations

from pathlib import Path

import pytest

from harness.cli import main
from harness.errors import ScenarioError
from harness.scenario import load_scenario, scenario_to_mapping

BASE = """\
format_version: 1
name: t
duration: 1
"""

WORKERS = """\
workers:
  - route: [[0, 0], [5, 0]]
  - name: bob
    route: [[1, 1], [1, 4], [2, 4]]
    speed: 0.9
    loop: cycle
    variation: 0.1
zones:
  loading_roi: [[10, -2], [14, -2], [14, 2], [10, 2]]
  trailer_tripwire: {a: [15, -1.5], b: [15, 1.5], inside: right}
"""


def test_workers_and_zones_load_with_defaults(tmp_path: Path) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(BASE + WORKERS)
    sc = load_scenario(path)
    w0, bob = sc.workers
    assert (w0.speed, w0.loop, w0.height, w0.radius, w0.variation) == (
        1.2, "back_and_forth", 1.75, 0.25, 0.0)
    assert (sc.worker_name(0), sc.worker_name(1)) == ("character_0", "bob")
    assert bob.route == ((1.0, 1.0), (1.0, 4.0), (2.0, 4.0)) and bob.loop == "cycle"
    assert len(sc.zones.loading_roi) == 4
    wire = sc.zones.trailer_tripwire
    assert wire is not None and (wire.a, wire.b, wire.inside) == ((15.0, -1.5), (15.0, 1.5),
                                                                  "right")
    resolved = scenario_to_mapping(sc)
    assert resolved["workers"][0]["speed"] == 1.2
    assert resolved["zones"]["trailer_tripwire"]["inside"] == "right"
    empty = tmp_path / "e.yaml"
    empty.write_text(BASE)
    sc = load_scenario(empty)
    assert sc.workers == () and sc.zones.loading_roi == () and sc.zones.trailer_tripwire is None


@pytest.mark.parametrize(("yaml_text", "field", "words"), [
    ("workers: [{route: [[0, 0]]}]", "workers[0].route", "at least two waypoints"),
    ("workers: [{route: [[0, 0], [1, 0], [1, 0]]}]", "workers[0].route[2]",
     "repeats the previous"),
    ("workers: [{route: [[0, 0], [1, 0]], speed: 0}]", "workers[0].speed", "must be > 0"),
    ("workers: [{route: [[0, 0], [1, 0]], loop: forever}]", "workers[0].loop", "'cycle'"),
    ("workers: [{route: [[0, 0], [1, 0]], radius: 0.7}]", "workers[0].radius",
     "height / 3"),
    ("workers: [{route: [[0, 0], [1, 0]], name: 'a b'}]", "workers[0].name", "must be letters"),
    ("workers: [{route: [[0, 0], [1, 0]]}, {name: character_0, route: [[0, 1], [1, 1]]}]",
     "workers[1].name", "duplicate worker name 'character_0'"),
    ("workers: [{path: [[0, 0], [1, 0]]}]", "workers[0].path", "unknown field"),
    ("zones: {loading_roi: [[0, 0], [1, 0]]}", "zones.loading_roi", "at least three points"),
    ("zones: {loading_roi: [[0, 0], [1, 1], [2, 2]]}", "zones.loading_roi", "zero area"),
    ("zones: {trailer_tripwire: {a: [1, 2], b: [1, 2]}}", "zones.trailer_tripwire.b",
     "must differ from a"),
    ("zones: {trailer_tripwire: {a: [1, 2], b: [3, 2], inside: up}}",
     "zones.trailer_tripwire.inside", "'left'"),
    ("zones: {trailer_tripwire: {a: [1, 2]}}", "zones.trailer_tripwire.b", "required field"),
], ids=["one-waypoint", "repeated-waypoint", "zero-speed", "bad-loop", "too-wide",
        "bad-name", "duplicate-name", "unknown-key", "roi-two-points", "roi-no-area",
        "tripwire-a-is-b", "tripwire-bad-side", "tripwire-missing-b"])
def test_bad_workers_and_zones_name_file_and_field(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], yaml_text: str, field: str,
        words: str) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(BASE + yaml_text + "\n")
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert info.value.file == str(path) and info.value.field == field
    assert words in info.value.message
    code = main(["validate", str(path)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1
    assert f"{path}: {field}: " in err


def test_zone_errors_name_the_included_file(tmp_path: Path) -> None:
    (tmp_path / "zones.yaml").write_text("zones: {loading_roi: [[0, 0], [1, 0]]}\n")
    path = tmp_path / "s.yaml"
    path.write_text(BASE + "include: zones.yaml\n")
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert info.value.file == str(tmp_path / "zones.yaml")
    assert info.value.field == "zones.loading_roi"
