"""The documentation site (docs/) builds without a warning, its scenarios are valid and every
``srr`` command it shows exists.

* The whole site is built with Sphinx's ``-W`` (warnings are errors) into a temporary folder.
* Every fenced ``yaml`` block of ``docs/**/*.md`` that is a whole scenario (it has
  ``format_version``) is written to a file and checked by ``srr validate``, beside the
  ``python`` blocks of its page that start with ``# file: NAME.py`` (the plug-ins it
  names). A block whose first line is ``# docs: not validated`` is skipped (a deliberately
  wrong example).
* Every other ``yaml`` block (a fragment: a few top-level blocks of a scenario) is checked by
  ``srr validate`` too, put on top of a bundled scenario (``dock_nominal.yaml``; a fragment
  with its own ``include`` gets only ``format_version`` and ``name``). A fragment that is a
  suite file is checked as ``srr suite`` checks one before its first run.
* Every ``srr`` command line shown in the docs and in README.md — in ``bash`` blocks and in
  inline code — names a command of the parser, and each of its ``--options`` is one that
  command takes.
"""

from __future__ import annotations

import argparse
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from harness.cli import _parser, main

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
SKIP_MARK = "# docs: not validated"


def _pages() -> list[Path]:
    return sorted(p for p in DOCS.rglob("*.md")
                  if "_build" not in p.parts and "_generated" not in p.parts)


def _blocks(text: str, lang: str) -> list[str]:
    return re.findall(rf"^```{lang}[^\n]*\n(.*?)^```", text, re.MULTILINE | re.DOTALL)


def scenario_blocks() -> list[tuple[str, str, dict[str, str]]]:
    """(page:index, text, the page's files) of every yaml block that is a whole scenario;
    the files are the page's python blocks headed ``# file: NAME.py``, by name."""
    found = []
    for page in _pages():
        text = page.read_text(encoding="utf-8")
        files = {m.group(1): block for block in _blocks(text, "python")
                 if (m := re.match(r"# file: (\w+\.py)\n", block))}
        for i, block in enumerate(_blocks(text, "yaml")):
            if re.search(r"^format_version:", block, re.MULTILINE) and not block.startswith(
                    SKIP_MARK):
                found.append((f"{page.relative_to(ROOT)}:{i}", block, files))
    return found


# -- the srr commands the docs show ------------------------------------------------------

def _subcommands(p: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in p._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def _options(p: argparse.ArgumentParser) -> set[str]:
    return {s for a in p._actions for s in a.option_strings}


def check_command(words: list[str], parser: argparse.ArgumentParser) -> str | None:
    """Why ``srr WORDS...`` is not a command the parser takes (None when it is). Only the
    command names and the ``--options`` are checked; values and placeholders are not."""
    p, name = parser, "srr"
    while True:
        subs = _subcommands(p)
        if not subs:
            break
        if not words or words[0].startswith("-"):
            if words and words[0] in ("-h", "--help"):
                return None
            return f"{name}: needs one of {sorted(subs)}"
        if words[0] not in subs:
            return f"{name}: no command {words[0]!r} (commands: {sorted(subs)})"
        p, name, words = subs[words[0]], f"{name} {words[0]}", words[1:]
    known = _options(p)
    for w in words:
        if w.startswith("--") and len(w) > 2:
            opt = w.split("=", 1)[0]
            if opt not in known:
                return f"{name}: no option {opt}"
    return None


_SRR = re.compile(r"(?:^|[\s(`;&|])(?:\S*/)?srr\s+([a-z][^\n`#|&;)]*)")


def command_lines(text: str) -> list[str]:
    """The ``srr ...`` invocations in bash blocks and inline code of a Markdown page."""
    found: list[str] = []
    for block in _blocks(text, "bash"):
        for line in block.replace("\\\n", " ").splitlines():
            found += [m.group(1) for m in _SRR.finditer(line)]
    prose = re.sub(r"^```.*?^```", "", text, flags=re.MULTILINE | re.DOTALL)
    for code in re.findall(r"`([^`\n]+)`", prose):
        found += [m.group(1) for m in _SRR.finditer(code)]
    # "srr run: FILE: FIELD: ..." is an error message srr prints, not a command
    return [c.strip() for c in found if not c.split(" ", 1)[0].endswith(":")]


def _words(command: str) -> list[str]:
    try:
        return shlex.split(command)
    except ValueError:  # an unbalanced quote inside an elided example
        return command.split()


def _shown_commands() -> list[tuple[str, str]]:
    pages = [*_pages(), ROOT / "README.md"]
    return [(str(p.relative_to(ROOT)), c) for p in pages
            for c in command_lines(p.read_text(encoding="utf-8"))]


def test_every_srr_command_shown_exists() -> None:
    parser = _parser()
    shown = _shown_commands()
    assert len(shown) > 30, "the docs show srr commands; none found: is the pattern broken?"
    bad = [f"{page}: `srr {cmd}`: {why}" for page, cmd in shown
           if (why := check_command(_words(cmd), parser))]
    assert not bad, "\n".join(bad)


def test_the_command_check_can_fail() -> None:
    parser = _parser()
    assert check_command(["run", "x.yaml", "--seed", "3", "--rtsp"], parser) is None
    assert check_command(["baseline", "bless", "R", "--reason", "x"], parser) is None
    assert "no command 'frobnicate'" in (check_command(["frobnicate"], parser) or "")
    assert "no option --colour" in (check_command(["run", "x.yaml", "--colour"], parser) or "")
    assert "needs one of" in (check_command(["baseline"], parser) or "")
    text = "see `srr inspect BAG` and\n```bash\n.venv/bin/srr suite a.yaml --jobs 2\n```\n"
    assert command_lines(text) == ["suite a.yaml --jobs 2", "inspect BAG"]
    assert command_lines("`srr run: x.yaml: duration: must be > 0`") == []


# -- every whole scenario in the docs is valid -------------------------------------------

def test_the_docs_show_whole_scenarios() -> None:
    names = [name for name, _, _ in scenario_blocks()]
    assert any("first-scenario" in n for n in names), names


@pytest.mark.slow
@pytest.mark.parametrize(("where", "text", "files"), scenario_blocks(),
                         ids=lambda v: str(v)[:40] if isinstance(v, str) else "")
def test_scenario_in_docs_validates(where: str, text: str, files: dict[str, str],
                                    tmp_path: Path,
                                    monkeypatch: pytest.MonkeyPatch,
                                    capsys: pytest.CaptureFixture[str]) -> None:
    # beside copies of the bundled scenarios, so a snippet's includes resolve as they would
    # in scenarios/
    shutil.copytree(ROOT / "scenarios", tmp_path / "scenarios")
    path = tmp_path / "scenarios" / "docs_snippet.yaml"
    path.write_text(text, encoding="utf-8")
    for name, source in files.items():  # plug-ins import from the working directory
        (tmp_path / name).write_text(source, encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    code = main(["validate", str(path)])
    out = capsys.readouterr()
    assert code == 0, f"{where}: srr validate exited {code}: {out.err.strip()}"


def test_the_plugin_pages_refusal_is_what_its_command_prints(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """The page on systems under test quotes what its ``srr validate ... --set`` command
    prints; run it on the page's own creep.py and creep.yaml. (It quoted the scenario file
    where srr names the ``--set`` flag that gave the value.)"""
    text = (DOCS / "howto" / "systems-under-test.md").read_text(encoding="utf-8")
    files = {m.group(1): block for block in _blocks(text, "python")
             if (m := re.match(r"# file: (\w+\.py)\n", block))}
    (scenario,) = [b for b in _blocks(text, "yaml") if re.search(r"^name: creep$", b, re.M)]
    (tmp_path / "creep.yaml").write_text(scenario, encoding="utf-8")
    (tmp_path / "creep.py").write_text(files["creep.py"], encoding="utf-8")
    found = re.search(r"`(srr validate creep\.yaml [^`]*)` prints\s+`(srr validate: [^`]*)`",
                      text)
    assert found, "the page no longer quotes a refused parameter"
    command, quoted = found.group(1), " ".join(found.group(2).split())
    monkeypatch.chdir(tmp_path)
    assert main(shlex.split(command)[1:]) == 2
    assert " ".join(capsys.readouterr().err.split()) == quoted


def fragment_blocks() -> list[tuple[str, str]]:
    """(page:index, text) of every yaml block that is not a whole scenario nor skipped."""
    found = []
    for page in _pages():
        for i, block in enumerate(_blocks(page.read_text(encoding="utf-8"), "yaml")):
            if not re.search(r"^format_version:", block, re.MULTILINE) and not block.startswith(
                    SKIP_MARK):
                found.append((f"{page.relative_to(ROOT)}:{i}", block))
    return found


@pytest.mark.slow
@pytest.mark.parametrize(("where", "text"), fragment_blocks(), ids=lambda v: str(v)[:40])
def test_fragment_in_docs_validates(where: str, text: str, tmp_path: Path,
                                    monkeypatch: pytest.MonkeyPatch,
                                    capsys: pytest.CaptureFixture[str]) -> None:
    import yaml

    from harness.suite.spec import load_suite

    shutil.copytree(ROOT / "scenarios", tmp_path / "scenarios")
    monkeypatch.chdir(tmp_path)
    fragment = yaml.safe_load(text)
    assert isinstance(fragment, dict), f"{where}: a yaml block that is no mapping"
    if "suite" in fragment or "scenarios" in fragment:
        path = tmp_path / "scenarios" / "suites" / "docs_suite.yaml"
        path.write_text(text, encoding="utf-8")
        assert load_suite([path]).entries, where
        return
    base: dict[str, object] = {"format_version": 1, "name": "docs_fragment"}
    if "include" not in fragment:
        base = yaml.safe_load((ROOT / "scenarios" / "dock_nominal.yaml").read_text(
            encoding="utf-8"))
    path = tmp_path / "scenarios" / "docs_fragment.yaml"
    path.write_text(yaml.safe_dump({**base, **fragment}, sort_keys=False), encoding="utf-8")
    code = main(["validate", str(path)])
    out = capsys.readouterr()
    assert code == 0, f"{where}: srr validate exited {code}: {out.err.strip()}"


# -- the site builds without a warning ---------------------------------------------------

@pytest.mark.slow
def test_docs_build_without_warnings(tmp_path: Path) -> None:
    out = tmp_path / "html"
    proc = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
         "-d", str(tmp_path / "doctrees"), str(DOCS), str(out)],
        capture_output=True, text=True, cwd=ROOT, check=False)
    assert proc.returncode == 0, f"sphinx -W failed:\n{proc.stderr[-4000:]}"
    assert (out / "index.html").is_file()
    assert (out / "get-started" / "first-scenario.html").is_file()
    for page in out.rglob("*.html"):  # the generated pages too
        assert not unexplained(page.read_text(encoding="utf-8")), page
    cli = (out / "reference" / "cli.html").read_text(encoding="utf-8")
    for command in _subcommands(_parser()):
        assert command in cli, f"reference/cli.html does not document `srr {command}`"


# -- words a reader cannot look up ------------------------------------------------------

# The reference systems are named by what they are (docs/explanation/reference-graphs.md),
# not by the numbers of their files; no page cites a design note or an issue the reader
# does not have.
_UNEXPLAINED = re.compile(r"\bseeds? ?0\d\d\b|\bissue \d+|DESIGN\.md", re.IGNORECASE)


def unexplained(text: str) -> list[str]:
    return [m.group(0) for m in _UNEXPLAINED.finditer(text)]


def test_docs_name_no_seed_numbers_issues_or_design_notes() -> None:
    bad = {str(p.relative_to(ROOT)): found for p in [*_pages(), ROOT / "README.md"]
           if (found := unexplained(p.read_text(encoding="utf-8")))}
    assert not bad, bad
    assert unexplained("as in seed 001, see DESIGN.md (issue 13)") == [
        "seed 001", "DESIGN.md", "issue 13"]
    assert unexplained("`tests/e2e/seed000_graphs.py`, seed 7") == []


# -- counts the docs state, against what they count --------------------------------------

def test_nightly_suite_counts_match_the_suite_file() -> None:
    from harness.suite.plan import plan_runs
    from harness.suite.spec import load_suite

    text = (DOCS / "howto" / "nightly-suite.md").read_text(encoding="utf-8")
    m = re.search(r"the (\w+) scenarios that ship a baseline.*?= (\d+) runs", text, re.DOTALL)
    assert m is not None, "nightly-suite.md: no 'the N scenarios that ship a baseline ... = M runs'"
    words = {"seven": 7, "eight": 8, "nine": 9, "ten": 10, "eleven": 11, "twelve": 12}
    spec = load_suite([ROOT / "scenarios" / "suites" / "nightly.yaml"])
    runs = plan_runs(spec)
    plain = [e for e in spec.entries if not e.sweep]
    assert int(m.group(2)) == len(runs), (
        f"the docs say {m.group(2)} runs, the suite plans {len(runs)}")
    assert words.get(m.group(1)) == len(plain), (
        f"the docs say {m.group(1)} scenarios, the suite has {len(plain)} without a sweep")


def test_docs_workflow_builds_with_warnings_as_errors_and_publishes() -> None:
    import yaml

    wf = yaml.safe_load((ROOT / ".github" / "workflows" / "docs.yml").read_text(encoding="utf-8"))
    steps = [s for job in wf["jobs"].values() for s in job["steps"]]
    runs = "\n".join(s.get("run", "") for s in steps)
    uses = [s.get("uses", "") for s in steps]
    build = next(line for line in runs.splitlines() if "sphinx" in line)
    assert " -W " in f" {build} " and " docs " in f" {build} ", build
    assert ".[docs]" in runs
    for action in ("actions/upload-artifact@", "actions/upload-pages-artifact@",
                   "actions/deploy-pages@"):
        assert any(u.startswith(action) for u in uses), f"docs.yml: no {action} step"
