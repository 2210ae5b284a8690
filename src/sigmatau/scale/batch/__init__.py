"""Many logs at once on a Dask cluster: one task per log, per-log outputs and a fleet summary.

:func:`analyze_many` runs the analysis of ``sigmatau analyze``
(:func:`sigmatau.io.read`, :func:`sigmatau.analysis.analyze_log`,
:func:`sigmatau.outputs.write_outputs`) on every log, one task per log, on a
`dask.distributed <https://distributed.dask.org>`_ cluster: a
``LocalCluster`` of single-threaded worker processes by default, or an
existing cluster given by its scheduler address. Dask is the optional extra
``dask`` (``pip install "sigmatau[dask]"``); ``import sigmatau`` does not load it.

Layout of the output directory ``OUT``::

    OUT/batch.json            settings of the run (the same on every rerun)
    OUT/index.jsonl           a line per log as it finishes (append-only journal; one per
                              path, content hash and outcome, however often rerun)
    OUT/batch.lock            while a run writes: its host, PID, process start time, boot id
    OUT/logs/<stem>-<sha12>/  the outputs of one log (results.json, CSVs, figures,
                              report.html, imu.yaml) and record.json, its summary
    OUT/fleet.csv             one row per log × channel × term: value, interval, limit, outlier
    OUT/fleet_logs.csv        one row per log: status, verdict, outliers, error and reason
    OUT/fleet.json            all of it, with the distribution of every term
    OUT/fleet_hist.png, OUT/fleet_strip.png, OUT/fleet.html

Resuming: a log's directory is named after the SHA-256 of its content and
appears only complete (it is written under a hidden name and renamed into
place, record.json included), so a rerun of the same command skips every log
whose directory exists — whatever interrupted the previous run — and a task
retried after a worker died keeps the one directory that got there first.

On an existing cluster: the workers need sigmatau (with its ``dask`` extra)
and must see the logs and ``OUT`` under the same paths (a shared file
system); one thread per worker process suits this work (each task is one log)::

    dask scheduler                                             # prints tcp://10.0.0.5:8786
    dask worker tcp://10.0.0.5:8786 --nworkers 8 --nthreads 1  # on each machine
    sigmatau batch '/data/line3/*.csv' --out /data/line3-fleet --scheduler tcp://10.0.0.5:8786

or ``analyze_many(paths, out, client=distributed.Client("tcp://10.0.0.5:8786"))``.

The steps, one module each (they import :mod:`.common` and not each other,
except :mod:`.report` the tables of :mod:`.summary` and :mod:`.run` all of them):

- :mod:`.inputs`: the logs named by patterns; the read and analysis settings checked;
- :mod:`.task`: one log, one Dask task (hash, analyse, write, publish, record);
- :mod:`.lock` and :mod:`.journal`: one run per ``OUT``; ``index.jsonl``, resuming, cleanup;
- :mod:`.limits`, :mod:`.summary`, :mod:`.report`: limits, fleet tables, figures and ``fleet.html``;
- :mod:`.cluster`, :mod:`.progress`, :mod:`.run`: the cluster, the progress shown, :func:`analyze_many`.

Examples
--------
>>> from sigmatau.batch import analyze_many                            # doctest: +SKIP
>>> fleet = analyze_many(["line3/*.csv"], "fleet-out", workers=2, limits="lsm6dsl")  # doctest: +SKIP
>>> fleet.summary()                                                    # doctest: +SKIP
"""

from .cluster import check_scheduler_address
from .common import CONNECT_TIMEOUT, LIMIT_MARGIN, OUTLIER_Z, ClusterError
from .inputs import expand_patterns
from .limits import load_limits
from .run import analyze_many
from .summary import FleetSummary

# Not public (not in __all__), re-exported for ``sigmatau batch`` (sigmatau.cli.batch) and the tests.
from .cluster import _distributed, local_worker_count, usable_cores  # noqa: F401
from .common import LOGS_DIR  # noqa: F401

__all__ = [
    "analyze_many",
    "expand_patterns",
    "load_limits",
    "FleetSummary",
    "check_scheduler_address",
    "ClusterError",
    "OUTLIER_Z",
    "LIMIT_MARGIN",
    "CONNECT_TIMEOUT",
]
