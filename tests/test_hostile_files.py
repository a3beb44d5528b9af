"""Hostile files for every command that reads one: damaged MCAP files and bag directories,
run directories with a missing or malformed ``summary.json``, baselines with wrong types.

Every case ends in exit 2 with one line naming the file and what is wrong, or — for damage a
reader cannot detect (a flipped bit in an unchecked field) — in an ordinary result, or, for
``recover``, in a rebuilt bag when the damage is a cut like a crash leaves; never a
traceback, and never something written that looks like a valid result.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from harness import api
from harness.cli import main
from tests.conftest import SCENARIOS, ModuleTmp

pytestmark = pytest.mark.slow  # every test damages (or runs) a real run

FW = SCENARIOS / "forklift_warehouse.yaml"
Damage = Callable[[bytes], bytes]


@pytest.fixture(scope="module")
def good_run(module_tmp: ModuleTmp) -> Path:
    out = module_tmp("hostile") / "run"
    api.run_scenario(api.load(FW, duration=0.5), source=str(FW), out=out)
    return out


def truncate(at: float) -> Damage:
    return lambda data: data[: int(len(data) * at)]


def flip(where: list[tuple[float, int]]) -> Damage:
    def apply(data: bytes) -> bytes:
        b = bytearray(data)
        for pos, bit in where:
            i = min(int(len(b) * pos), len(b) - 1)
            b[i] ^= 1 << bit
        return bytes(b)
    return apply


damages = st.one_of(
    st.floats(0.0, 0.999).map(truncate),
    st.lists(st.tuples(st.floats(0.0, 1.0), st.integers(0, 7)), min_size=1,
             max_size=8).map(flip),
    st.binary(max_size=2000).map(lambda junk: (lambda _data: junk)),
    st.just(lambda _data: b""),
    st.just(lambda _data: b'{"not": "an mcap"}\n'),
)


def copy_run(good: Path, tmp: Path) -> Path:
    run = tmp / "run"
    if run.exists():
        shutil.rmtree(run)
    shutil.copytree(good, run)
    return run


def cli(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str]:
    code = main(list(argv))
    return code, capsys.readouterr().err.strip()


def one_clean_line(code: int, err: str, command: str) -> None:
    assert code in (0, 1, 2, 3), (code, err)
    if code == 2:
        said = "baseline bless" if command == "baseline" else command  # as the command names it
        assert len(err.splitlines()) == 1 and err.startswith(f"srr {said}: "), err
        assert "Traceback" not in err


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(damage=damages, command=st.sampled_from(["inspect", "report", "replay", "bless",
                                                "diff", "recover", "export"]))
def test_damaged_mcap(good_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str],
                      damage: Damage, command: str) -> None:
    run = copy_run(good_run, tmp_path)
    (mcap,) = (run / "bag").glob("*.mcap")
    original = mcap.read_bytes()
    mcap.write_bytes(damage(original))
    report_before = (run / "report.html").read_bytes()
    out, bdir = tmp_path / "out", tmp_path / "baselines"
    shutil.rmtree(out, ignore_errors=True)
    shutil.rmtree(bdir, ignore_errors=True)
    (tmp_path / "d.html").unlink(missing_ok=True)  # examples share tmp_path
    (tmp_path / "x.rrd").unlink(missing_ok=True)
    argv = {"inspect": ["inspect", str(run / "bag")], "report": ["report", str(run)],
            "replay": ["replay", str(run), "--out", str(out), "-q"],
            "bless": ["baseline", "bless", str(run), "--reason", "r", "--baselines",
                      str(bdir)],
            "diff": ["diff", str(good_run), str(run), "--html", str(tmp_path / "d.html")],
            "recover": ["recover", str(run)],
            "export": ["export", str(run), "--rerun", str(tmp_path / "x.rrd")]}[command]
    damaged = mcap.read_bytes()
    code, err = cli(capsys, *argv)
    one_clean_line(code, err, argv[0])
    if code == 2:
        assert not out.exists() and not (tmp_path / "d.html").exists()
        assert not (tmp_path / "x.rrd").exists() and not list(tmp_path.glob(".*.partial"))
        assert (run / "report.html").read_bytes() == report_before
        assert not list(bdir.glob("*.json")) if bdir.exists() else True
        assert mcap.read_bytes() == damaged  # recover leaves what it refuses untouched
    shortened = damaged != original and len(damaged) < len(original) * 0.999
    if command == "recover" and code == 0 and shortened:
        # a crash-like cut is what recover is for: the result reads back whole
        assert api.recover(run).bag.status == "valid"
    elif shortened:
        assert code == 2, err  # a shortened file is always noticed


@pytest.fixture(scope="module", params=["bag", "mcap"])
def ros1_run(request: pytest.FixtureRequest, module_tmp: ModuleTmp) -> Path:
    """The forklift run recorded as ROS 1: a ``.bag``, or MCAP with the ``ros1`` profile."""
    out = module_tmp(f"hostile-ros1-{request.param}") / "run"
    sc = api.load(FW, duration=0.5, overrides=["output.ros=1",
                                               f"output.format={request.param}"])
    api.run_scenario(sc, source=str(FW), out=out)
    return out


@settings(max_examples=25, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(damage=damages, command=st.sampled_from(["inspect", "report", "replay", "bless",
                                                "diff", "recover", "export"]))
def test_damaged_ros1_recording(ros1_run: Path, tmp_path: Path,
                                capsys: pytest.CaptureFixture[str], damage: Damage,
                                command: str) -> None:
    """The same for a ROS 1 run's recording; ``recover`` refuses it whole or damaged."""
    run = copy_run(ros1_run, tmp_path)
    (file,) = (run / "bag").iterdir()
    original = file.read_bytes()
    file.write_bytes(damage(original))
    report_before = (run / "report.html").read_bytes()
    out, bdir = tmp_path / "out", tmp_path / "baselines"
    shutil.rmtree(out, ignore_errors=True)
    shutil.rmtree(bdir, ignore_errors=True)
    (tmp_path / "x.rrd").unlink(missing_ok=True)
    argv = {"inspect": ["inspect", str(run / "bag")], "report": ["report", str(run)],
            "replay": ["replay", str(run), "--out", str(out), "-q"],
            "bless": ["baseline", "bless", str(run), "--reason", "r", "--baselines",
                      str(bdir)],
            "diff": ["diff", str(ros1_run), str(run)],
            "recover": ["recover", str(run)],
            "export": ["export", str(run), "--rerun", str(tmp_path / "x.rrd")]}[command]
    damaged = file.read_bytes()
    code, err = cli(capsys, *argv)
    one_clean_line(code, err, argv[0])
    if code == 2:
        assert not out.exists() and (run / "report.html").read_bytes() == report_before
        assert not (tmp_path / "x.rrd").exists()
        assert not list(bdir.glob("*.json")) if bdir.exists() else True
        assert file.read_bytes() == damaged
    if damaged != original and len(damaged) < len(original) * 0.999:
        assert code == 2, err  # a shortened file is always noticed
    if command == "recover" and damaged[:32] == original[:32]:  # still says it is ROS 1
        assert code == 2 and "a ROS 1 recording" in err, err


SUMMARIES = ["", "{", "[]", "null", '{"verdict": 3}', '{"scenario": "x"}',
             '{"verdict": "PASS", "topics": 5}', '{"verdict": "PASS", "seed": "abc", '
             '"scenario": "forklift_warehouse", "metrics": "none"}']


@pytest.mark.parametrize("text", SUMMARIES)
@pytest.mark.parametrize("command", ["report", "replay", "bless", "export"])
def test_malformed_summary(good_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str],
                           text: str, command: str) -> None:
    run = copy_run(good_run, tmp_path)
    (run / "summary.json").write_text(text)
    before = (run / "report.html").read_bytes()
    argv = {"report": ["report", str(run)],
            "replay": ["replay", str(run), "--out", str(tmp_path / "out"), "-q"],
            "bless": ["baseline", "bless", str(run), "--reason", "r", "--baselines",
                      str(tmp_path / "b")],
            "export": ["export", str(run), "--rerun", str(tmp_path / "b.rrd")]}[command]
    code, err = cli(capsys, *argv)
    assert code == 2, err
    assert not (tmp_path / "b.rrd").exists()
    one_clean_line(code, err, argv[0])
    assert "summary.json" in err, err
    assert not (tmp_path / "out").exists() and not (tmp_path / "b").exists()
    assert (run / "report.html").read_bytes() == before


SUMMARY_FIELDS = [("baseline", 5), ("baseline.topics_differing", 5),
                  ("baseline.versions_differing", "x"),
                  ("baseline.versions_differing", {"numpy": 3}),
                  ("baseline.config_differences", 7), ("baseline.digest_matches", "yes"),
                  ("comparison", [1]), ("comparison", [{"name": "m"}]), ("duration_s", "x"),
                  ("reasons", 5), ("warnings", 5), ("systems_under_test", 5), ("versions", 5),
                  ("versions", {"numpy": [2]}), ("scene_files", 5), ("graphs", [{}]),
                  ("sut_endpoints", {"follower": {"publishes": 5}})]


@pytest.mark.parametrize(("field", "value"), SUMMARY_FIELDS)
@pytest.mark.parametrize("command", ["report", "bless", "replay"])
def test_malformed_summary_field(good_run: Path, tmp_path: Path,
                                 capsys: pytest.CaptureFixture[str], field: str, value: object,
                                 command: str) -> None:
    """Every part of a summary that the report, the console or blessing reads (the baseline
    entry, the comparison rows, reasons, versions, ...) is checked field by field: a wrong
    type is one line naming it, nothing written (they were tracebacks)."""
    run = copy_run(good_run, tmp_path)
    data = json.loads((run / "summary.json").read_text())
    if field.startswith("baseline."):
        data["baseline"] = {"digest": "0", "digest_matches": False, field.split(".")[1]: value}
    else:
        data[field] = value
    (run / "summary.json").write_text(json.dumps(data))
    before = (run / "report.html").read_bytes()
    argv = {"report": ["report", str(run)],
            "bless": ["baseline", "bless", str(run), "--reason", "r", "--baselines",
                      str(tmp_path / "b")],
            "replay": ["replay", str(run), "--out", str(tmp_path / "b"), "-q"]}[command]
    code, err = cli(capsys, *argv)
    assert code == 2, err
    one_clean_line(code, err, argv[0])
    assert f"summary.json: {field}" in err, err
    assert not (tmp_path / "b").exists() and (run / "report.html").read_bytes() == before


def test_missing_summary_and_missing_bag(good_run: Path, tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    run = copy_run(good_run, tmp_path)
    (run / "summary.json").unlink()
    for argv in (["report", str(run)], ["replay", str(run), "-q"]):
        code, err = cli(capsys, *argv)
        assert code == 2 and "summary.json" in err, err
    run = copy_run(good_run, tmp_path)
    shutil.rmtree(run / "bag")
    for argv in (["report", str(run)], ["replay", str(run), "-q"], ["inspect", str(run)]):
        code, err = cli(capsys, *argv)
        assert code == 2 and "metadata.yaml: missing" in err, err


@pytest.mark.parametrize("edit", [
    lambda d: d.update(metrics=[1, 2]),
    lambda d: d.update(seed="abc"),
    lambda d: d["metrics"][next(iter(d["metrics"]))].update(value="high"),
    lambda d: d.update(config=[1]),
    lambda d: d.pop("scenario"),
])
def test_baselines_with_wrong_types(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                    edit: Callable[[dict[str, object]], None]) -> None:
    bdir = tmp_path / "b"
    bdir.mkdir()
    data = json.loads((SCENARIOS.parent / "baselines" / "forklift_warehouse.json").read_text())
    edit(data)
    (bdir / "forklift_warehouse.json").write_text(json.dumps(data))
    code, err = cli(capsys, "run", str(FW), "--duration", "0.5", "--baselines", str(bdir),
                    "--out", str(tmp_path / "r"), "-q")
    assert code == 2, err
    assert err.startswith(f"srr run: {bdir / 'forklift_warehouse.json'}: not a valid baseline"), err
    assert len(err.splitlines()) == 1
    assert not (tmp_path / "r" / "summary.json").exists()
