"""A MUJOCO_GL backend whose library is missing (``MUJOCO_GL=osmesa`` without OSMesa) failed
inside PyOpenGL while ``import mujoco`` loaded it, with a 40-line traceback for any command
that builds a scene: it is one line saying what to install, exit 2. The failure is made here
by a file at ``.../mujoco/osmesa/`` raising as PyOpenGL does, whatever this machine has."""

from __future__ import annotations

import runpy
from pathlib import Path

import pytest

from harness import cli
from harness.glbackend import gl_failure


def _raise_from_backend(tmp_path: Path, backend: str) -> BaseException:
    where = tmp_path / "site" / "mujoco" / backend
    where.mkdir(parents=True)
    (where / "__init__.py").write_text("_p = None\n_p.GL.glGetError\n")
    try:
        runpy.run_path(str(where / "__init__.py"))
    except AttributeError as err:
        return err
    raise AssertionError("the stand-in backend did not raise")


def test_a_backend_failure_is_one_line_saying_what_to_install(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    err = _raise_from_backend(tmp_path, "osmesa")
    monkeypatch.setenv("MUJOCO_GL", "osmesa")

    def validate(_args: object) -> int:
        raise err

    monkeypatch.setitem(cli.COMMANDS, "validate", validate)
    assert cli.main(["validate", "x.yaml"]) == 2
    out = capsys.readouterr().err.strip()
    assert out.startswith("srr validate: MuJoCo cannot load its OpenGL backend "
                          "(MUJOCO_GL=osmesa: AttributeError: ")
    assert "apt-get install libosmesa6" in out and "MUJOCO_GL=disable" in out
    assert len(out.splitlines()) == 1


def test_other_errors_are_not_taken_for_a_backend_failure(tmp_path: Path) -> None:
    assert gl_failure(ValueError("x")) is None
    egl = gl_failure(_raise_from_backend(tmp_path, "egl"))
    assert egl is not None and "libegl1" in str(egl)
