"""One run of a scenario, as named steps around the typed run summary.

The steps, in the order a run takes them:

* :mod:`harness.run.simulate` — *prepare*: check everything that can be checked before a run
  (scoring, disk space, wiring, live view, RTSP) and build the simulation; ``srr validate``;
* :mod:`harness.run.record` — *own the directory* (:mod:`harness.runlock`), *record* (the tick
  loop), *score*, *judge* and *write the outputs* (summary, JUnit, report);
* :mod:`harness.run.judge` — compare the scores with the baseline and decide the verdict;
* :mod:`harness.run.baselines` — where a scenario's baselines live, and blessing a run;
* :mod:`harness.run.replay` — an open-loop replay of a recorded run, recorded like a run;
* :mod:`harness.run.recover` — turn what a killed run left back into a valid run directory;
* :mod:`harness.run.rerender` — ``srr report``: a finished run's report rendered again;
* :mod:`harness.run.summary` — :class:`~harness.run.summary.RunSummary`, the typed
  ``summary.json`` every step above writes or reads;
* :mod:`harness.run.facts` — the small facts every summary carries (versions, topic table,
  combined digest, the command to reproduce a run); :mod:`harness.run.loading` — a scenario
  loaded with the command line's overrides.

:mod:`harness.api` re-exports the public functions; :mod:`harness.suite` builds on this package,
never the reverse. This module imports none of its submodules: each is imported where it is
used.
"""

__all__: list[str] = []
