"""A message type the typestore does not know is refused where a plug-in declares it
(``ctx.publisher`` / ``ctx.subscribe``), by ``srr validate`` as by ``srr run``: one line
naming the file, the entry and the call, with the closest known type. It passed both, and
a publisher's first message would have failed to serialize mid-run."""

from __future__ import annotations

from pathlib import Path

import pytest

from harness.cli import main

SCENE = """\
format_version: 1
name: t
duration: 0.2
world: {{size: [6.0, 6.0], shelves: [], dock: {{enabled: false}}}}
robots:
  - name: tb
    model: turtlebot3_waffle_pi
systems_under_test:
  - {{name: typo, plugin: "tests.sut.typo_plugins:{cls}"}}
"""


@pytest.mark.parametrize(("cls", "words"), [
    ("PublishesTwits", "publisher('foo', 'geometry_msgs/msg/Twits'): unknown message type "
                       "'geometry_msgs/msg/Twits'; did you mean 'geometry_msgs/msg/Twist'?"),
    ("SubscribesOdometri", "subscribe('odom', 'nav_msgs/msg/Odometri'): unknown message "
                           "type 'nav_msgs/msg/Odometri'; did you mean "
                           "'nav_msgs/msg/Odometry'?"),
    ("ShortName", "publisher('foo', 'std_msgs/String'): unknown message type "
                  "'std_msgs/String'; did you mean 'std_msgs/msg/String'?"),
])
def test_an_unknown_message_type_is_refused_naming_the_entry(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], cls: str, words: str) -> None:
    path = tmp_path / "t.yaml"
    path.write_text(SCENE.format(cls=cls))
    out = tmp_path / "out"
    for command in ("validate", "run"):
        extra = ["--out", str(out), "-q"] if command == "run" else []
        assert main([command, str(path), *extra]) == 2
        err = capsys.readouterr().err.strip()
        assert err == f"srr {command}: {path}: systems_under_test[0]: {words}", err
        assert not out.exists()


def test_require_msgtype() -> None:
    from harness.serde.messages import UnknownMessageType, require_msgtype

    assert require_msgtype("geometry_msgs/msg/Twist") == "geometry_msgs/msg/Twist"
    with pytest.raises(UnknownMessageType, match=r"'nope' \(expected pkg/msg/Name\)"):
        require_msgtype("nope")
