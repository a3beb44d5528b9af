"""JUnit XML for CI systems: one test case per health check (and, later, per metric)."""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path
from typing import Protocol

__all__ = ["write_junit"]


class _Case(Protocol):
    name: str
    ok: bool
    detail: str


def write_junit(path: Path, suite: str, cases: Sequence[_Case]) -> None:
    failures = sum(not c.ok for c in cases)
    root = ET.Element("testsuites", name="srr", tests=str(len(cases)), failures=str(failures))
    ts = ET.SubElement(root, "testsuite", name=suite, tests=str(len(cases)),
                       failures=str(failures), errors="0", skipped="0")
    for c in cases:
        tc = ET.SubElement(ts, "testcase", classname=f"srr.{suite}", name=c.name)
        if not c.ok:
            ET.SubElement(tc, "failure", message=c.detail).text = c.detail
        else:
            ET.SubElement(tc, "system-out").text = c.detail
    tmp = path.with_suffix(".xml.tmp")
    ET.ElementTree(root).write(tmp, encoding="utf-8", xml_declaration=True)
    os.replace(tmp, path)
