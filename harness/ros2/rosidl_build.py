"""Generate and compile a ROS 2 interface package with the rosidl tools of the ``ros-jazzy-*``
wheels, without colcon, ament_cmake or CMake.

This is what ``rosidl_generate_interfaces()`` does for a package, step for step, with the same
generator arguments (read off the wheels' own ``*_generate_interfaces.cmake``), restricted to
what rclpy needs:

1. ``rosidl_adapter``: ``.msg``/``.srv``/``.action`` → ``.idl``;
2. ``rosidl_generator_type_description``: the type descriptions and RIHS01 hashes (``.json``);
3. the generators ``rosidl_generator_c``, ``rosidl_typesupport_introspection_c``,
   ``rosidl_typesupport_fastrtps_c`` (the code Fast DDS serializes with, so the wire type is
   ``<pkg>::msg::dds_::<Name>_``), ``rosidl_typesupport_c`` (the dispatch between the two) and
   ``rosidl_generator_py``;
4. a C and a C++ compiler build the five libraries and the Python extension modules.

The C++ type supports (``rosidl_typesupport_cpp`` and friends) are not built: only C++ nodes
(rclcpp) use them, and the wheels have no rclcpp.

The result is an install prefix laid out like the wheels' (``lib/``, ``share/<pkg>``, the ament
index) plus ``python/<pkg>``, which needs no environment variable: the libraries find each
other and the wheels' libraries through their RUNPATH (``$ORIGIN`` and the wheels' ``lib/``).
The ``rosidl_typesupport_c`` dispatch ``dlopen()`` s ``lib<pkg>__rosidl_typesupport_fastrtps_c.so``
by bare name, which the loader would look for only on the ``LD_LIBRARY_PATH`` the process
started with; ``lib<pkg>__rosidl_typesupport_c.so`` therefore links both C type supports, so
they are loaded with it and the bare name matches their SONAME.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import shutil
import subprocess
import sys
import sysconfig
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

from harness.ros2.errors import Ros2SetupError

__all__ = [
    "GENERATORS",
    "InterfacePackage",
    "Toolchain",
    "build_interface_package",
    "find_toolchain",
    "interface_dependencies",
]

# The Python packages (from the ros-jazzy-* wheels) whose generators run, in order.
GENERATORS = (
    "rosidl_adapter",
    "rosidl_generator_type_description",
    "rosidl_generator_c",
    "rosidl_typesupport_introspection_c",
    "rosidl_typesupport_fastrtps_c",
    "rosidl_typesupport_c",
    "rosidl_generator_py",
)

# C type supports rclpy can dispatch to, as registered by the wheels in the ament index.
_C_TYPESUPPORTS = ("rosidl_typesupport_fastrtps_c", "rosidl_typesupport_introspection_c")

_KINDS = ("msg", "srv", "action")


@dataclass(frozen=True)
class InterfacePackage:
    """A ROS interface package's sources: ``source/package.xml`` and ``source/<kind>/*``."""

    name: str
    source: Path
    files: tuple[str, ...]  # relative to source, e.g. "msg/TFMessage.msg"
    dependencies: tuple[str, ...]  # the DEPENDENCIES of rosidl_generate_interfaces()


@dataclass(frozen=True)
class Toolchain:
    """What a build needs besides the wheels: compilers and the headers of this Python."""

    cc: str
    cxx: str
    python_include: Path
    numpy_include: Path
    ext_suffix: str


def find_toolchain() -> Toolchain:
    """The compilers (``$CC``/``$CXX``, else ``cc``/``c++``) and the Python and NumPy headers,
    or :class:`Ros2SetupError` saying in one line what to install."""
    missing = []
    cc = shutil.which(os.environ.get("CC", "cc"))
    cxx = shutil.which(os.environ.get("CXX", "c++"))
    if cc is None or cxx is None:
        missing.append("a C and C++ compiler (apt-get install build-essential)")
    python_include = Path(sysconfig.get_paths()["include"])
    if not (python_include / "Python.h").is_file():
        version = f"{sys.version_info.major}.{sys.version_info.minor}"
        missing.append(f"the Python {version} headers, {python_include}/Python.h "
                       f"(apt-get install python3-dev, or libpython{version}-dev)")
    try:
        import numpy
    except ImportError:
        numpy_include = Path()
        missing.append("numpy (pip install numpy)")
    else:
        numpy_include = Path(numpy.get_include())
    ext_suffix = sysconfig.get_config_var("EXT_SUFFIX")
    if missing:
        raise Ros2SetupError("missing " + "; ".join(missing))
    assert cc is not None and cxx is not None and isinstance(ext_suffix, str)
    return Toolchain(cc, cxx, python_include, numpy_include, ext_suffix)


def _package_xml_dependencies(path: Path) -> list[str]:
    root = ET.parse(path).getroot()
    tags = ("depend", "build_depend", "build_export_depend", "exec_depend")
    return [e.text.strip() for tag in tags for e in root.findall(tag) if e.text]


def _idl_files(ros_prefix: Path, pkg: str) -> list[Path]:
    share = ros_prefix / "share" / pkg
    return sorted(p for kind in _KINDS for p in (share / kind).glob("*.idl"))


def interface_dependencies(package: InterfacePackage, ros_prefix: Path) -> list[str]:
    """The interface packages ``package`` depends on, directly or not, as
    ``rosidl_generate_interfaces()`` collects them (services add ``service_msgs``, actions
    ``action_msgs`` too)."""
    kinds = {f.split("/")[0] for f in package.files}
    direct = list(package.dependencies)
    if kinds & {"srv", "action"}:
        direct.append("service_msgs")
    if "action" in kinds:
        direct.append("action_msgs")
    found: list[str] = []
    todo = list(direct)
    while todo:
        pkg = todo.pop(0)
        if pkg in found or pkg == package.name:
            continue
        xml = ros_prefix / "share" / pkg / "package.xml"
        if not xml.is_file():
            if pkg in direct:
                raise Ros2SetupError(f"{package.name} needs the interface package {pkg}, which "
                                     f"is not installed under {ros_prefix}")
            continue
        if _idl_files(ros_prefix, pkg):
            found.append(pkg)
        todo += _package_xml_dependencies(xml)
    return found


def _write_json(path: Path, data: dict[str, object]) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")
    return path


def _visibility_header(template: Path, out: Path, pkg: str) -> None:
    text = template.read_text(encoding="utf-8")
    text = text.replace("@PROJECT_NAME@", pkg).replace("@PROJECT_NAME_UPPER@", pkg.upper())
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text, encoding="utf-8")


def _generate(package: InterfacePackage, ros_prefix: Path, work: Path,
              deps: list[str]) -> list[tuple[str, str]]:
    """Runs the generators into ``work``; returns the IDL tuples (base, relative path)."""
    import rosidl_adapter
    import rosidl_generator_c
    import rosidl_generator_py
    import rosidl_generator_type_description
    import rosidl_typesupport_c
    import rosidl_typesupport_fastrtps_c
    import rosidl_typesupport_introspection_c

    pkg = package.name
    share = ros_prefix / "share"
    adapter_out = work / "rosidl_adapter" / pkg
    idl_tuples: list[tuple[str, str]] = []
    for rel in package.files:
        idl = rosidl_adapter.convert_to_idl(package.source, pkg, Path(rel), adapter_out)
        idl_tuples.append((str(adapter_out), str(Path(idl).relative_to(adapter_out))))
    tuples = [f"{base}:{rel}" for base, rel in idl_tuples]
    dependencies = [f"{d}:{p}" for d in deps for p in _idl_files(ros_prefix, d)]

    description_out = work / "rosidl_generator_type_description" / pkg
    rosidl_generator_type_description.generate_type_hash(str(_write_json(
        work / "rosidl_generator_type_description__arguments.json", {
            "package_name": pkg, "idl_tuples": tuples, "output_dir": str(description_out),
            "include_paths": [f"{d}:{share / d}" for d in deps]})))
    description_tuples = [
        f"{rel}:{description_out / Path(rel).parent / (Path(rel).stem + '.json')}"
        for _, rel in idl_tuples]

    def arguments(generator: str, **extra: object) -> str:
        return str(_write_json(work / f"{generator}__arguments.json", {
            "package_name": pkg, "idl_tuples": tuples,
            "ros_interface_dependencies": dependencies,
            "output_dir": str(work / generator / pkg),
            "template_dir": str(share / generator / "resource"),
            "target_dependencies": [], **extra}))

    rosidl_generator_c.generate_c(arguments(
        "rosidl_generator_c", type_description_tuples=description_tuples,
        ros_interface_files=[str(package.source / f) for f in package.files]))
    rosidl_typesupport_introspection_c.generate_c(
        arguments("rosidl_typesupport_introspection_c"))
    rosidl_typesupport_fastrtps_c.generate_typesupport_fastrtps_c(
        arguments("rosidl_typesupport_fastrtps_c"))
    rosidl_typesupport_c.generate_c(arguments("rosidl_typesupport_c"), list(_C_TYPESUPPORTS))
    py_out = work / "rosidl_generator_py" / pkg
    py_out.mkdir(parents=True, exist_ok=True)
    (py_out / "__init__.py").write_text("", encoding="utf-8")
    rosidl_generator_py.generate_py(arguments("rosidl_generator_py"),
                                    ["rosidl_typesupport_c", *_C_TYPESUPPORTS])
    for generator in ("rosidl_generator_c", "rosidl_typesupport_introspection_c",
                      "rosidl_typesupport_fastrtps_c"):
        _visibility_header(share / generator / "resource" / f"{generator}__visibility_control.h.in",
                           work / generator / pkg / "msg" / f"{generator}__visibility_control.h",
                           pkg)
    return idl_tuples


@dataclass
class _Compiler:
    toolchain: Toolchain
    ros_prefix: Path
    work: Path
    jobs: int
    log: list[str]

    def run(self, cmd: Sequence[str]) -> None:
        self.log.append(" ".join(cmd))
        proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
        if proc.stdout or proc.stderr:
            self.log.append(proc.stdout + proc.stderr)
        if proc.returncode != 0:
            lines = (proc.stdout + proc.stderr).strip().splitlines() or ["(no output)"]
            first = next((line for line in lines if "error" in line), lines[-1])
            raise Ros2SetupError(f"compiling failed: {Path(cmd[0]).name} exited "
                                 f"{proc.returncode}: {first.strip()}")

    def objects(self, sources: list[Path], includes: list[Path], cxx: bool,
                defines: Sequence[str] = ()) -> list[Path]:
        """Compiles ``sources`` in parallel; returns the object files."""
        compiler = self.toolchain.cxx if cxx else self.toolchain.cc
        std = "-std=c++17" if cxx else "-std=c11"
        # the wheels install most headers to include/<pkg>/<pkg>/..., Fast CDR to include/
        ros_include = self.ros_prefix / "include"
        include_flags = [f"-I{p}" for p in includes]
        include_flags += [f"-I{p}" for p in sorted(ros_include.iterdir()) if p.is_dir()]
        include_flags.append(f"-I{ros_include}")
        outs = [self.work / "obj" / (str(s.relative_to(self.work)).replace("/", "__") + ".o")
                for s in sources]
        (self.work / "obj").mkdir(exist_ok=True)
        cmds = [[compiler, std, "-O2", "-fPIC", "-w", *(f"-D{d}" for d in defines),
                 *include_flags, "-c", str(s), "-o", str(o)] for s, o in zip(sources, outs,
                                                                              strict=True)]
        with ThreadPoolExecutor(max_workers=self.jobs) as pool:
            list(pool.map(self.run, cmds))
        return outs

    def link(self, out: Path, objects: list[Path], libs: Sequence[str], own_libs: Path,
             cxx: bool) -> None:
        out.parent.mkdir(parents=True, exist_ok=True)
        origin = os.path.relpath(own_libs, out.parent)
        rpath = "$ORIGIN" if origin == "." else f"$ORIGIN/{origin}"
        ros_lib = self.ros_prefix / "lib"
        self.run([self.toolchain.cxx if cxx else self.toolchain.cc, "-shared", "-o", str(out),
                  *map(str, objects), f"-Wl,-soname,{out.name}", "-Wl,--enable-new-dtags",
                  "-Wl,--no-as-needed", f"-Wl,-rpath,{rpath}:{ros_lib}", f"-L{own_libs}",
                  f"-L{ros_lib}", *(f"-l{lib}" for lib in libs)])


def _sources(root: Path, pattern: str) -> list[Path]:
    return sorted(root.glob(pattern))


def build_interface_package(package: InterfacePackage, ros_prefix: Path, prefix: Path,
                            work: Path, toolchain: Toolchain, log: list[str],
                            jobs: int = 0) -> None:
    """Generates and compiles ``package`` against the ROS install at ``ros_prefix`` (a venv
    with the wheels) into the install prefix ``prefix``, using ``work`` as the build
    directory, appending what it runs and what that prints to ``log``.

    Raises :class:`Ros2SetupError` when a generator or the compiler fails."""
    pkg = package.name
    deps = interface_dependencies(package, ros_prefix)
    log.append(f"dependencies: {' '.join(deps)}")
    printed = io.StringIO()  # the generators print every file they read and write
    try:
        with contextlib.redirect_stdout(printed):
            idl_tuples = _generate(package, ros_prefix, work, deps)
    except Ros2SetupError:
        raise
    except Exception as err:  # the generators raise anything: name it in one line
        raise Ros2SetupError(f"generating {pkg} failed: {type(err).__name__}: {err}") from err
    finally:
        log.append(printed.getvalue())
    comp = _Compiler(toolchain, ros_prefix, work, jobs or os.cpu_count() or 1, log)
    lib = prefix / "lib"
    gen_c, gen_py = work / "rosidl_generator_c", work / "rosidl_generator_py"
    intro_c = work / "rosidl_typesupport_introspection_c"
    fast_c, ts_c = work / "rosidl_typesupport_fastrtps_c", work / "rosidl_typesupport_c"

    def per_dep(suffix: str) -> list[str]:
        return [f"{d}__{suffix}" for d in deps
                if (ros_prefix / "lib" / f"lib{d}__{suffix}.so").is_file()]

    runtime = ["rosidl_runtime_c", "rcutils"]
    generator_c = f"{pkg}__rosidl_generator_c"
    comp.link(lib / f"lib{generator_c}.so",
              comp.objects(_sources(gen_c / pkg, "*/detail/*.c"), [gen_c], cxx=False,
                           defines=[f"ROSIDL_GENERATOR_C_BUILDING_DLL_{pkg}"]),
              [*per_dep("rosidl_generator_c"), *runtime], lib, cxx=False)
    comp.link(lib / f"lib{pkg}__rosidl_typesupport_introspection_c.so",
              comp.objects(_sources(intro_c / pkg, "*/detail/*.c"), [intro_c, gen_c], cxx=False,
                           defines=[f"ROSIDL_TYPESUPPORT_INTROSPECTION_C_BUILDING_DLL_{pkg}"]),
              [generator_c, *per_dep("rosidl_typesupport_introspection_c"),
               "rosidl_typesupport_introspection_c", *runtime], lib, cxx=False)
    comp.link(lib / f"lib{pkg}__rosidl_typesupport_fastrtps_c.so",
              comp.objects(_sources(fast_c / pkg, "*/detail/*.cpp"), [fast_c, gen_c], cxx=True,
                           defines=[f"ROSIDL_TYPESUPPORT_FASTRTPS_C_BUILDING_DLL_{pkg}"]),
              [generator_c, *per_dep("rosidl_typesupport_fastrtps_c"),
               "rosidl_typesupport_fastrtps_c", "rosidl_typesupport_fastrtps_cpp", "fastcdr",
               "rmw", "rosidl_dynamic_typesupport", *runtime], lib, cxx=True)
    typesupport_c = f"{pkg}__rosidl_typesupport_c"
    comp.link(lib / f"lib{typesupport_c}.so",
              comp.objects(_sources(ts_c / pkg, "*/*.cpp"), [gen_c], cxx=True,
                           defines=[f"ROSIDL_GENERATOR_C_BUILDING_DLL_{pkg}"]),
              [generator_c, *(f"{pkg}__{t}" for t in _C_TYPESUPPORTS),
               *per_dep("rosidl_typesupport_c"), "rosidl_typesupport_c", *runtime],
              lib, cxx=True)
    py_includes = [gen_c, gen_py, toolchain.python_include, toolchain.numpy_include]
    generator_py = f"{pkg}__rosidl_generator_py"
    comp.link(lib / f"lib{generator_py}.so",
              comp.objects(_sources(gen_py / pkg, "*/_*_s.c"), py_includes, cxx=False),
              [generator_c, typesupport_c, *per_dep("rosidl_generator_py"),
               *per_dep("rosidl_typesupport_c"), *per_dep("rosidl_generator_c"), *runtime],
              lib, cxx=False)
    py_pkg = prefix / "python" / pkg
    for typesupport in ("rosidl_typesupport_c", *_C_TYPESUPPORTS):
        (ext_source,) = _sources(gen_py / pkg, f"_{pkg}_s.ep.{typesupport}.c")
        extras = [] if typesupport == "rosidl_typesupport_c" else [f"{pkg}__{typesupport}"]
        comp.link(py_pkg / f"{pkg}_s__{typesupport}{toolchain.ext_suffix}",
                  comp.objects([ext_source], py_includes, cxx=False),
                  [generator_py, *extras, typesupport_c, generator_c, "rosidl_typesupport_c",
                   "rmw", "rosidl_dynamic_typesupport", *runtime], lib, cxx=False)
    _install(package, prefix, work, idl_tuples)


def _install(package: InterfacePackage, prefix: Path, work: Path,
             idl_tuples: list[tuple[str, str]]) -> None:
    """The Python package, the interface files, type descriptions and the ament index
    entries, where ``rosidl_generate_interfaces()`` would install them."""
    pkg = package.name
    py_out, py_pkg = work / "rosidl_generator_py" / pkg, prefix / "python" / pkg
    for path in sorted(py_out.rglob("*.py")):
        dest = py_pkg / path.relative_to(py_out)
        dest.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(path, dest)
    share = prefix / "share" / pkg
    share.mkdir(parents=True, exist_ok=True)
    shutil.copy2(package.source / "package.xml", share / "package.xml")
    description_out = work / "rosidl_generator_type_description" / pkg
    for base, rel in idl_tuples:
        (share / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(Path(base) / rel, share / rel)
        stem = Path(rel).with_suffix("")
        shutil.copy2(description_out / f"{stem}.json", share / f"{stem}.json")
    for rel in package.files:
        shutil.copy2(package.source / rel, share / rel)
    index = prefix / "share" / "ament_index" / "resource_index"
    lines = sorted([rel for _, rel in idl_tuples] + list(package.files))
    for resource, content in (("packages", ""), ("rosidl_interfaces", "\n".join(lines)),
                              ("package_run_dependencies",
                               ";".join([*package.dependencies, "rosidl_default_runtime"]))):
        (index / resource).mkdir(parents=True, exist_ok=True)
        (index / resource / pkg).write_text(content, encoding="utf-8")

