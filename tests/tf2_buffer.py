"""Feed transforms to a real tf2 ``BufferCore`` and report what it made of them.

Run with the *system* Python that has Debian's ``python3-tf2`` (ROS 1's tf2_py binding of the
same C++ tf2 core ROS 2 uses); ``tests/tf2check.py`` does that. Reads JSON on stdin::

    {"transforms": [{"parent", "child", "t_ns", "static", "topic", "xyz", "xyzw"}, ...],
     "root": "world"}

and prints JSON: per frame its parent as tf2 holds it and whether ``root → frame`` looks up at
the latest time (with the translation), plus tf2's own errors from ``set_transform``. tf2's
warnings (TF_REPEATED_DATA, TF_SELF_TRANSFORM, ...) go to stderr, where the caller reads them.
"""

import json
import sys

import genpy
import tf2_py
import yaml
from geometry_msgs.msg import TransformStamped


def main() -> None:
    data = json.load(sys.stdin)
    root = data["root"]
    buf = tf2_py.BufferCore(genpy.Duration(3600))
    errors = []
    for t in data["transforms"]:
        msg = TransformStamped()
        msg.header.frame_id = t["parent"]
        msg.child_frame_id = t["child"]
        msg.header.stamp = genpy.Time(t["t_ns"] // 1_000_000_000, t["t_ns"] % 1_000_000_000)
        tr, q = msg.transform.translation, msg.transform.rotation
        tr.x, tr.y, tr.z = t["xyz"]
        q.x, q.y, q.z, q.w = t["xyzw"]
        try:
            if t["static"]:
                buf.set_transform_static(msg, t["topic"])
            else:
                buf.set_transform(msg, t["topic"])
        except Exception as err:  # tf2's exceptions are the finding, not a crash
            errors.append(f"{type(err).__name__}: {err}")
    frames = {}
    latest = genpy.Time(0, 0)
    held = yaml.safe_load(buf.all_frames_as_yaml()) or {}  # tf2's own frame → parent table
    for frame in sorted({t["child"] for t in data["transforms"]}):
        parent = held.get(frame, {}).get("parent", "<not in tf2>")
        try:
            got = buf.lookup_transform_core(root, frame, latest)
            v = got.transform.translation
            found, xyz, why = True, [v.x, v.y, v.z], ""
        except Exception as err:
            found, xyz, why = False, None, f"{type(err).__name__}: {err}"
        frames[frame] = {"parent": parent, "found": found, "xyz": xyz, "why": why}
    json.dump({"frames": frames, "errors": errors}, sys.stdout)


if __name__ == "__main__":
    main()
