"""One run of a scenario, as named steps around the typed run summary.

The steps, in the order a run takes them:

* :mod:`harness.run.simulate` — *prepare*: load nothing, check everything that can be checked
  before a run (scoring, disk space, wiring, live view, RTSP), build the simulation;
* :mod:`harness.run.record` — *own the directory* (:mod:`harness.runlock`), *record* (the tick
  loop), *score*, *judge* and *write the outputs* (summary, JUnit, report);
* :mod:`harness.run.judge` — compare the scores with the baseline and decide the verdict;
* :mod:`harness.run.baselines` — where a scenario's baselines live, and blessing a run;
* :mod:`harness.run.replay` — an open-loop replay of a recorded run, recorded like a run;
* :mod:`harness.run.recover` — turn what a killed run left back into a valid run directory;
* :mod:`harness.run.facts` — the small facts every summary carries (versions, topic table,
  combined digest, the command to reproduce a run).

The run summary itself, written and read, is :class:`harness.summary.RunSummary`.
:mod:`harness.api` re-exports the public functions; :mod:`harness.suite` builds on this package,
never the reverse. Submodules are imported on their own (this module imports none of them), so
reading a summary or recovering a run does not load MuJoCo.
"""

__all__: list[str] = []
