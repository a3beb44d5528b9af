"""Release hygiene: the wheel that ``python -m build`` makes (the same PEP 517 build, here
through ``pip wheel``: setuptools in an isolated build environment) holds every file of the
``harness`` package, installs into a fresh virtual environment, and there ``srr --version``
names the installed version and ``srr run`` runs a bundled scenario from a folder outside the
repository, compares it with its baseline and passes.

The fresh environment has no srr but the wheel's: it sees the test environment's third-party
packages through a ``.pth`` file naming the folders this interpreter imports from (but the
checkout), plain path entries after its own site-packages (an editable install's finder in
them is not loaded: ``.pth`` files are read only in the environment's own site-packages),
and PYTHONPATH is cleared; the test checks that ``harness`` is imported from the wheel.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

pytestmark = pytest.mark.slow

#: The bundled scenario run from the installed wheel: a model file (URDF and meshes, found
#: relative to the scenario) and a baseline to compare with.
SCENARIO = "diffbot_urdf"


def _env() -> dict[str, str]:
    return {k: v for k, v in os.environ.items()
            if k not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")}


def _run(cmd: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    res = subprocess.run(cmd, cwd=cwd, env=_env(), text=True, capture_output=True,
                         timeout=600, check=False)
    assert res.returncode == 0, f"{cmd}: exit {res.returncode}\n{res.stdout}\n{res.stderr}"
    return res


def _package_files(src: Path) -> set[str]:
    return {p.relative_to(src).as_posix() for p in (src / "harness").rglob("*")
            if p.is_file() and "__pycache__" not in p.parts and p.suffix != ".pyc"}


def test_wheel_installs_in_a_fresh_venv_and_runs_a_scenario(tmp_path: Path) -> None:
    # the sources as a checkout has them (no build/ or egg-info of earlier builds)
    src = tmp_path / "src"
    shutil.copytree(ROOT / "harness", src / "harness",
                    ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    for name in ("pyproject.toml", "README.md"):
        shutil.copy2(ROOT / name, src / name)
    dist = tmp_path / "dist"
    _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(dist), str(src)],
         tmp_path)
    (wheel,) = dist.glob("srr-*.whl")
    with zipfile.ZipFile(wheel) as zf:
        shipped = {n for n in zf.namelist() if n.startswith("harness/")}
    missing = _package_files(src) - shipped
    assert not missing, f"the wheel lacks package files: {sorted(missing)}"

    venv = tmp_path / "venv"
    _run([sys.executable, "-m", "venv", "--without-pip", str(venv)], tmp_path)
    py = venv / "bin" / "python"
    site = Path(_run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                     tmp_path).stdout.strip())
    # where this interpreter finds its packages, but not the sources: no folder that holds a
    # harness package (the checkout; its .venv, as CI has it, stays)
    deps = [p for p in dict.fromkeys(sys.path)
            if p and Path(p).is_dir() and not (Path(p) / "harness").exists()]
    (site / "_srr_test_deps.pth").write_text("".join(f"{d}\n" for d in deps), encoding="utf-8")
    _run([sys.executable, "-m", "pip", "--python", str(py), "install", "--no-deps", "--no-index",
          "-q", str(wheel)], tmp_path)

    # a project outside the repository: the scenario, its model files and its baseline
    proj = tmp_path / "project"
    (proj / "scenarios" / "models").mkdir(parents=True)
    shutil.copy2(ROOT / "scenarios" / f"{SCENARIO}.yaml", proj / "scenarios")
    shutil.copytree(ROOT / "scenarios" / "models" / "srr_diffbot",
                    proj / "scenarios" / "models" / "srr_diffbot")
    shutil.copytree(ROOT / "baselines", proj / "baselines",
                    ignore=lambda _d, names: [n for n in names
                                              if not n.startswith(f"{SCENARIO}.")])

    where = _run([str(py), "-c", "import harness, importlib.metadata as m; "
                  "print(harness.__file__); print(m.version('srr'))"], proj).stdout.split()
    assert Path(where[0]).is_relative_to(venv), f"harness imported from {where[0]}"
    srr = str(venv / "bin" / "srr")
    assert _run([srr, "--version"], proj).stdout.strip() == f"srr {where[1]}"

    res = _run([srr, "run", f"scenarios/{SCENARIO}.yaml", "--out", "runs/r", "-q"], proj)
    summary = json.loads((proj / "runs" / "r" / "summary.json").read_text(encoding="utf-8"))
    assert summary["verdict"] == "PASS", res.stdout
    assert Path(summary["baseline"]["path"]).resolve() == \
        (proj / "baselines" / f"{SCENARIO}.json").resolve()
    assert (proj / "runs" / "r" / "report.html").stat().st_size > 0
