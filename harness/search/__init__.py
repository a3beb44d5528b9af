"""``srr search``: falsification. An optimizer (optuna) picks scenario parameters — the same
dotted ``--set`` paths a sweep uses — to drive one metric of the run's ``summary.json`` across
a threshold; every run goes through the suite's executors, the study is kept in SQLite so a
killed search resumes, and each run that crosses the threshold (a *counterexample*) is written
as a scenario file with its parameters baked in, ready to join a suite with a baseline.

Modules: :mod:`~harness.search.space` (``--space PATH=RANGE`` → dimensions),
:mod:`~harness.search.objective` (``--objective`` and its threshold → violation),
:mod:`~harness.search.study` (the optuna study: samplers, storage, resume),
:mod:`~harness.search.counterexamples` (scenario files, suite entries, baselines),
:mod:`~harness.search.runner` (all of it, and the outputs: ``search.json``, ``junit.xml``,
``index.html``).
"""

__all__: list[str] = []
