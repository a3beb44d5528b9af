"""``srr baseline bless`` and ``srr report`` check the run's bag against its summary first,
as ``srr diff`` does: a bag swapped for another recording, or one whose bytes were damaged,
is refused (exit 2, one line) and nothing is written."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from harness.cli import main
from tests.conftest import ModuleTmp

FORKLIFT = Path(__file__).resolve().parents[2] / "scenarios" / "forklift_warehouse.yaml"

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def runs(module_tmp: ModuleTmp) -> tuple[Path, Path]:
    root = module_tmp("bless")
    plain, other = root / "plain", root / "other"
    assert main(["run", str(FORKLIFT), "--duration", "1", "-q", "--no-video", "--out",
                 str(plain)]) in (0, 1)
    assert main(["run", str(FORKLIFT), "--duration", "1", "-q", "--no-video", "--out",
                 str(other), "--set", "robots.forklift.odometry.odom_topic=odom2"]) in (0, 1)
    return plain, other


def _swapped(tmp_path: Path, runs: tuple[Path, Path]) -> Path:
    run = tmp_path / "swapped"
    shutil.copytree(runs[0], run)
    shutil.copy(runs[1] / "bag" / "bag.mcap", run / "bag" / "bag.mcap")
    return run


def _damaged(tmp_path: Path, runs: tuple[Path, Path]) -> Path:
    run = tmp_path / "damaged"
    shutil.copytree(runs[0], run)
    mcap = run / "bag" / "bag.mcap"
    data = bytearray(mcap.read_bytes())
    data[len(data) // 2] ^= 0xFF  # a byte inside a chunk: its CRC no longer holds
    mcap.write_bytes(bytes(data))
    return run


@pytest.mark.parametrize("make", [_swapped, _damaged])
def test_bless_and_report_refuse_a_bag_that_is_not_the_summarys(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], runs: tuple[Path, Path],
        make: object) -> None:
    run = make(tmp_path, runs)  # type: ignore[operator]
    before = (run / "report.html").read_bytes()
    baselines = tmp_path / "baselines"
    for argv in (["baseline", "bless", str(run), "--reason", "x", "--baselines",
                  str(baselines)], ["report", str(run), "--no-video"]):
        assert main(argv) == 2, argv
        err = capsys.readouterr().err.strip()
        assert "\n" not in err and str(run / "bag") in err, err
        assert "does not match summary.json" in err or "cannot read" in err, err
    assert not baselines.exists()
    assert (run / "report.html").read_bytes() == before
