"""The layers (README, "Architecture") hold: the import-linter contracts in pyproject.toml are
kept, and they catch an import that breaks them; importing a pure layer, or parsing the
command line, loads no MuJoCo, graph, builder or simulation code (asserted on the
``sys.modules`` of a fresh interpreter, which sees what the contracts cannot: package
``__init__`` files that import more than their caller asked for).
"""

from __future__ import annotations

import importlib
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: Packages whose ``__init__`` exports its names lazily (harness._lazy).
LAZY_PACKAGES = ("harness.bus", "harness.diff", "harness.live", "harness.metrics",
                 "harness.recording", "harness.regression", "harness.serde", "harness.sim",
                 "harness.sut", "harness.video", "harness.wiring")
#: The pure layers and the run-level modules they stand on.
PURE = ("harness.scenario", "harness.metrics", "harness.regression", "harness.frames",
        "harness.report", "harness.report.html", "harness.report.data", "harness.scoring",
        "harness.camera_topics", "harness.tf_tree", "harness.diskspace")
#: What none of them may load.
HEAVY = ("mujoco", "harness.engine", "harness.graph", "harness.builders", "harness.sim.world")


def _lint_imports(cwd: Path) -> subprocess.CompletedProcess[str]:
    exe = shutil.which("lint-imports", path=str(Path(sys.executable).parent)) \
        or shutil.which("lint-imports")
    assert exe is not None, "lint-imports not found: install the dev extra (import-linter)"
    env = {**os.environ, "PYTHONPATH": str(cwd)}
    return subprocess.run([exe, "--no-cache", "--no-logo"], cwd=cwd, env=env, text=True,
                          capture_output=True, timeout=120, check=False)


def _modules_after(code: str) -> dict[str, object]:
    """Run ``code`` in a fresh interpreter; returns what it printed as JSON."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, text=True,
                          capture_output=True, timeout=120, check=False)
    assert proc.returncode == 0, proc.stderr
    result: dict[str, object] = json.loads(proc.stdout.strip().splitlines()[-1])
    return result


def test_the_layer_contracts_are_kept() -> None:
    proc = _lint_imports(ROOT)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "2 kept, 0 broken" in proc.stdout


def test_the_contracts_catch_an_import_that_breaks_a_layer(tmp_path: Path) -> None:
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    shutil.copytree(ROOT / "harness", tmp_path / "harness",
                    ignore=shutil.ignore_patterns("__pycache__"))
    types = tmp_path / "harness" / "metrics" / "types.py"
    types.write_text(types.read_text(encoding="utf-8") + "\nimport harness.engine  # noqa\n",
                     encoding="utf-8")
    proc = _lint_imports(tmp_path)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "harness.metrics is not allowed to import harness.engine" in proc.stdout
    assert "2 broken" in proc.stdout


@pytest.mark.slow
def test_pure_layers_load_no_simulation_code_even_when_used() -> None:
    # Every name the pure packages export is looked up, so a lazy export that drags in
    # a heavy module is caught too, not only the bare import.
    code = (
        "import importlib, json, sys\n"
        f"for name in {PURE!r}:\n"
        "    mod = importlib.import_module(name)\n"
        "    for attr in getattr(mod, '__all__', ()):\n"
        "        getattr(mod, attr)\n"
        f"print(json.dumps({{'loaded': sorted(m for m in {HEAVY!r} if m in sys.modules)}}))\n"
    )
    assert _modules_after(code) == {"loaded": []}


def test_import_harness_metrics_loads_nothing_it_does_not_need() -> None:
    code = ("import json, sys\nimport harness.metrics\n"
            "print(json.dumps({'mujoco': 'mujoco' in sys.modules, 'harness': sorted("
            "m for m in sys.modules if m.startswith('harness'))}))\n")
    found = _modules_after(code)
    assert found["mujoco"] is False
    assert found["harness"] == ["harness", "harness._lazy", "harness.metrics"]


@pytest.mark.parametrize("argv", [["--help"], ["run", "--help"], ["--version"]])
def test_the_command_line_parses_without_loading_the_api(argv: list[str]) -> None:
    code = (
        "import contextlib, io, json, sys\nfrom harness.cli import main\n"
        "out = io.StringIO()\n"
        "with contextlib.redirect_stdout(out):\n"
        "    try:\n"
        f"        main({argv!r})\n"
        "    except SystemExit as exit:\n"
        "        code = exit.code\n"
        "print(json.dumps({'code': code, 'text': out.getvalue(), 'loaded': sorted(m for m in "
        "('mujoco', 'numpy', 'pandas', 'rich', 'harness.api', 'harness.bus.bus', "
        "'harness.scenario') if m in sys.modules)}))\n"
    )
    found = _modules_after(code)
    assert found["code"] == 0
    assert "srr" in str(found["text"])
    assert found["loaded"] == []


#: What a run needs only once it has been recorded (scoring, the report, reading a bag back),
#: or only some commands need (``srr diff``, ``recover``, ``replay``, ``export``): the suite's
#: process and a run's start-up import none of it (issue 26).
LATER = ("pandas", "scipy.spatial", "scipy.optimize", "jinja2", "mcap.reader",
         "harness.recording.bagread", "harness.frames", "harness.metrics.perception",
         "harness.diff", "harness.diff.metrics", "harness.report.html")


@pytest.mark.slow
@pytest.mark.parametrize("module", ["harness.suite.runner", "harness.run.simulate"])
def test_starting_a_run_or_a_suite_loads_nothing_it_needs_only_later(module: str) -> None:
    code = (f"import json, sys\nimport {module}\n"
            f"print(json.dumps({{'loaded': sorted(m for m in {LATER!r} if m in sys.modules), "
            "'mujoco': 'mujoco' in sys.modules}))\n")
    found = _modules_after(code)
    assert found["mujoco"] is True  # what the run needs before its loop is imported
    assert found["loaded"] == []


@pytest.mark.slow
@pytest.mark.parametrize("modules", [
    ("harness.api",),
    # what `srr diff`, `srr report`, `srr recover` and `srr export` import through the API
    ("harness.api", "harness.diff.core", "harness.run.rerender", "harness.run.recover",
     "harness.export.rerun"),
])
def test_commands_that_read_a_run_back_load_no_simulation_code(modules: tuple[str, ...]) -> None:
    # importing the scene builders, graphs and MuJoCo took ~1 s of every `srr diff` before
    code = (f"import importlib, json, sys\nfor m in {modules!r}: importlib.import_module(m)\n"
            f"print(json.dumps(sorted(m for m in {HEAVY!r} if m in sys.modules)))\n")
    assert _modules_after(code) == []


def test_the_ros1_message_store_is_made_only_when_something_uses_it() -> None:
    # 0.1-0.2 s of every srr command before: most runs write and read no ROS 1
    code = ("import json, sys\nimport harness.api, harness.cli\n"
            "from harness.serde.ros1 import msgdef, ros1_typestore\n"
            "before = ros1_typestore.cache_info().currsize\n"
            "msgdef('geometry_msgs/msg/Twist')\n"
            "print(json.dumps({'before': before, "
            "'after': ros1_typestore.cache_info().currsize}))\n")
    assert _modules_after(code) == {"before": 0, "after": 1}


@pytest.mark.slow
def test_a_suite_imports_what_its_runs_need_at_their_end_before_it_forks() -> None:
    # srr suite calls it before forking its hosts, which then share these modules
    code = ("import json, sys\nfrom harness import api\napi.import_after_the_loop()\n"
            f"print(json.dumps({{'missing': sorted(m for m in {LATER!r} "
            "if m not in sys.modules)}))\n")
    assert _modules_after(code) == {"missing": ["harness.diff", "harness.diff.metrics"]}


@pytest.mark.parametrize("package", (*LAZY_PACKAGES, "harness.api"))
def test_lazy_exports_are_the_submodules_objects(package: str) -> None:
    mod = importlib.import_module(package)
    names = list(mod.__all__)
    assert set(names) <= set(dir(mod))
    for name in names:
        value = getattr(mod, name)
        where = mod._WHERE.get(name)
        if where is not None:
            home = where if where.startswith("harness.") else f"{package}.{where}"
            assert value is getattr(importlib.import_module(home), name), name
    with pytest.raises(AttributeError, match="no attribute 'no_such_name'"):
        _ = mod.no_such_name


def test_an_export_named_like_its_submodule_is_the_export() -> None:
    compare_module = importlib.import_module("harness.regression.compare")
    from harness.regression import compare

    assert callable(compare) and compare is compare_module.compare
