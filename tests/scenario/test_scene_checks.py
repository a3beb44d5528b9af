"""Mistakes a new scenario made that validated and ran with silently wrong scores: a zone off
the floor (refused), a fixed camera inside a robot or fixed geometry (warned), radians in a
degrees field (warned). Each is one line naming the file and the field, from ``srr validate``
as from ``srr run`` (which makes the same checks)."""

from __future__ import annotations

from pathlib import Path

import pytest

from harness.cli import main

ROOM = """\
format_version: 1
name: t
duration: 2
srr_gt: true
world: {size: [30, 20]}
robots:
  - {name: forklift, model: forklift, spawn: {position: [-12, 0, 0]}}
"""
ROOM_EXTENT = ("the 30 x 20 m room (world.size: x -15..15, y -10..10) and the trailer "
               "(world.dock)")


def _validate(capsys: pytest.CaptureFixture[str], tmp_path: Path,
              text: str) -> tuple[Path, int, list[str]]:
    path = tmp_path / "scenario.yaml"
    path.write_text(text)
    code = main(["validate", str(path)])
    return path, code, capsys.readouterr().err.strip().splitlines()


def _mine(err: list[str], words: str) -> list[str]:
    """The lines of ``err`` that say ``words`` (the scene also warns that nothing drives
    its forklift: no system under test publishes cmd_vel)."""
    return [line for line in err if words in line]


@pytest.mark.parametrize(("zones", "field", "extent", "why"), [
    ("zones:\n  loading_roi: [[-40, -3], [-35, -3], [-35, 3]]\n", "zones.loading_roi",
     "x -40..-35, y -3..3", "no robot or worker can be in it, so the safety score and any "
     "in_zone spec over it are never tested"),
    ("scoring:\n  perception: {area: [[0, 30], [5, 30], [5, 35], [0, 35]]}\n",
     "scoring.perception.area", "x 0..5, y 30..35",
     "no worker or track can be in it, so perception scores nothing"),
])
def test_a_zone_off_the_floor_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                         zones: str, field: str, extent: str,
                                         why: str) -> None:
    path, code, err = _validate(capsys, tmp_path, ROOM + zones)
    assert code == 2, err
    assert err == [f"srr validate: {path}: {field}: the polygon ({extent}) does not overlap "
                   f"the floor of {ROOM_EXTENT}: {why}; move it onto the floor"]


def test_a_tripwire_whose_line_misses_the_floor_is_refused(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path, code, err = _validate(capsys, tmp_path, ROOM + "zones:\n  trailer_tripwire: "
                                "{a: [40, 3], b: [40, -3]}\n")
    assert code == 2, err
    assert err == [f"srr validate: {path}: zones.trailer_tripwire: the line through a "
                   f"[40.0, 3.0] and b [40.0, -3.0] does not cross the floor of {ROOM_EXTENT}: "
                   "every point of the floor is on one side of it, so the forklift is always "
                   "or never inside the trailer; move it across the trailer's entrance"]


def test_zones_on_the_floor_are_accepted(tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    # partly outside the room, in the trailer only, a tripwire whose segment is off the floor
    # but whose line (what the safety score uses) crosses it: all fine, and no new warning
    _path, _code, before = _validate(capsys, tmp_path, ROOM)
    _path, code, err = _validate(capsys, tmp_path, ROOM + (
        "zones:\n  loading_roi: [[-20, -3], [-14, -3], [-14, 3], [-20, 3]]\n"
        "  trailer_tripwire: {a: [17, 30], b: [17, 25]}\n"
        "scoring:\n  perception: {area: [[16, -1], [20, -1], [20, 1], [16, 1]]}\n"))
    assert code == 0, err
    assert err == before, err



def test_a_tripwire_in_the_trailer_s_doorway_is_accepted(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # the line along the room's east wall, where the trailer meets it: the room on one side,
    # the trailer on the other (each floor polygon alone lies on one side of it)
    room = ROOM.replace("world: {size: [30, 20]}",
                        "world: {size: [30, 20], dock: {position: [15, 0]}}")
    _path, _code, before = _validate(capsys, tmp_path, room)
    _path, code, err = _validate(capsys, tmp_path, room + "zones:\n  trailer_tripwire: "
                                 "{a: [15, 3], b: [15, -3]}\n")
    assert code == 0, err
    assert err == before, err


@pytest.mark.parametrize(("pos", "inside"), [
    ("[-12, 0, 1]", "robot forklift at its spawn pose (its geom 'forklift/chassis')"),
    ("[-15.1, 0, 1]", "the west wall"),
    ("[-6, 6, 0.15]", "shelf 0 (world.shelves[0])"),  # in the rack's lowest board
    ("[0, 0, -0.5]", "the floor"),
])
def test_a_fixed_camera_inside_something_is_warned_about(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], pos: str, inside: str) -> None:
    path, code, err = _validate(
        capsys, tmp_path, ROOM + f"cameras:\n  - {{name: cam, spawn: {{position: {pos}}}}}\n")
    assert code == 0, err
    shown = ", ".join(f"{float(v):g}" for v in pos.strip("[]").split(","))
    assert _mine(err, "cameras[0]") == [
        f"srr validate: warning: {path}: cameras[0].spawn.position: ({shown}) is inside "
        f"{inside}: the camera sees only the inside of it; move the camera"], err


def _shell(outer: float, inner: float) -> tuple[str, str]:
    """A closed box shell's vertices and faces (MJCF): an outer box facing out and an inner
    box facing in, the hollow between them a room."""
    corners = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    vertex = " ".join(f"{c * h:g}" for h in (outer, inner) for v in corners for c in v)
    faces = []
    for off, flip in ((0, False), (8, True)):
        for a, b, c, d in quads:
            tris = [(a, b, c), (a, c, d)]
            faces += [(off + i, off + k, off + j) if flip else (off + i, off + j, off + k)
                      for i, j, k in tris]
    return vertex, " ".join(f"{i} {j} {k}" for t in faces for i, j, k in [t])


@pytest.mark.parametrize(("pos", "warned"), [
    ("[0, 0, 0]", False),     # in the building's hollow: a room, where cameras go
    ("[0, 0, 4.5]", True),    # in its ceiling's material
    ("[0, 0, 6]", False),     # above the building
])
def test_a_camera_in_a_hollow_mesh_is_in_its_room_not_inside_it(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], pos: str, warned: bool) -> None:
    vertex, face = _shell(5.0, 4.0)
    (tmp_path / "building.xml").write_text(
        '<mujoco model="building"><asset>'
        f'<mesh name="shell" vertex="{vertex}" face="{face}" inertia="shell"/></asset>'
        '<worldbody><geom name="hall" type="mesh" mesh="shell" pos="20 20 5"/>'
        '</worldbody></mujoco>')
    x, y, z = (float(v) for v in pos.strip("[]").split(","))
    text = (ROOM.replace("world: {size: [30, 20]}",
                         "world: {size: [60, 60], model: {mjcf: building.xml, mode: extend}}")
            + f"cameras:\n  - {{name: cam, spawn: {{position: [{x + 20}, {y + 20}, {z + 5}]}}}}\n")
    path, code, err = _validate(capsys, tmp_path, text)
    assert code == 0, err
    mine = _mine(err, "cameras[0]")
    assert bool(mine) == warned, err
    if warned:
        assert mine == [f"srr validate: warning: {path}: cameras[0].spawn.position: "
                        f"({x + 20:g}, {y + 20:g}, {z + 5:g}) is inside 'hall' of "
                        f"{tmp_path / 'building.xml'}: the camera sees only the inside of it; "
                        "move the camera"]


def test_a_fixed_camera_in_free_space_is_not_warned_about(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # above the forklift, and in a rack's open bay between two boards
    text = ROOM + ("cameras:\n  - {name: a, spawn: {position: [-12, 0, 3]}}\n"
                   "  - {name: b, spawn: {position: [-6, 6, 0.5]}}\n")
    _path, code, err = _validate(capsys, tmp_path, text)
    assert code == 0, err
    assert _mine(err, "cameras[") == [], err


@pytest.mark.parametrize(("change", "field", "value", "degrees"), [
    ("  - {name: f2, model: forklift, spawn: {position: [0, 0, 0], rpy_deg: [0, 0, 3.14159]}}\n",
     "robots[1].spawn.rpy_deg[2]", "3.14159", "180"),
    ("  - {name: f2, model: forklift, spawn: {position: [0, 0, 0], rpy_deg: [0, 0, -1.5708]}}\n",
     "robots[1].spawn.rpy_deg[2]", "-1.5708", "-90"),
    ("  - {name: f2, model: forklift, spawn: {position: [0, 0, 0]}, "
     "control: {max_steer_deg: 1.5708}}\n",
     "robots[1].control.max_steer_deg", "1.5708", "90"),
    ("cameras:\n  - {name: cam, spawn: {position: [0, 0, 3], rpy_deg: [0, 6.2832, 0]}}\n",
     "cameras[0].spawn.rpy_deg[1]", "6.2832", "360"),
    ("cameras:\n  - {name: cam, spawn: {position: [0, 0, 3]}, fovy_deg: 1.05}\n",
     "cameras[0].fovy_deg", "1.05", "60.2"),
    ("world:\n  shelves: [{position: [0, 6], yaw_deg: 3.1416}]\n",
     "world.shelves[0].yaw_deg", "3.1416", "180"),
])
def test_radians_in_a_degrees_field_are_warned_about(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], change: str, field: str,
        value: str, degrees: str) -> None:
    text = ROOM + change
    if change.startswith("world:"):
        text = ROOM.replace("world: {size: [30, 20]}\n", "") + change
    path, code, err = _validate(capsys, tmp_path, text)
    assert code == 0, err
    assert _mine(err, "looks like radians") == [
        f"srr validate: warning: {path}: {field}: {value} looks like radians: {value} rad is "
        f"{degrees}°; this field is in degrees, write {degrees}"], err


def test_degrees_that_only_come_near_radians_are_not_warned_about(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # 3.2 is 0.06 from pi; 0 is not radians; a field of view of 4 degrees is no radian one
    # (4 rad is more than 180 degrees); a disabled camera is not checked
    text = ROOM + (
        "  - {name: f2, model: forklift, spawn: {position: [0, 0, 0], rpy_deg: [0, 0, 3.2]}}\n"
        "cameras:\n  - {name: a, spawn: {position: [0, 0, 3], rpy_deg: [0, 0, 0]}, fovy_deg: 4}\n"
        "  - {name: b, enabled: false, spawn: {position: [0, 0, 3]}, fovy_deg: 1.05}\n")
    _path, code, err = _validate(capsys, tmp_path, text)
    assert code == 0, err
    assert _mine(err, "looks like radians") == [], err
