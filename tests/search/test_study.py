"""The study: seeded batches that do not depend on whether the search was resumed between
them, killed trials marked and not counted, other settings refused, a damaged study.db
refused in one line (real optuna, real SQLite; no simulation)."""

from __future__ import annotations

from pathlib import Path

import pytest

from harness.errors import SrrError
from harness.search.objective import parse_objective
from harness.search.space import parse_space
from harness.search.study import ask_batch, finished_trials, open_study

SPACE = parse_space(["a.x=0..1", "a.n=1..9:1", "a.c=[p, q, r]"])
OBJ = parse_objective("safety.over_mute", below=None, above=1.0)
CONFIG = {"space": "x", "seed": 7}


def _value(params: dict[str, object]) -> float:
    return float(params["a.x"]) * float(params["a.n"])  # type: ignore[arg-type]


def _run(db: Path, batches: int, *, reopen: bool, sampler: str) -> list[dict[str, object]]:
    study = open_study(db, OBJ, CONFIG)
    for _ in range(batches):
        if reopen:  # a new process resuming the study between batches
            study = open_study(db, OBJ, CONFIG)
        for t in ask_batch(study, SPACE, sampler, 7, 2):
            study.tell(t, _value(t.params))
    return [t.params for t in study.get_trials()]


@pytest.mark.slow  # 5-10 s each on a loaded 2-core box (SQLite writes)
@pytest.mark.parametrize("sampler", ["tpe", "random", "qmc", "cmaes"])
def test_same_seed_same_trials_resumed_or_not(tmp_path: Path, sampler: str) -> None:
    """Past the samplers' random start-up trials (TPE 6, CMA-ES 4)."""
    straight = _run(tmp_path / "a.db", 5, reopen=False, sampler=sampler)
    resumed = _run(tmp_path / "b.db", 5, reopen=True, sampler=sampler)
    assert len(straight) == 10 and straight == resumed
    assert len({repr(sorted(p.items())) for p in straight}) > 5  # it does sample


@pytest.mark.slow
def test_a_trial_left_running_is_marked_killed(tmp_path: Path) -> None:
    db = tmp_path / "s.db"
    study = open_study(db, OBJ, CONFIG)
    [done, left] = ask_batch(study, SPACE, "random", 7, 2)
    study.tell(done, 0.5)
    del left  # the process dies here: the trial stays RUNNING in the database
    again = open_study(db, OBJ, CONFIG)
    trials = again.get_trials()
    assert [t.state.name for t in trials] == ["COMPLETE", "FAIL"]
    assert trials[1].user_attrs["srr"] == {"status": "killed"}
    assert [t.number for t in finished_trials(again)] == [0]  # killed trials do not count
    [nxt] = ask_batch(again, SPACE, "random", 7, 1)
    assert nxt.number == 2  # numbers are not reused


@pytest.mark.slow
def test_other_settings_are_refused(tmp_path: Path) -> None:
    db = tmp_path / "s.db"
    open_study(db, OBJ, CONFIG)
    with pytest.raises(SrrError, match=r"holds a search with other settings \(seed differs\)"):
        open_study(db, OBJ, {**CONFIG, "seed": 8})


def test_a_damaged_study_is_refused_in_one_line(tmp_path: Path) -> None:
    db = tmp_path / "study.db"
    db.write_bytes(b"this is not SQLite" * 100)
    with pytest.raises(SrrError) as err:
        open_study(db, OBJ, CONFIG)
    assert "study.db is not a readable search study" in str(err.value)
    assert "\n" not in str(err.value)
