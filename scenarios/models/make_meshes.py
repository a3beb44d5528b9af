"""Write the test models' meshes (run from anywhere: ``python scenarios/models/make_meshes.py``).

The files are committed; this script says how they were made and makes them again, byte for
byte. MuJoCo reads binary STL (not ASCII) and Wavefront OBJ, so there is one of each:

* ``srr_diffbot/meshes/chassis.stl``: the diff-drive robot's shell, a box with bevelled front
  corners, 0.30 x 0.22 x 0.08 m, centred on its origin.
* ``srr_diffbot/meshes/wheel.obj``: a wheel, radius 0.05 m, width 0.03 m, axle along +Y.
* ``pallet_truck/meshes/mast.obj``: the pallet truck's mast, two uprights and a cross bar.
* ``shelf_world/meshes/bollard.obj``: a bollard in the test world, an octagonal prism with
  corners 0.2 m from its axis (the first on +X), 0.8 m high, its base at z = 0.
"""

from __future__ import annotations

import math
import struct
from pathlib import Path

HERE = Path(__file__).resolve().parent

Vec = tuple[float, float, float]


def _normal(a: Vec, b: Vec, c: Vec) -> Vec:
    u = (b[0] - a[0], b[1] - a[1], b[2] - a[2])
    v = (c[0] - a[0], c[1] - a[1], c[2] - a[2])
    n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
    length = math.sqrt(sum(x * x for x in n)) or 1.0
    return (n[0] / length, n[1] / length, n[2] / length)


def write_stl(path: Path, triangles: list[tuple[Vec, Vec, Vec]]) -> None:
    """Binary STL: 80-byte header, count, then normal + 3 vertices + attribute per facet."""
    out = bytearray(b"srr test mesh".ljust(80, b"\0"))
    out += struct.pack("<I", len(triangles))
    for a, b, c in triangles:
        out += struct.pack("<12fH", *_normal(a, b, c), *a, *b, *c, 0)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(bytes(out))


def write_obj(path: Path, vertices: list[Vec], faces: list[tuple[int, ...]]) -> None:
    lines = ["# srr test mesh"]
    lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in vertices]
    lines += ["f " + " ".join(str(i + 1) for i in face) for face in faces]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines) + "\n")


def prism(outline: list[tuple[float, float]], z0: float, z1: float
          ) -> tuple[list[Vec], list[tuple[int, ...]]]:
    """A convex outline (counter-clockwise, XY) extruded from z0 to z1: vertices and faces."""
    n = len(outline)
    verts = [(x, y, z0) for x, y in outline] + [(x, y, z1) for x, y in outline]
    faces: list[tuple[int, ...]] = [tuple(reversed(range(n))), tuple(range(n, 2 * n))]
    faces += [(i, (i + 1) % n, n + (i + 1) % n, n + i) for i in range(n)]
    return verts, faces


def triangles(verts: list[Vec], faces: list[tuple[int, ...]]) -> list[tuple[Vec, Vec, Vec]]:
    return [(verts[f[0]], verts[f[k]], verts[f[k + 1]]) for f in faces
            for k in range(1, len(f) - 1)]


def box_outline(hx: float, hy: float, bevel: float) -> list[tuple[float, float]]:
    return [(-hx, -hy), (hx - bevel, -hy), (hx, -hy + bevel), (hx, hy - bevel),
            (hx - bevel, hy), (-hx, hy)]


def main() -> None:
    verts, faces = prism(box_outline(0.15, 0.11, 0.04), -0.04, 0.04)
    write_stl(HERE / "srr_diffbot" / "meshes" / "chassis.stl", triangles(verts, faces))

    # Wheel: a 16-sided prism along Y (outline in XZ, extruded in Y).
    segs = 16
    ring = [(0.05 * math.cos(2 * math.pi * k / segs), 0.05 * math.sin(2 * math.pi * k / segs))
            for k in range(segs)]
    verts, faces = prism(ring, -0.015, 0.015)
    write_obj(HERE / "srr_diffbot" / "meshes" / "wheel.obj",
              [(x, z, y) for x, y, z in verts], [tuple(reversed(f)) for f in faces])

    mast_v: list[Vec] = []
    mast_f: list[tuple[int, ...]] = []
    for cx, cy, hx, hy, z0, z1 in ((0.0, -0.3, 0.04, 0.04, 0.0, 1.8),
                                   (0.0, 0.3, 0.04, 0.04, 0.0, 1.8),
                                   (0.0, 0.0, 0.04, 0.34, 1.7, 1.8)):
        v, f = prism([(cx - hx, cy - hy), (cx + hx, cy - hy), (cx + hx, cy + hy),
                      (cx - hx, cy + hy)], z0, z1)
        base = len(mast_v)
        mast_v += v
        mast_f += [tuple(base + i for i in face) for face in f]
    write_obj(HERE / "pallet_truck" / "meshes" / "mast.obj", mast_v, mast_f)

    octagon = [(0.2 * math.cos(math.pi * k / 4), 0.2 * math.sin(math.pi * k / 4))
               for k in range(8)]
    verts, faces = prism(octagon, 0.0, 0.8)
    write_obj(HERE / "shelf_world" / "meshes" / "bollard.obj", verts, faces)


if __name__ == "__main__":
    main()
