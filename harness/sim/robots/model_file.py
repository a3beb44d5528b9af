"""Read a robot's model file (URDF or MJCF) into a MuJoCo spec ready to attach to the world.

:func:`read_model_file` is the reading part alone (parsing, asset paths, assets in memory),
shared with world files (:mod:`harness.sim.world_file`); :func:`load_model_file` adds the
robot's checks.

MuJoCo parses both formats itself (``mujoco.MjSpec.from_string`` / ``from_file``); this
module prepares what it reads and checks that the result stands on its own:

* URDF: ``package://`` and relative mesh URIs (relative to the URDF file's directory, not
  the scenario file's) are resolved (:mod:`.paths`) and written back as absolute paths, and
  the ``<mujoco><compiler>`` extension is set so that visual geoms are kept (MuJoCo drops
  them from URDF by default), links joined by fixed joints stay separate bodies (each link
  keeps its name, for TF and sensor mounts) and paths are not stripped.
  URDF joint types are read from the XML too, since a fixed joint leaves no MuJoCo joint.
* xacro: expanded to URDF by the ``xacro`` package (:mod:`.xacro_file`), then read as a URDF
  whose relative paths start from the ``.xacro`` file's directory.
* MJCF: read with its includes; mesh, texture and height-field files are resolved against the
  file's ``meshdir``/``texturedir``.
* Every asset file is read once into memory and named by its content hash, so the world's
  spec compiles from memory (several robots from one file, or files from several
  directories, never clash) and the meshes are those MuJoCo loads: STL (binary, at most
  200000 faces: a bigger one is refused naming the file, where MuJoCo would suggest it is
  ASCII), OBJ, MSH.
* The model is compiled alone once: a file MuJoCo refuses is reported against the model file,
  before the world is built. Its robot must be one tree under a single top-level body.

Errors are :class:`ModelFileError` with a one-line message; the caller names the scenario
field.
"""

from __future__ import annotations

import hashlib
import math
import re
import types
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import mujoco

from harness.sim.robots.common import ActuatorMode
from harness.sim.robots.paths import ModelPathError, PackagePath, resolve_uri
from harness.sim.robots.xacro_file import (
    UnknownXacroArg,
    XacroError,
    XacroInputs,
    expand_xacro,
)
from harness.validation import close_match

__all__ = ["JointInfo", "LoadedModel", "ModelFileError", "ModelKind", "ParsedModel",
           "file_digest",
           "included_files", "load_model_file", "one_line", "read_model_file"]

#: The formats a model file can be written in.
ModelKind = Literal["urdf", "mjcf", "xacro"]
_URDF_COMPILER = {"discardvisual": "false", "fusestatic": "false", "strippath": "false"}
_JOINT_KINDS = {
    mujoco.mjtJoint.mjJNT_HINGE: "hinge",
    mujoco.mjtJoint.mjJNT_SLIDE: "slide",
    mujoco.mjtJoint.mjJNT_BALL: "ball",
    mujoco.mjtJoint.mjJNT_FREE: "free",
}


class ModelFileError(Exception):
    """A model file that cannot be used; the message is one line. ``field``: the field of
    the model block it is about, where that is not the file's (``args.wheel_radus``)."""

    def __init__(self, message: str, field: str = "") -> None:
        self.field = field
        super().__init__(message)


@dataclass(frozen=True)
class JointInfo:
    """A joint of the model: MuJoCo ``kind`` (``hinge``, ``slide``, ``ball``, ``free``, or
    ``none`` for a URDF joint MuJoCo has no joint for, e.g. ``fixed``), whether it is limited,
    and how the file calls it (URDF type, or the MuJoCo kind)."""

    name: str
    kind: str
    limited: bool
    described: str

    @property
    def spins(self) -> bool:
        """An unlimited hinge: a joint a wheel can turn on for ever."""
        return self.kind == "hinge" and not self.limited


@dataclass(frozen=True)
class LoadedModel:
    """A parsed, checked model file. ``spec`` is fresh (not attached anywhere); ``assets`` are
    the files it needs, by the names ``spec`` uses. ``links``: body names, model order, the
    root first. ``actuators``: joint → (actuator name, servo mode or None for another kind)
    for the actuators the file puts on single joints. ``joint_inertia``: each 1-dof joint's
    inertia at the reference pose (kg·m²). ``kind`` is the format MuJoCo read (a xacro
    file's is ``urdf``); ``xacro``: what a xacro file's expansion read. ``warnings``: what
    is odd about the model without making it unusable (one line each)."""

    path: Path
    kind: Literal["urdf", "mjcf"]
    spec: mujoco.MjSpec
    assets: Mapping[str, bytes]
    root: str
    links: tuple[str, ...]
    link_parents: Mapping[str, str]
    joints: Mapping[str, JointInfo]
    actuators: Mapping[str, tuple[str, ActuatorMode | None]]
    mass: float
    joint_inertia: Mapping[str, float]
    xacro: XacroInputs | None = None
    warnings: tuple[str, ...] = ()


def one_line(err: BaseException) -> str:
    """MuJoCo's (often multi-line) error message on one line, at most 300 characters."""
    text = "; ".join(line.strip() for line in str(err).splitlines() if line.strip())
    text = text.removeprefix("Error: ")
    return text if len(text) <= 300 else text[:297] + "..."


@dataclass(frozen=True)
class _PreparedUrdf:
    """A URDF as MuJoCo is to read it: ``text``; ``joint_types``: its joints' URDF types by
    joint name; ``massless``: the links with collision geometry whose ``<inertial>`` gives
    them a mass of 0 kg."""

    text: str
    joint_types: dict[str, str]
    massless: tuple[str, ...]


def _read_urdf(path: Path, packages: PackagePath, text: str | None = None) -> _PreparedUrdf:
    """The URDF prepared for MuJoCo. ``text``: the URDF (a xacro file's expansion) when it
    is not ``path``'s content."""
    try:
        root = ET.fromstring(path.read_bytes() if text is None else text)
    except ET.ParseError as err:
        raise ModelFileError(f"not well-formed XML: {err}") from err
    except OSError as err:
        raise ModelFileError(f"cannot read: {err}") from err
    if root.tag != "robot":
        raise ModelFileError(f"not a URDF file (its root element is <{root.tag}>, "
                             "expected <robot>)")
    types_ = {j.get("name", ""): j.get("type", "") for j in root.iter("joint")
              if j.get("name") and j.get("type")}
    _check_joint_links(root)
    massless = _check_inertials(root)
    for mesh in root.iter("mesh"):
        uri = mesh.get("filename")
        if not uri:
            raise ModelFileError("a <mesh> element has no filename")
        try:
            file = resolve_uri(uri, path.parent, packages)
        except ModelPathError as err:
            raise ModelFileError(f"mesh {err}") from err
        if not file.is_file():
            raise ModelFileError(f"mesh {uri!r}: file not found ({file})")
        mesh.set("filename", str(file.resolve()))
    ext = root.find("mujoco")
    if ext is None:
        ext = ET.SubElement(root, "mujoco")
    compiler = ext.find("compiler")
    if compiler is None:
        compiler = ET.SubElement(ext, "compiler")
    for key, value in _URDF_COMPILER.items():
        compiler.set(key, value)
    return _PreparedUrdf(ET.tostring(root, encoding="unicode"), types_, massless)


def _check_joint_links(root: ET.Element) -> None:
    """Every joint of the URDF joins two links it has: MuJoCo says only "URDF joint parent or
    child missing" and a line number. Link and joint names are unique, a link is the child of
    one joint at most and the joints form no cycle, as urdfdom requires: MuJoCo says
    "repeated URDF name:", "URDF body has multiple parents:" and "URDF body not found"
    without a name, and keeps a repeated joint name on the first joint only, leaving the
    other nameless. MuJoCo reads a link named ``world`` as the world body: a root ``world``
    link is left out (its child becomes the root), but a joint's child ``world`` would be
    dropped with its geometry without a word."""
    for kind in ("link", "joint"):
        seen: set[str] = set()
        for item in root.findall(kind):
            name = item.get("name", "")
            if name in seen:
                raise ModelFileError(f"two <{kind}> elements are named {name!r}: a URDF's "
                                     f"{kind} names must be unique")
            seen.add(name)
    links = {link.get("name", "") for link in root.findall("link")}
    joint_of: dict[str, str] = {}  # child link → its joint
    parent_of: dict[str, str] = {}  # child link → parent link
    for joint in root.findall("joint"):  # not a <transmission>'s joints
        name = joint.get("name", "")
        ends: list[str] = []
        for end in ("parent", "child"):
            element = joint.find(end)
            link = element.get("link") if element is not None else None
            if not link:
                raise ModelFileError(f"joint {name!r} has no <{end} link=\"...\"/>")
            if link not in links:
                close = close_match(link, links)
                hint = f" (did you mean {close!r}?)" if close else ""
                raise ModelFileError(f"joint {name!r}: {end} link {link!r} does not exist"
                                     f"{hint}")
            ends.append(link)
        parent, child = ends
        if child in joint_of:
            raise ModelFileError(f"link {child!r} is the child of two joints, "
                                 f"{joint_of[child]!r} and {name!r}: a link has one parent")
        if child == "world":
            raise ModelFileError(f"joint {name!r}: child link 'world': MuJoCo reads a URDF "
                                 "link named 'world' as the world itself and drops it from "
                                 "the robot; rename the link")
        joint_of[child], parent_of[child] = name, parent
    for link in sorted(parent_of):
        chain = [link]
        while chain[-1] in parent_of:
            up = parent_of[chain[-1]]
            if up in chain:
                loop = chain[chain.index(up):][::-1]  # parent → child
                ring = [*loop, loop[0]]
                joints = ", ".join(repr(joint_of[x]) for x in ring[1:])
                raise ModelFileError(f"links {' → '.join(ring)} form a cycle (joints "
                                     f"{joints}): a URDF is a tree")
            chain.append(up)


def _inertial_value(link: str, what: str, raw: str) -> float:
    """``raw``, the value of a link's mass or inertia diagonal entry (``what``), as a number
    that can be one: finite, 0 or more."""
    try:
        value = float(raw)
    except ValueError:
        raise ModelFileError(f"link {link!r}: {what} {raw!r} is not a number") from None
    if not math.isfinite(value):
        raise ModelFileError(f"link {link!r}: {what} {raw!r} is not a finite number")
    if value < 0:
        hint = " (MuJoCo would make it 0 kg)" if what == "mass" else ""
        raise ModelFileError(f"link {link!r}: {what} {raw} is negative{hint}")
    return value


def _check_inertials(root: ET.Element) -> tuple[str, ...]:
    """Refuse a link's mass or inertia diagonal that is negative or not a finite number
    (MuJoCo makes a negative mass 0 kg without a word, and takes NaN and infinity); return
    the links with collision geometry whose mass is 0 kg."""
    massless: list[str] = []
    for link in root.findall("link"):
        name = link.get("name", "")
        inertial = link.find("inertial")
        if inertial is None:
            continue
        mass = inertial.find("mass")
        raw = mass.get("value") if mass is not None else None
        if raw is not None and _inertial_value(name, "mass", raw) == 0 \
                and link.find("collision") is not None:
            massless.append(name)
        inertia = inertial.find("inertia")
        for key in ("ixx", "iyy", "izz"):
            raw = inertia.get(key) if inertia is not None else None
            if raw is not None:
                _inertial_value(name, f"inertia {key}", raw)
    return tuple(massless)


def _parse(path: Path, kind: ModelKind, packages: PackagePath, args: Mapping[str, str],
           ) -> tuple[mujoco.MjSpec, _PreparedUrdf | None, XacroInputs | None]:
    if not path.exists():
        raise ModelFileError("file not found")
    if not path.is_file():
        raise ModelFileError("is not a file")
    urdf: _PreparedUrdf | None = None
    inputs: XacroInputs | None = None
    try:
        if kind == "xacro":
            try:
                expanded = expand_xacro(path, args, packages)
            except XacroError as err:
                field = f"args.{err.name}" if isinstance(err, UnknownXacroArg) else ""
                raise ModelFileError(str(err), field) from err
            inputs = expanded.inputs
            urdf = _read_urdf(path, packages, expanded.text)
            spec = mujoco.MjSpec.from_string(urdf.text)
        elif kind == "urdf":
            urdf = _read_urdf(path, packages)
            spec = mujoco.MjSpec.from_string(urdf.text)
        else:
            spec = mujoco.MjSpec.from_file(str(path))
    except ValueError as err:
        shown = "the URDF xacro made of it" if kind == "xacro" else f"it as {kind.upper()}"
        raise ModelFileError(f"MuJoCo cannot read {shown}: {one_line(err)}") from err
    return spec, urdf, inputs


#: The file each in-memory asset name was read from (names are content hashes), so that
#: MuJoCo's messages, which name the asset, can name the user's file instead.
_ASSET_FILES: dict[str, str] = {}
_ASSET_NAME = re.compile(r"srr-[0-9a-f]{20}\.\w+")


def _shown(file: Path, folder: Path) -> str:
    """``file`` as a message shows it: relative to the model file's folder when inside it
    (short, as the model names it), else whole."""
    try:
        return file.resolve().relative_to(folder.resolve()).as_posix()
    except ValueError:
        return str(file)


def _named(message: str) -> str:
    """``message`` with each in-memory asset name replaced by the file it was read from."""
    return _ASSET_NAME.sub(lambda m: _ASSET_FILES.get(m.group(0), m.group(0)), message)


#: The most faces MuJoCo reads from a binary STL file: its ``stl_decoder`` refuses more as
#: "perhaps this is an ASCII file?".
_STL_MAX_FACES = 200_000


def _stl_faces(data: bytes) -> int | None:
    """The number of faces a binary STL file's header gives, when the file's size agrees with
    it (an ASCII or a truncated file's does not: MuJoCo's own message fits those), else
    None."""
    if len(data) < 84:
        return None
    faces = int.from_bytes(data[80:84], "little")
    return faces if len(data) == 84 + 50 * faces else None


def _take_assets(spec: mujoco.MjSpec, path: Path, packages: PackagePath) -> dict[str, bytes]:
    """Read every asset file into memory and point the spec at it by content hash."""
    base = Path(spec.modelfiledir) if spec.modelfiledir else path.parent
    assets: dict[str, bytes] = {}
    groups = (("mesh", spec.meshes, spec.meshdir), ("texture", spec.textures, spec.texturedir),
              ("height field", spec.hfields, spec.meshdir))
    for what, items, subdir in groups:
        for item in items:
            if not item.file:
                continue
            try:
                file = resolve_uri(item.file, base / subdir if subdir else base, packages)
            except ModelPathError as err:
                raise ModelFileError(f"{what} {err}") from err
            try:
                data = file.read_bytes()
            except OSError:
                raise ModelFileError(f"{what} {item.file!r}: file not found ({file})") from None
            faces = _stl_faces(data) if file.suffix.lower() == ".stl" else None
            if faces is not None and faces > _STL_MAX_FACES:
                raise ModelFileError(
                    f"{what} {_shown(file, path.parent)!r} has {faces} faces, more than the "
                    f"{_STL_MAX_FACES} MuJoCo reads; decimate it (e.g. with Blender or "
                    "meshlab)")
            key = f"srr-{hashlib.sha256(data).hexdigest()[:20]}{file.suffix.lower()}"
            assets[key] = data
            _ASSET_FILES[key] = _shown(file, path.parent)
            item.file = key
    spec.meshdir = ""
    spec.texturedir = ""
    return assets


def _servo_mode(model: mujoco.MjModel, act: int) -> ActuatorMode | None:
    """POSITION for a position servo, VELOCITY for a velocity servo, None for anything else."""
    gain, bias = model.actuator_gainprm[act], model.actuator_biasprm[act]
    if (model.actuator_gaintype[act] != mujoco.mjtGain.mjGAIN_FIXED
            or model.actuator_biastype[act] != mujoco.mjtBias.mjBIAS_AFFINE or gain[0] <= 0):
        return None
    if bias[1] == -gain[0] and bias[0] == 0:
        return ActuatorMode.POSITION
    if bias[1] == 0 and bias[2] == -gain[0] and bias[0] == 0:
        return ActuatorMode.VELOCITY
    return None


def _describe(kind: str, limited: bool, urdf_type: str | None) -> str:
    if urdf_type:
        return urdf_type
    return f"{'limited' if limited else 'unlimited'} {kind}" if kind in ("hinge", "slide") \
        else kind


@dataclass(frozen=True)
class ParsedModel:
    """A model file as MuJoCo reads it, not yet checked: ``spec`` (fresh) names its asset
    files by the keys of ``assets`` (their bytes, in memory); ``urdf_types``: a URDF's joint
    types by joint name (empty for MJCF); ``xacro``: what a xacro file's expansion read
    (None for another kind); ``massless``: a URDF's links with collision geometry whose
    ``<inertial>`` gives them a mass of 0 kg."""

    path: Path
    kind: ModelKind
    spec: mujoco.MjSpec
    assets: Mapping[str, bytes]
    urdf_types: Mapping[str, str]
    xacro: XacroInputs | None = None
    massless: tuple[str, ...] = ()


def read_model_file(path: Path, kind: ModelKind, packages: PackagePath,
                    args: Mapping[str, str] | None = None) -> ParsedModel:
    """Parse ``path`` (a URDF prepared as the module says; a xacro file expanded with
    ``args`` first) and bring its asset files into memory; what the model is for (a robot,
    a world) is the caller's to check."""
    spec, urdf, inputs = _parse(path, kind, packages, args or {})
    assets = _take_assets(spec, path, packages)
    return ParsedModel(path, kind, spec, types.MappingProxyType(assets),
                       types.MappingProxyType(urdf.joint_types if urdf else {}), inputs,
                       urdf.massless if urdf else ())


def load_model_file(path: Path, kind: ModelKind, packages: PackagePath,
                    args: Mapping[str, str] | None = None) -> LoadedModel:
    """Parse ``path``, bring its asset files into memory and compile it alone to check it."""
    parsed = read_model_file(path, kind, packages, args)
    spec, urdf_types, assets = parsed.spec, parsed.urdf_types, dict(parsed.assets)
    for i, act in enumerate(spec.actuators):  # named, so the world can find them again
        if not act.name:
            act.name = f"srr_actuator_{i}"
    tops = list(spec.worldbody.bodies)
    if not tops:
        raise ModelFileError("has no bodies (links)")
    if len(tops) > 1:
        names = ", ".join(repr(b.name) for b in tops[:4])
        raise ModelFileError(f"has {len(tops)} top-level bodies ({names}): a robot must be one "
                             "tree under a single root link")
    spec.assets = assets
    try:
        model = spec.compile()
    except ValueError as err:
        raise ModelFileError(f"MuJoCo cannot build it: {_named(one_line(err))}") from err

    def name(objtype: mujoco.mjtObj, idx: int) -> str:
        return mujoco.mj_id2name(model, objtype, idx) or ""

    root_id = int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, tops[0].name))
    links = [name(mujoco.mjtObj.mjOBJ_BODY, b) for b in range(1, model.nbody)]
    unnamed = [i for i, n in enumerate(links) if not n]
    if unnamed:
        raise ModelFileError(f"body {unnamed[0] + 1} has no name: every link needs one")
    parents = {links[b - 1]: links[int(model.body_parentid[b]) - 1]
               for b in range(1, model.nbody) if b != root_id}
    joints: dict[str, JointInfo] = {}
    inertia: dict[str, float] = {}
    for j in range(model.njnt):
        jname = name(mujoco.mjtObj.mjOBJ_JOINT, j)
        if not jname:
            continue
        jkind = _JOINT_KINDS.get(mujoco.mjtJoint(int(model.jnt_type[j])), "other")
        limited = bool(model.jnt_limited[j])
        joints[jname] = JointInfo(jname, jkind, limited,
                                  _describe(jkind, limited, urdf_types.get(jname)))
        if jkind in ("hinge", "slide"):
            inertia[jname] = float(model.dof_M0[model.jnt_dofadr[j]])
    for jname, utype in urdf_types.items():
        if jname not in joints:
            joints[jname] = JointInfo(jname, "none", False, utype)
    actuators: dict[str, tuple[str, ActuatorMode | None]] = {}
    for a in range(model.nu):
        if model.actuator_trntype[a] != mujoco.mjtTrn.mjTRN_JOINT:
            continue
        jname = name(mujoco.mjtObj.mjOBJ_JOINT, int(model.actuator_trnid[a, 0]))
        aname = name(mujoco.mjtObj.mjOBJ_ACTUATOR, a)
        if jname and jname not in actuators:
            actuators[jname] = (aname, _servo_mode(model, a))
    mass = float(model.body_mass[1:].sum())
    # URDF allows a mass of 0 (a frame-only link); one that collides is a part of the robot
    # left weightless, which changes how it drives, pushes and is pushed: said, not refused.
    warnings = tuple(f"link {link!r} has collision geometry but a mass of 0 kg (its "
                     f"<inertial>), so the whole robot weighs {mass:.3g} kg; give the link "
                     "its mass" for link in parsed.massless)
    return LoadedModel(
        path=path, kind="mjcf" if kind == "mjcf" else "urdf", xacro=parsed.xacro, spec=spec,
        assets=types.MappingProxyType(assets),
        root=tops[0].name, links=tuple(links), link_parents=types.MappingProxyType(parents),
        joints=types.MappingProxyType(joints), actuators=types.MappingProxyType(actuators),
        mass=mass, joint_inertia=types.MappingProxyType(inertia), warnings=warnings)


def included_files(path: Path) -> list[tuple[str, Path]]:
    """Every file an MJCF file pulls in with ``<include file=...>``, recursively, in document
    order, each once: (the path as written, the file MuJoCo reads). MuJoCo looks for an
    included file in the main file's directory first, then in the including file's; an
    absolute path is taken as it is. A file that cannot be read or parsed is skipped (MuJoCo
    has already read the model, so it is none MuJoCo used)."""
    found: list[tuple[str, Path]] = []
    seen: set[Path] = set()

    def visit(file: Path) -> None:
        try:
            root = ET.fromstring(file.read_bytes())
        except (OSError, ET.ParseError):
            return
        for inc in root.iter("include"):
            name = inc.get("file")
            if not name:
                continue
            written = Path(name)
            candidates = [written] if written.is_absolute() else \
                [path.parent / written, file.parent / written]
            target = next((c for c in candidates if c.is_file()), None)
            if target is None or target.resolve() in seen:
                continue
            seen.add(target.resolve())
            found.append((name, target))
            visit(target)

    visit(path)
    return found


def file_digest(path: Path, assets: Mapping[str, bytes],
                xacro: XacroInputs | None = None) -> str:
    """SHA-256 over a model file's bytes, its assets' names (content hashes, see
    :func:`_take_assets`: every mesh, texture and height field, wherever it is named) and
    the bytes of every file it includes (:func:`included_files`): what changes when any file
    that shapes the model does. A file without includes has the digest it had before srr
    hashed includes. For a xacro file (``xacro``), its includes are the files xacro read
    (each by its bytes, in the order read, not by its path, which differs between
    machines), and the arguments it was given count too."""
    digest = hashlib.sha256(path.read_bytes())
    for key in sorted(assets):
        digest.update(key.encode())
    if xacro is not None:
        for file in xacro.files:
            digest.update(b"\0xacro input\0")
            digest.update(hashlib.sha256(file.read_bytes()).digest())
        for name, value in xacro.args:
            digest.update(f"\0xacro arg {name}={value}\0".encode())
        return digest.hexdigest()
    for name, file in included_files(path):
        digest.update(f"\0include {name}\0".encode())
        digest.update(hashlib.sha256(file.read_bytes()).digest())
    return digest.hexdigest()
