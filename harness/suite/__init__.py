"""``srr suite``: many scenario runs — scenarios × sweep points × repeats — on parallel worker
processes or a Ray cluster, with statistics over repeats, flakiness, and outputs for CI
(``OUT/summary.json``, ``OUT/junit.xml``, ``OUT/index.html``).

Modules: :mod:`~harness.suite.sweep` (sweep declarations → points), :mod:`~harness.suite.spec`
(suite files and paths → entries), :mod:`~harness.suite.plan` (entries → runs),
:mod:`~harness.suite.worker` (one run, in whatever process it is given),
:mod:`~harness.suite.local` and :mod:`~harness.suite.ray_executor` (where runs execute),
:mod:`~harness.suite.stats` and :mod:`~harness.suite.results` (repeats → groups, verdicts),
:mod:`~harness.suite.outputs` (the files CI reads), :mod:`~harness.suite.runner` (all of it);
:mod:`~harness.suite.diff` and :mod:`~harness.suite.diff_page` (``srr diff SUITE_A SUITE_B``:
two suite output folders compared run by run).
"""

__all__: list[str] = []
