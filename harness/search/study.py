"""The optuna study behind a search: samplers, SQLite storage, resuming.

The study lives in ``OUT/study.db`` (optuna's RDB storage on SQLite). Re-running the same
command resumes it: finished trials are kept and count towards the budget, a trial that was
running when the search was killed is marked failed (``killed``; its number is not reused and
it does not count), and new trials take the next numbers. The settings that define the search
(scenario, ``--set``, ``--space``, objective, sampler, seed) are stored with the study; a
command that differs in any of them is refused instead of mixing two searches.

Seeding: trials are asked in batches of ``--jobs``, and the sampler of each batch is made
afresh with a seed derived from ``--seed`` and the batch's first trial number (QMC keeps
``--seed``: its points are one scrambled Sobol sequence indexed by the trial count). So a batch's
parameters depend only on the seed, that number and the trials finished before it — the same
whether the search ran in one go or was killed and resumed between batches. A search
killed in the middle of a batch resumes with a new batch (its killed trials are not rerun with
the same parameters), so from there on its trials differ from an uninterrupted search's.
"""

from __future__ import annotations

import logging
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from harness.errors import SrrError
from harness.search.objective import Objective
from harness.search.space import Dimension

__all__ = ["ATTR", "SAMPLERS", "ask_batch", "finished_trials", "importances", "open_study",
           "status"]

#: ``--sampler`` names.
SAMPLERS = ("tpe", "random", "qmc", "cmaes")
STUDY_NAME = "srr-search"
#: The trial's user attribute that holds srr's record of it (one write per trial).
ATTR = "srr"


def _optuna() -> Any:
    try:
        import optuna
    except ImportError as err:
        raise SrrError("srr search: optuna is not installed (pip install 'srr[search]')") \
            from err
    optuna.logging.set_verbosity(logging.WARNING)
    return optuna


def make_sampler(name: str, seed: int) -> Any:
    optuna = _optuna()
    if name == "tpe":
        # multivariate: the parameters of a narrow failure region are found together
        return optuna.samplers.TPESampler(seed=seed, multivariate=True, n_startup_trials=6)
    if name == "random":
        return optuna.samplers.RandomSampler(seed=seed)
    if name == "qmc":
        with warnings.catch_warnings():  # "experimental" since optuna 3.0; srr pins behaviour
            warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
            return optuna.samplers.QMCSampler(seed=seed, qmc_type="sobol", scramble=True)
    if name == "cmaes":
        try:
            import cmaes  # noqa: F401
        except ImportError as err:
            raise SrrError("--sampler cmaes: needs the cmaes package (pip install "
                           "'srr[search]')") from err
        return optuna.samplers.CmaEsSampler(seed=seed, n_startup_trials=4)
    raise SrrError(f"--sampler {name}: expected one of {', '.join(SAMPLERS)}")


def distributions(space: Sequence[Dimension]) -> dict[str, Any]:
    d = _optuna().distributions
    out: dict[str, Any] = {}
    for dim in space:
        if dim.kind == "categorical":
            out[dim.path] = d.CategoricalDistribution(list(dim.choices))
        elif dim.kind == "int":
            step = int(dim.step or 1)
            high = int(dim.low) + (int(dim.high) - int(dim.low)) // step * step
            out[dim.path] = d.IntDistribution(int(dim.low), high, step=step)
        else:
            fstep = dim.step
            fhigh = dim.high if fstep is None else dim.low + int(
                (dim.high - dim.low) / fstep + 1e-9) * fstep
            out[dim.path] = d.FloatDistribution(dim.low, fhigh, log=dim.log, step=fstep)
    return out


def _connector(db: Path) -> Any:
    """SQLite connections in WAL mode with ``synchronous=NORMAL``: a commit is not an fsync
    (a trial's ask and tell cost 0.07 s instead of 0.2–0.3 s on a loaded 2-core box), and a
    killed process still loses nothing committed (only an OS crash could lose the last
    commits)."""
    import sqlite3

    def connect() -> sqlite3.Connection:
        con = sqlite3.connect(db, timeout=60, check_same_thread=False)
        con.execute("pragma journal_mode=WAL")
        con.execute("pragma synchronous=NORMAL")
        return con

    return connect


def status(trial: Any) -> str | None:
    """What srr recorded of a trial's outcome (None: nothing yet)."""
    rec = trial.user_attrs.get(ATTR)
    return str(rec.get("status")) if isinstance(rec, dict) and rec.get("status") else None


def open_study(db: Path, objective: Objective, config: Mapping[str, Any]) -> Any:
    """Create or resume the study in ``db``; refuse one made with other settings. Trials a
    killed search left running are marked failed (``status: killed``)."""
    optuna = _optuna()
    from sqlalchemy.exc import SQLAlchemyError

    try:
        storage = optuna.storages.RDBStorage(
            f"sqlite:///{db.resolve()}", engine_kwargs={"creator": _connector(db.resolve())})
        study = optuna.create_study(storage=storage, study_name=STUDY_NAME,
                                    direction=objective.direction, load_if_exists=True)
    except (SQLAlchemyError, RuntimeError) as err:
        first = (str(err).strip().splitlines() or [type(err).__name__])[0]
        raise SrrError(f"--out {db.parent}: {db.name} is not a readable search study "
                       f"({first[:200]}); move it away to start afresh") from None
    if study.direction.name.lower() != objective.direction:
        raise SrrError(f"--out {db.parent}: holds a search that {study.direction.name.lower()}s "
                       f"its objective; give another --out or the same command")
    stored = study.user_attrs.get("config")
    if stored is None:
        study.set_user_attr("config", dict(config))
    elif stored != dict(config):
        diff = sorted(k for k in set(stored) | set(config) if stored.get(k) != config.get(k))
        raise SrrError(f"--out {db.parent}: holds a search with other settings "
                       f"({', '.join(diff)} {'differs' if len(diff) == 1 else 'differ'}); give "
                       "another --out or the same command")
    running = optuna.trial.TrialState.RUNNING
    for t in study.get_trials(deepcopy=False, states=(running,)):
        study._storage.set_trial_user_attr(t._trial_id, ATTR, {"status": "killed"})
        study.tell(t.number, state=optuna.trial.TrialState.FAIL)
    return study


def finished_trials(study: Any) -> list[Any]:
    """Trials that ran to an outcome (complete, or failed as invalid), in number order."""
    states = _optuna().trial.TrialState
    return [t for t in study.get_trials(deepcopy=False, states=(states.COMPLETE, states.FAIL))
            if status(t) != "killed"]


def ask_batch(study: Any, space: Sequence[Dimension], sampler: str, seed: int,
              n: int) -> list[Any]:
    """``n`` new trials, from a sampler seeded by ``seed`` and the first new trial number."""
    first = len(study.get_trials(deepcopy=False))
    # QMC keeps its seed: one scrambled Sobol sequence, indexed by the study's trial count,
    # so the batches together stay a low-discrepancy set (resuming continues the sequence)
    study.sampler = make_sampler(sampler, seed if sampler == "qmc" else
                                 (seed * 1_000_003 + first) % 2**32)
    dists = distributions(space)
    return [study.ask(dists) for _ in range(n)]


def importances(study: Any, seed: int) -> dict[str, float]:
    """Each parameter's importance for the objective (optuna's PED-ANOVA over the complete
    trials: NumPy and SciPy only, where fANOVA needs scikit-learn); empty when there are too
    few trials to say."""
    optuna = _optuna()
    complete = study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))
    if len(complete) < 4 or len({t.value for t in complete}) < 2:
        return {}
    del seed  # PED-ANOVA is deterministic
    try:
        ev = optuna.importance.PedAnovaImportanceEvaluator()
        return {str(k): float(v) for k, v in
                optuna.importance.get_param_importances(study, evaluator=ev).items()}
    except (RuntimeError, ValueError, ImportError, ZeroDivisionError):
        return {}
