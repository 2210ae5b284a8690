"""The Dask cluster of a batch: the scheduler address checked and probed, a local cluster's worker
count, and the client to submit through."""

from __future__ import annotations

import logging
import os
import re
import socket
import warnings
from typing import Any, Callable, Optional

from ...errors import ParameterError
from .common import CONNECT_TIMEOUT, ClusterError, _one_line


def _distributed() -> Any:
    """The module ``distributed``, imported only when a batch runs.

    Raises MissingDependencyError naming the extra ``dask`` when it is absent.
    """
    try:
        import distributed
    except ImportError:
        from ...io import MissingDependencyError

        raise MissingDependencyError(
            "batch analysis needs the optional packages dask and distributed, which are not installed;"
            ' install them with: pip install "sigmatau[dask]"'
        ) from None
    return distributed


def usable_cores() -> int:
    """Cores this process may run on (its CPU affinity where the platform tells it)."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


_SCHEMES = ("tcp", "tls", "ws", "wss", "ucx")
_ADDRESS = re.compile(r"(?:(?P<scheme>[A-Za-z][A-Za-z0-9+.-]*)://)?"
                      r"(?P<host>\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_](?:[A-Za-z0-9_.-]*[A-Za-z0-9_])?)"
                      r":(?P<port>[0-9]{1,5})")


def check_scheduler_address(address: Any, *, name: str = "scheduler") -> str:
    """``address`` checked to be a Dask scheduler address, ``[scheme://]host:port``, before any connection.

    Parameters
    ----------
    address : str
        ``tcp://10.0.0.5:8786`` (the scheme may be ``tcp``, ``tls``, ``ws``, ``wss``
        or ``ucx``; without one, ``tcp``); the host a name, an IPv4 address or a
        bracketed IPv6 address; the port 1–65535.
    name : str
        What to call it in the message (the CLI says ``--scheduler``).

    Returns
    -------
    str
        The address as given.

    Raises
    ------
    ParameterError
        Anything else, named in a one-line message.

    Examples
    --------
    >>> check_scheduler_address("tcp://10.0.0.5:8786")
    'tcp://10.0.0.5:8786'
    """
    example = "such as tcp://host:8786"
    if not isinstance(address, str):
        raise ParameterError(f"{name} {address!r} is not a scheduler address {example}")
    m = _ADDRESS.fullmatch(address.strip())
    if m is None:
        raise ParameterError(f"{name} {address!r} is not a scheduler address {example} ([scheme://]host:port)")
    scheme = (m["scheme"] or "tcp").lower()
    if scheme not in _SCHEMES:
        raise ParameterError(f"{name} {address!r} is not a scheduler address {example}: scheme {scheme!r} is not"
                             f" one of {', '.join(_SCHEMES)}")
    if not 1 <= int(m["port"]) <= 65535:
        raise ParameterError(f"{name} {address!r} is not a scheduler address {example}: port {m['port']} is not"
                             " in 1-65535")
    return address


def _probe_scheduler(address: str) -> None:
    """Fail fast, in one line, when nothing answers at ``address`` (a TCP connection, before any
    Dask client: a client that fails to connect lingers for tens of seconds at exit)."""
    m = _ADDRESS.fullmatch(address.strip())
    if m is None or (m["scheme"] or "tcp").lower() == "ucx":  # UCX is not TCP: left to Dask's own timeout
        return
    host = m["host"].strip("[]")
    try:
        with socket.create_connection((host, int(m["port"])), timeout=CONNECT_TIMEOUT):
            pass
    except socket.gaierror as exc:
        reason = f"unknown host {host!r} ({exc.strerror or exc})"
    except (TimeoutError, socket.timeout):
        reason = "no answer"
    except OSError as exc:
        reason = (exc.strerror or str(exc)).lower()
    else:
        return
    raise ClusterError(f"cannot reach the Dask scheduler at {address!r} within {CONNECT_TIMEOUT:g} s: {reason}")


def local_worker_count(requested: Optional[int], logs: int, cores: int) -> tuple[int, str]:
    """Worker processes of a local cluster: the request (default the cores), at most the cores and the
    logs (each task is one log on one single-threaded process); and a note when a request was capped."""
    n = max(1, min(requested or cores, cores, logs))
    note = ""
    if requested is not None and requested > n:
        note = (f"workers={requested} capped to {n}: {cores} usable core(s), {logs} log(s) to analyse;"
                " more processes would only compete for them")
    return n, note


def _connect(client: Any, scheduler: Optional[str], workers: int) -> tuple[Any, Callable[[], None]]:
    """The client to use and how to close what was opened here."""
    if client is not None:
        return client, lambda: None
    distributed = _distributed()
    if scheduler is not None:
        try:
            c = distributed.Client(scheduler, timeout=f"{CONNECT_TIMEOUT:g}s", set_as_default=False)
        except (OSError, TimeoutError) as exc:
            raise ClusterError(f"cannot reach the Dask scheduler at {scheduler!r} within {CONNECT_TIMEOUT:g} s:"
                               f" {_one_line(exc)}") from None
        except (ValueError, TypeError) as exc:
            raise ParameterError(f"--scheduler {scheduler!r} is not a scheduler address such as"
                                 f" tcp://host:8786 ({_one_line(exc)})") from None
        return c, c.close
    n = workers
    import dask

    try:
        # Dask's nanny sets MALLOC_TRIM_THRESHOLD_=65536 in its workers, which also fixes glibc's mmap
        # threshold at 128 KiB: every array of a long log is then mmapped and page-faulted afresh,
        # and the analysis runs 2-3 times slower (measured). Unset here (None unsets it).
        with dask.config.set({"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}), \
                warnings.catch_warnings():  # the scheduler's HTTP port: another one is taken when 8787 is
            warnings.filterwarnings("ignore", message="Port .* is already in use")
            # silence_logs: a worker whose heartbeat meets the scheduler already closing logs a
            # traceback at ERROR (seen once in CI); batch reports every log's outcome itself.
            cluster = distributed.LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                                               dashboard_address=None, silence_logs=logging.CRITICAL)
    except Exception as exc:
        raise ClusterError(f"cannot start a local Dask cluster of {n} workers: {_one_line(exc)}") from None
    # Not the process's default client: batch submits and waits through it explicitly, and a
    # default one would leave dask's global scheduler pointing at a closed cluster afterwards.
    c = distributed.Client(cluster, set_as_default=False)

    def close() -> None:
        c.close()
        cluster.close()

    return c, close
