"""Every file that shapes the scene is in its digest (``scene_files``): an MJCF model's
``<include>`` files, recursively, as MuJoCo finds them, as well as the file, its meshes and
its textures; a file without includes keeps the digest it had."""

from __future__ import annotations

import hashlib
from pathlib import Path

from harness.scenario import load_scenario
from harness.sim import World
from harness.sim.robots.model_file import file_digest, included_files
from tests.conftest import SCENARIOS

MAIN = """\
<mujoco>
  <include file="parts/room.xml"/>
  <worldbody><light pos="0 0 4"/></worldbody>
</mujoco>
"""
ROOM = """\
<mujoco>
  <include file="pillar.xml"/>
  <worldbody><geom name="wall" type="box" pos="3 0 1" size="0.1 3 1"/></worldbody>
</mujoco>
"""
PILLAR = """\
<mujoco>
  <worldbody><geom name="pillar" type="cylinder" pos="-2 0 1" size="0.2 1"/></worldbody>
</mujoco>
"""
SCENARIO = """\
format_version: 1
name: t
duration: 1
world: {model: {mjcf: world/main.xml}}
robots:
  - {name: tb3, model: turtlebot3_waffle_pi}
"""


def _digest(tmp_path: Path) -> str:
    path = tmp_path / "scenario.yaml"
    return World.build(load_scenario(path), str(path)).scene_files["world.model"]


def test_editing_an_included_file_changes_the_scene_digest(tmp_path: Path) -> None:
    (tmp_path / "world" / "parts").mkdir(parents=True)
    (tmp_path / "world" / "main.xml").write_text(MAIN)
    (tmp_path / "world" / "parts" / "room.xml").write_text(ROOM)
    pillar = tmp_path / "world" / "parts" / "pillar.xml"  # beside the file including it
    pillar.write_text(PILLAR)
    (tmp_path / "scenario.yaml").write_text(SCENARIO)
    assert [name for name, _ in included_files(tmp_path / "world" / "main.xml")] == [
        "parts/room.xml", "pillar.xml"]
    first = _digest(tmp_path)
    assert _digest(tmp_path) == first
    pillar.write_text(PILLAR.replace('pos="-2 0 1"', 'pos="-2 1 1"'))  # same path, moved
    second = _digest(tmp_path)
    assert second != first
    room = tmp_path / "world" / "parts" / "room.xml"
    room.write_text(ROOM.replace('size="0.1 3 1"', 'size="0.1 3 2"'))
    assert _digest(tmp_path) not in (first, second)


def test_a_file_without_includes_keeps_its_digest() -> None:
    """The bundled model files include nothing: their digest is still the file's bytes and
    its assets' names, so the bundled baselines' scene digests stay comparable."""
    path = SCENARIOS / "models" / "shelf_world" / "shelf_world.xml"
    assert included_files(path) == []
    assets = {"srr-0123.obj": b""}
    expected = hashlib.sha256(path.read_bytes())
    expected.update(b"srr-0123.obj")
    assert file_digest(path, assets) == expected.hexdigest()
