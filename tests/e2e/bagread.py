"""Independent read-back of recorded bags with mcap + mcap-ros2-support (not rosbags)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory


def mcap_file(run_dir: Path) -> Path:
    (path,) = sorted((run_dir / "bag").glob("*.mcap"))
    return path


def decoded(run_dir: Path) -> Iterator[tuple[str, str, int, Any]]:
    """(topic, schema name, log time ns, decoded message) for every message in the bag."""
    with mcap_file(run_dir).open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for schema, channel, message, msg in reader.iter_decoded_messages():
            yield channel.topic, schema.name, message.log_time, msg
