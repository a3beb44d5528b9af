"""JUnit XML for CI systems: one test case per health check (and, later, per metric)."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from harness.atomic import write_text_atomic

__all__ = ["Case", "junit_cases", "write_junit", "xml_document"]

#: What XML 1.0 cannot hold, even escaped: control characters other than tab and newlines
#: (an ANSI colour code in a plug-in's exception message), lone surrogates, U+FFFE/U+FFFF.
_NOT_XML = re.compile("[^\t\n\r\x20-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")


def xml_document(root: ET.Element) -> str:
    """``root`` as a whole XML document that every parser reads: a character XML cannot hold
    (in a reason, a name) is written as its ``\\xNN`` escape."""
    ET.indent(root)
    text = _NOT_XML.sub(lambda m: f"\\x{ord(m.group()):02x}" if ord(m.group()) < 0x100
                        else f"\\u{ord(m.group()):04x}", ET.tostring(root, encoding="unicode"))
    return '<?xml version="1.0" encoding="utf-8"?>\n' + text + "\n"


@dataclass(frozen=True)
class Case:
    name: str
    ok: bool
    detail: str
    skipped: bool = False  # not decided (an interrupted search): neither passed nor failed


def junit_cases(summary: Mapping[str, Any]) -> list[Case]:
    """One case per health gate and per compared metric (or per metric, without baseline)."""
    cases = [Case(f"health.{h['name']}", h["ok"], h["detail"]) for h in summary["health"]]
    if summary.get("comparison"):
        for e in summary["comparison"]:
            ok = e["status"] not in ("regressed", "missing")
            cases.append(Case(e["name"], ok, f"{e['status'].replace('_', ' ')}: value "
                              f"{e['value']} baseline {e['baseline']} tolerance "
                              f"{e['tolerance']}"))
    else:
        for m in summary.get("metrics", []):
            cases.append(Case(m["name"], True, f"{m['value']} {m['unit']} (no baseline)"))
    if summary.get("verdict") in ("FAIL", "UNSCORED", "MISMATCH"):
        cases.append(Case("verdict", False, "; ".join(summary.get("reasons", []))))
    if summary.get("verdict") == "RECORDED":  # passes, and says that nothing was judged
        cases.append(Case("verdict", True, "RECORDED: " + "; ".join(summary.get("reasons", []))))
    return cases


def write_junit(path: Path, suite: str, cases: Sequence[Case]) -> None:
    skipped = sum(c.skipped for c in cases)
    failures = sum(not c.ok and not c.skipped for c in cases)
    root = ET.Element("testsuites", name="srr", tests=str(len(cases)), failures=str(failures))
    ts = ET.SubElement(root, "testsuite", name=suite, tests=str(len(cases)),
                       failures=str(failures), errors="0", skipped=str(skipped))
    for c in cases:
        tc = ET.SubElement(ts, "testcase", classname=f"srr.{suite}", name=c.name)
        if c.skipped:
            ET.SubElement(tc, "skipped", message=c.detail).text = c.detail
        elif not c.ok:
            ET.SubElement(tc, "failure", message=c.detail).text = c.detail
        else:
            ET.SubElement(tc, "system-out").text = c.detail
    write_text_atomic(path, xml_document(root))
