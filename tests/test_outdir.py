"""``--out`` paths where no output folder can be: one line naming the option, exit 2."""

from __future__ import annotations

from pathlib import Path

import pytest

from harness.cli import main

SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "forklift_warehouse.yaml"
SUITE = Path(__file__).resolve().parents[1] / "scenarios" / "suites" / "pr.yaml"


@pytest.mark.parametrize("command", [["run", str(SCENARIO)], ["suite", str(SUITE)]])
def test_an_out_path_that_cannot_be_a_folder_is_one_line(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], command: list[str]) -> None:
    afile = tmp_path / "afile"
    afile.write_text("mine")
    for out, said in ((afile, f"--out {afile}: is a file, not a folder"),
                      (afile / "sub" / "x", f"--out {afile / 'sub' / 'x'}: {afile} is a file, "
                                            "not a folder")):
        assert main([*command, "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip().splitlines()  # warnings first, in a suite
        assert err[-1] == f"srr {command[0]}: {said}", err
    assert afile.read_text() == "mine"


def test_a_bad_argument_is_one_line_naming_the_command_once(
        capsys: pytest.CaptureFixture[str]) -> None:
    for argv, said in ((["bogus"], "srr: error: argument command: invalid choice"),
                       (["validate", "a.yaml", "b.yaml"], "srr: error: unrecognized "
                                                          "arguments: b.yaml"),
                       (["run", "--seed", "x", "a.yaml"], "srr run: error: argument --seed")):
        with pytest.raises(SystemExit) as exit_:
            main(argv)
        assert exit_.value.code == 2
        assert capsys.readouterr().err.startswith(said)


def test_a_run_that_fails_leaves_an_out_folder_the_user_made(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """A run that fails after it took its (empty, user-made) --out folder removes what it
    wrote there, not the folder."""
    from harness.errors import SrrError
    from harness.run import record

    def fails(*args: object, **kwargs: object) -> None:
        raise SrrError("no recorder today")

    monkeypatch.setattr(record, "_open_recorder", fails)
    out = tmp_path / "mine"
    out.mkdir()
    assert main(["run", str(SCENARIO), "--duration", "1", "-q", "--out", str(out)]) == 2
    assert capsys.readouterr().err.strip().endswith("no recorder today")
    assert out.is_dir() and not any(out.iterdir())
    fresh = tmp_path / "fresh"  # one srr made goes with what it wrote
    assert main(["run", str(SCENARIO), "--duration", "1", "-q", "--out", str(fresh)]) == 2
    assert not fresh.exists()


def test_reason_without_a_bless_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    """--reason says why a baseline is blessed: given without the option that blesses, it
    would be dropped silently."""
    for argv, said in (
            (["run", str(SCENARIO), "--reason", "x"], "srr run: --reason: only with "
                                                      "--update-baseline"),
            (["suite", str(SUITE), "--reason", "x"], "srr suite: --reason: only with "
                                                     "--update-baselines")):
        assert main(argv) == 2
        assert capsys.readouterr().err.strip().splitlines()[-1].startswith(said)


def test_a_file_option_under_a_file_says_so(tmp_path: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    afile = tmp_path / "afile"
    afile.write_text("mine")
    assert main(["schema", "--out", str(afile / "x.json")]) == 2
    assert capsys.readouterr().err.strip() == (
        f"srr schema: --out {afile / 'x.json'}: {afile} is a file, not a folder")


def test_remove_empty_undoes_only_what_making_a_folder_made(tmp_path: Path) -> None:
    from harness.outdir import first_missing, remove_empty

    run = tmp_path / "reports" / "scene" / "run1"
    made = first_missing(run)
    assert made == tmp_path / "reports"
    run.mkdir(parents=True)
    (tmp_path / "reports" / "other").mkdir()  # another run's, made meanwhile
    remove_empty(run, made)
    assert not (tmp_path / "reports" / "scene").exists()
    assert (tmp_path / "reports" / "other").is_dir()  # not empty: stays, and so does reports
    remove_empty(tmp_path / "elsewhere", made)  # not under what was made: nothing happens
    assert (tmp_path / "reports").is_dir()
    assert first_missing(tmp_path) is None
