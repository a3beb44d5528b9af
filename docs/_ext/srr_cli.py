"""The ``srr`` argument parser for sphinx-argparse, which reads help texts as reStructuredText:
the same parser (``harness.cli._parser``) with the characters reStructuredText would take as
markup (``*``, ``|``, backquotes) escaped, so ``/gt/*`` shows as written."""

from __future__ import annotations

import argparse
import re

from harness.cli import _parser

_MARKUP = re.compile(r"([\\*|`])")


def _escape(text: str | None) -> str | None:
    return None if text is None else _MARKUP.sub(r"\\\1", text)


def _walk(p: argparse.ArgumentParser) -> None:
    p.description = _escape(p.description)
    p.epilog = _escape(p.epilog)
    for action in p._actions:
        if action.help not in (None, argparse.SUPPRESS):
            action.help = _escape(action.help)
        if isinstance(action, argparse._SubParsersAction):
            for choice in action._choices_actions:
                choice.help = _escape(choice.help)
            for sub in action.choices.values():
                _walk(sub)


def parser() -> argparse.ArgumentParser:
    p = _parser()
    _walk(p)
    return p
