"""CI runs exactly the test command the README gives a newcomer, so the two cannot drift apart.

The README's command is the fenced ``bash`` block under the set-up heading that runs pytest;
``.ci/run``'s last command line (after its system packages) must be that command, word for word
once whitespace is normalised.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
CI_RUN = ROOT / ".ci" / "run"


def _squash(text: str) -> str:
    return " ".join(text.split())


def readme_test_command(markdown: str) -> str:
    """The one command of the fenced bash block, in the set-up section, that runs pytest."""
    section = re.search(r"^## Set-up\b.*?(?=^## )", markdown, re.MULTILINE | re.DOTALL)
    assert section is not None, "README.md: no '## Set-up' section"
    blocks = re.findall(r"^```bash\n(.*?)^```", section.group(0), re.MULTILINE | re.DOTALL)
    commands = [_squash(b) for b in blocks if "pytest" in b]
    assert len(commands) == 1, (
        f"README.md: expected one ```bash block running pytest in the set-up section, "
        f"found {len(commands)}")
    return commands[0]


def ci_last_command(script: str) -> str:
    """The last command of a shell script: its last non-comment line, continuations joined."""
    lines = script.replace("\\\n", " ").splitlines()
    commands = [line for line in lines if line.strip() and not line.lstrip().startswith("#")]
    assert commands, ".ci/run: no command"
    return _squash(commands[-1])


def test_ci_runs_exactly_the_readme_test_command() -> None:
    readme = readme_test_command(README.read_text(encoding="utf-8"))
    ci = ci_last_command(CI_RUN.read_text(encoding="utf-8"))
    assert ci == readme, (
        f".ci/run's last command differs from README.md's test command:\n"
        f"  .ci/run:   {ci}\n  README.md: {readme}")


def test_the_comparison_can_fail() -> None:
    readme = "## Set-up: x\n\n```bash\npython -m  pytest -q\n```\n\n## Next\n"
    assert readme_test_command(readme) == "python -m pytest -q"
    assert ci_last_command("#!/bin/sh\nset -e\npython -m pytest \\\n  -q\n# done\n") == (
        "python -m pytest -q")
    assert ci_last_command("python -m pytest -q -m 'not slow'\n") != readme_test_command(readme)
