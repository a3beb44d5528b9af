"""The page templates (``harness/report/templates/``): shipped with the package, loaded by
name, one stylesheet whose verdict colours are :data:`VERDICT_COLORS`, escaping on."""

from __future__ import annotations

import re
import tomllib
from fnmatch import fnmatchcase
from pathlib import Path

from markupsafe import Markup

import harness
from harness.report.templates import VERDICT_COLORS, environment, template

HARNESS = Path(harness.__file__).parent
PROJECT = HARNESS.parent
TEMPLATES = HARNESS / "report" / "templates"


def _package_data() -> list[str]:
    with (PROJECT / "pyproject.toml").open("rb") as f:
        cfg = tomllib.load(f)
    return list(cfg["tool"]["setuptools"]["package-data"]["harness"])


def test_every_template_file_is_package_data() -> None:
    """An installed wheel has what the loader reads: each file of the folder is matched by
    a package-data pattern of pyproject.toml."""
    globs = _package_data()
    files = [p for p in TEMPLATES.iterdir() if p.is_file() and p.suffix != ".py"]
    assert {p.suffix for p in files} == {".html", ".css", ".js"}
    for p in files:
        rel = p.relative_to(HARNESS).as_posix()
        assert any(fnmatchcase(rel, g) for g in globs), f"{rel} is not package data"


def test_the_loader_lists_every_page_and_nothing_else() -> None:
    names = {n for n in environment().list_templates() if n.endswith((".html", ".css", ".js"))}
    on_disk = {p.name for p in TEMPLATES.iterdir() if p.suffix in (".html", ".css", ".js")}
    assert names == on_disk
    assert {"page.html", "macros.html", "report.html", "diff.html", "suite.html"} <= names


def test_stylesheet_verdict_colours_are_the_plots_colours() -> None:
    css = template("page.css").render()
    root = css[:css.index("}")]
    found = dict(re.findall(r"--([A-Z]+):(#[0-9a-f]{6})", root))
    assert found == VERDICT_COLORS


def test_values_are_escaped_and_markup_is_not() -> None:
    notices = environment().get_template("macros.html").module.notices  # type: ignore[attr-defined]
    out = str(notices(["<b>x</b> & y", Markup("<i>ok</i>")], "problem"))
    assert out == ('<div class="problem">&lt;b&gt;x&lt;/b&gt; &amp; y</div>'
                   '<div class="problem"><i>ok</i></div>')
