"""The search page from a search summary: structure (threshold, a dot per trial, the
best-so-far curve, importances, counterexamples linked to their reports), a summary missing
fields, and nothing that reaches the network."""

from __future__ import annotations

import re
from typing import Any

from harness.report.search_page import render_search_page


def _summary() -> dict[str, Any]:
    trials = [
        {"number": 0, "id": "t00000", "params": {"workers.0.speed": 1.0}, "status": "holds",
         "value": 0.4, "margin": 1.1, "verdict": "PASS", "report": "runs/t00000/report.html",
         "log": "logs/t00000.log", "reason": None},
        {"number": 1, "id": "t00001", "params": {"workers.0.speed": 2.4}, "status": "violated",
         "value": 3.2, "margin": -1.7, "verdict": "PASS", "report": "runs/t00001/report.html",
         "log": "logs/t00001.log", "reason": None},
        {"number": 2, "id": "t00002", "params": {"workers.0.speed": 0.7}, "status": "invalid",
         "value": None, "margin": None, "verdict": "INVALID", "report": None,
         "log": "logs/t00002.log", "reason": "the worker crashed: killed by signal SIGSEGV"},
    ]
    return {
        "format": "srr-search/1", "name": "crossing", "scenario": "crossing",
        "objective": {"metric": "safety.over_mute", "violated": "above", "threshold": 1.5},
        "space": [{"path": "workers.0.speed", "kind": "float", "range": "0.5..2.5"}],
        "sampler": "tpe", "seed": 0, "budget": 3, "executor": "local", "jobs": 2,
        "wall_s": 12.0, "verdict": "VIOLATED", "exit_code": 1, "first_violation": 1,
        "counts": {"trials": 3, "violated": 1, "valid": 2, "invalid": 1, "killed": 0},
        "best_so_far": [0.4, 3.2, 3.2], "importances": {"workers.0.speed": 1.0},
        "trials": trials,
        "counterexamples": [{"trial": 1, "id": "t00001", "name": "crossing_t00001",
                             "file": "counterexamples/crossing_t00001.yaml",
                             "params": {"workers.0.speed": 2.4}, "value": 3.2,
                             "report": "runs/t00001/report.html", "note": None}],
    }


def test_page_structure() -> None:
    page = render_search_page(_summary())
    assert 'data-verdict="FAIL"' in page and "VIOLATED" in page  # red banner, the word
    assert re.search(r'class="threshold"[^>]*data-value="1.5"', page)
    dots = re.findall(r'data-trial="(\d+)" data-status="(\w+)"', page)
    assert dots == [("0", "holds"), ("1", "violated"), ("2", "invalid")]
    assert page.count('class="best-so-far"') == 1
    assert '<tr data-param="workers.0.speed">' in page
    cex = page[page.index('id="counterexamples"'):page.index('id="trials"')]
    assert 'href="counterexamples/crossing_t00001.yaml"' in cex
    assert 'href="runs/t00001/report.html"' in cex and "workers.0.speed = 2.4" in cex
    assert "killed by signal SIGSEGV" in page
    assert '<span data-count="violated">1 violated</span>' in page
    assert 'data-count="killed"' not in page  # only when some were
    assert "<script" not in page and not re.search(r'(src|href)="(https?:)?//', page)


def test_a_search_that_holds() -> None:
    s = _summary()
    s.update(verdict="HOLDS", exit_code=0, counterexamples=[], first_violation=None)
    page = render_search_page(s)
    assert 'data-verdict="PASS"' in page and 'id="no-counterexample"' in page


def test_a_summary_missing_fields_still_renders() -> None:
    page = render_search_page({})
    assert "No trial has run yet." in page and 'data-verdict="INVALID"' in page
