"""Sweeps on a Dask cluster: the chunks of a sweep (or the segments of an optimal grid) as
Dask tasks, on a running ``dask.distributed`` scheduler or on a local cluster of processes.

Where the work runs is one string, ``dask`` (``--dask`` on the command line):

- ``"local:N"`` starts a :class:`distributed.LocalCluster` of N worker *processes* with one
  thread each (Ipopt and MUMPS are not thread-safe; N processes use N cores) and stops it
  afterwards;
- any other string is the address of a running scheduler (``tcp://host:8786``, or
  ``host:8786``), e.g. one started by dask-jobqueue on SLURM or by dask-kubernetes. An
  address that does not answer within :data:`CONNECT_TIMEOUT` seconds is a
  :class:`~softclose.errors.ConfigError` naming it (exit 2), and so is a worker that cannot
  import this version of softclose.

What is sent is plain values, never CasADi objects (they do not pickle): the task function is
importable (:func:`softclose.sweeps.chunks.evaluate_chunk`,
:func:`softclose.sweeps.optimal.solve_segment`) and its arguments are a config dict, key names
and numpy arrays; each worker process builds (and caches) its own simulator or NLP from the
config. The results are therefore the same numbers as the local run's, whatever the number
of workers.

A worker that is lost while it holds a task (killed, out of memory, its node preempted) has
that task rescheduled by the Dask scheduler on another worker; :func:`map_tasks` yields every
task's result exactly once, releases it at once (so a lost worker never forces finished work
to be redone) and keeps a bounded number of tasks in flight, so a sweep of millions of
designs streams. A cluster that stops working in the middle -- the scheduler lost, every
worker gone for :data:`NO_WORKERS_TIMEOUT` seconds, a task that kills worker after worker
(``distributed.KilledWorker``) -- is a :class:`ClusterLost` (a
:class:`~softclose.errors.NumericalError`) saying so; the sweep's mapper ends there, so that
the runner keeps every finished chunk and the sweep can be resumed. Progress is the caller's
own line (:class:`softclose.present.progress.Progress`, fed as results arrive from ``as_completed``):
Dask's ``progress`` does not combine with ``as_completed`` (dask/distributed#2423).
"""

from __future__ import annotations

import contextlib
import logging
import re
import threading
import time
import uuid
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from ..errors import ConfigError, NumericalError, SoftcloseError
from .chunks import evaluate_chunk
from ..version import __version__
from ..interrupt import sigint_handler

#: seconds to wait for a scheduler to answer before the address is refused
CONNECT_TIMEOUT = 5.0
#: seconds more given to the handshake with a server that accepted the connection
HANDSHAKE_GRACE = 3.0
#: tasks kept in flight per worker thread (enough to keep every worker busy while results
#: travel back; few enough that a long sweep's inputs are not all held by the scheduler)
IN_FLIGHT_PER_THREAD = 3
#: the largest local cluster (``local:N``) accepted
MAX_LOCAL_WORKERS = 512
#: seconds a cluster that had workers may go without any (all lost, none restarted) while
#: tasks wait, before the run stops with :class:`ClusterLost`
NO_WORKERS_TIMEOUT = 60.0
#: seconds between looks at a cluster while no result is ready
POLL = 0.01
#: the loggers in this process that narrate a lost scheduler or worker (reconnection
#: attempts, keys rescheduled, the tracebacks of result transfers cut off, which Dask's
#: event loop reports through tornado): :class:`ClusterLost` says it in one line instead
_QUIET_LOGGERS = ("distributed.client", "distributed.scheduler", "distributed.core",
                  "distributed.comm", "distributed.batched", "distributed.utils",
                  "tornado.application")

_LOCAL = re.compile(r"^\s*local\s*:\s*(\S*)\s*$")


def parse_dask(spec: str) -> tuple[str, int | None]:
    """``("local", N)`` for ``"local:N"``, else ``(address, None)``; bad forms are a
    ConfigError naming the option."""
    if not isinstance(spec, str) or not spec.strip():
        raise ConfigError(f"--dask {spec!r}: expected a scheduler address "
                          "(tcp://host:8786) or local:N")
    m = _LOCAL.match(spec)
    if m:
        n = m.group(1)
        if not re.fullmatch(r"\d+", n) or not 1 <= int(n) <= MAX_LOCAL_WORKERS:
            raise ConfigError(f"--dask {spec}: local:N needs a number of worker processes N "
                              f"from 1 to {MAX_LOCAL_WORKERS}, got {n!r}")
        return "local", int(n)
    address = spec.strip()
    if "://" not in address and ":" not in address:
        raise ConfigError(f"--dask {spec}: expected a scheduler address with a port, e.g. "
                          "tcp://host:8786, or local:N")
    return address, None


class ClusterLost(NumericalError):
    """The cluster stopped working in the middle of a run: the scheduler was lost, every
    worker is gone, or a task ended every worker that ran it. The results yielded before
    are good (a sweep keeps them and can be resumed); the message says what happened."""


def _import_distributed():
    try:
        import distributed
    except ImportError:
        raise ConfigError("--dask needs dask.distributed, which is not installed: "
                          "pip install 'softclose[dask]'") from None
    return distributed


def _worker_version() -> str:
    """Run on each worker: the softclose version it imports (checks that it can)."""
    return __version__


@contextlib.contextmanager
def connect(dask) -> Iterator[Any]:
    """A ``distributed.Client`` for ``dask`` (see the module docstring); a Client passed in
    is used as it is and left open. A local cluster is closed on exit."""
    distributed = _import_distributed()
    if isinstance(dask, distributed.Client):
        with _quiet_dask_logs():
            yield dask
        return
    where, n = parse_dask(dask)
    with _quiet_dask_logs():
        yield from _connect(distributed, where, n)


def _connect(distributed, where: str, n: int | None) -> Iterator[Any]:
    """The Client of :func:`connect` for a local cluster of ``n`` processes or an address."""
    if where == "local":
        with _workers_ignore_ctrl_c():
            cluster = distributed.LocalCluster(
                n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                silence_logs=logging.ERROR)
        try:
            client = distributed.Client(cluster)
            try:
                yield client
            finally:
                client.close()
        finally:
            cluster.close()
        return
    client = _client(distributed, where)
    try:
        _check_workers(client, where)
        yield client
    finally:
        client.close()


def _client(distributed, where: str):
    """``distributed.Client(where)``, or a ConfigError naming the address within
    :data:`CONNECT_TIMEOUT` + :data:`HANDSHAKE_GRACE` seconds. Dask bounds the TCP connection
    by its timeout but not the handshake that follows, so on a port where another server
    listens (a web server, the dashboard) the Client would wait for ever, or read that
    server's greeting as a frame length: the Client is made in a thread that is given up
    on, and whatever it raises is one line."""
    made: dict = {}

    def attempt():
        try:
            made["client"] = distributed.Client(where, timeout=CONNECT_TIMEOUT)
        except Exception as exc:  # noqa: BLE001 - reported below, as one line
            made["error"] = exc

    t = threading.Thread(target=attempt, name="softclose-dask-connect", daemon=True)
    t.start()
    t.join(CONNECT_TIMEOUT + HANDSHAKE_GRACE)
    if t.is_alive():
        raise ConfigError(f"--dask {where}: something listens there but did not answer as a "
                          f"Dask scheduler within {CONNECT_TIMEOUT + HANDSHAKE_GRACE:g} s; "
                          "give the scheduler's address (port 8786 unless set otherwise)")
    exc = made.get("error")
    if exc is None:
        return made["client"]
    why = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    if isinstance(exc, (OSError, ValueError, TimeoutError)):
        raise ConfigError(f"--dask {where}: no Dask scheduler answered ({why}); start one "
                          "(`dask scheduler`) or give its address") from None
    raise ConfigError(f"--dask {where}: what answered there is not a Dask scheduler "
                      f"({type(exc).__name__}); give the scheduler's address (port 8786 "
                      "unless set otherwise)") from None


@contextlib.contextmanager
def _quiet_dask_logs():
    """Hold back Dask's own narration of a lost scheduler or worker (ERROR and WARNING lines
    with tracebacks on stderr) while connected: a failure is reported once, as a
    :class:`ClusterLost` or a ConfigError."""
    loggers = [logging.getLogger(name) for name in _QUIET_LOGGERS]
    levels = [lg.level for lg in loggers]
    for lg in loggers:
        lg.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        for lg, level in zip(loggers, levels):
            lg.setLevel(level)


def _workers_ignore_ctrl_c():
    """Start local worker processes with SIGINT ignored (they inherit it): Ctrl-C in a
    terminal reaches the whole process group, and only this process should act on it (it
    cancels the tasks and closes the cluster); otherwise every worker prints a traceback.
    A Ctrl-C during the second or so of start-up is therefore not seen."""
    import signal

    return sigint_handler(signal.SIG_IGN)


def _check_workers(client, where: str) -> None:
    """The workers present must import this softclose (same version): say so if not."""
    try:
        versions = client.run(_worker_version, on_error="return")
    except Exception as exc:  # noqa: BLE001 - a scheduler that fails here is unusable
        raise ConfigError(f"--dask {where}: the scheduler did not run a check on its workers "
                          f"({type(exc).__name__}: {exc})") from None
    for worker, v in versions.items():
        if isinstance(v, BaseException):
            raise ConfigError(f"--dask {where}: worker {worker} cannot import softclose "
                              f"({type(v).__name__}: {v}); install it on the workers")
        if v != __version__:
            raise ConfigError(f"--dask {where}: worker {worker} has softclose {v}, this "
                              f"process {__version__}; install the same version")


def workers_of(client) -> tuple[int, int]:
    """(worker processes, threads) the scheduler has now."""
    nthreads = client.nthreads()
    return len(nthreads), int(sum(nthreads.values()))


def map_tasks(client, fn: Callable, tasks: Iterable[tuple[Any, tuple]],
              label: str = "task") -> Iterator[tuple[Any, Any]]:
    """Run ``fn(*args)`` for every ``(tag, args)`` of ``tasks`` on ``client``'s workers;
    yield ``(tag, result)`` once per task, in the order they finish.

    ``tasks`` is consumed lazily: at most :data:`IN_FLIGHT_PER_THREAD` tasks per worker
    thread are submitted ahead (the count follows the cluster as it grows or shrinks). A
    task whose worker is lost is rerun by the scheduler; its result is yielded once. An
    exception raised by ``fn`` is re-raised here (a ConfigError stays one). A cluster that
    stops working -- the scheduler lost, no worker left for :data:`NO_WORKERS_TIMEOUT`
    seconds after there were some, a task that ends every worker that runs it -- raises
    :class:`ClusterLost` (the results yielded before are good). The tasks still queued are
    cancelled however the iteration ends (exhausted, an error, Ctrl-C, close()).
    """
    distributed = _import_distributed()
    run = uuid.uuid4().hex[:12]
    it = iter(enumerate(tasks))
    pending: dict = {}                       # future -> tag
    ac = distributed.as_completed(with_results=True, raise_errors=False)
    asked = [-1e9, 0]                        # (when, threads)
    silent = [None]                          # since when the scheduler's polls have failed
    had_workers = [False]
    workerless = [None]                      # since when the cluster has had no worker
    finished = [0]

    def threads() -> int:
        """The cluster's worker threads, asked at most once a second. One failed poll is
        not a lost scheduler (distributed can fail a call on a passing comm state; the
        client's status says when the connection is really gone, see disconnected()); a
        scheduler whose polls keep failing for CONNECT_TIMEOUT seconds is."""
        now = time.perf_counter()
        if now - asked[0] > 1.0:
            try:
                asked[:] = [now, workers_of(client)[1]]
                silent[0] = None
            except Exception as exc:  # noqa: BLE001 - any failure: ask again in a second
                silent[0] = silent[0] or now
                if now - silent[0] > CONNECT_TIMEOUT:
                    raise ClusterLost(f"the Dask scheduler {_address(client)} stopped "
                                      f"answering after {finished[0]} {label}s "
                                      f"({type(exc).__name__})") from None
                asked[0] = now               # (the last count stands meanwhile)
        return asked[1]

    def disconnected() -> ClusterLost | None:
        if getattr(client, "status", "running") == "running":
            return None
        return ClusterLost(f"the connection to the Dask scheduler {_address(client)} was "
                           f"lost after {finished[0]} {label}s")

    def watch() -> None:
        """While no result is ready: give up on a lost scheduler, or on a cluster that has
        lost every worker."""
        lost = disconnected()
        if lost is not None:
            raise lost
        if threads() > 0:
            had_workers[0], workerless[0] = True, None
            return
        if not had_workers[0]:               # none yet (a cluster still starting): wait
            return
        now = time.perf_counter()
        workerless[0] = workerless[0] or now
        if now - workerless[0] > NO_WORKERS_TIMEOUT:
            raise ClusterLost(f"every Dask worker of {_address(client)} was lost after "
                              f"{finished[0]} {label}s and none came back within "
                              f"{NO_WORKERS_TIMEOUT:g} s")

    def top_up() -> None:
        cap = max(IN_FLIGHT_PER_THREAD * max(threads(), 1), 2)
        while len(pending) < cap:
            nxt = next(it, None)
            if nxt is None:
                return
            i, (tag, args) = nxt
            fut = client.submit(fn, *args, key=f"softclose-{label}-{run}-{i}", pure=False)
            pending[fut] = tag
            ac.add(fut)

    try:
        top_up()
        while pending:
            while not ac.has_ready():
                watch()
                time.sleep(POLL)
            fut, result = next(ac)
            if fut not in pending:           # yielded twice (never expected): once only
                continue
            tag = pending.pop(fut)
            if fut.status == "error":
                _raise_task_error(result, label, tag)
            if fut.status == "cancelled":
                raise disconnected() or ClusterLost(
                    f"Dask cancelled the {label} {_describe(tag)} after {finished[0]} "
                    f"{label}s (the scheduler restarted or the cluster closed)")
            fut.release()                    # the result is ours: the cluster may forget it
            del fut
            finished[0] += 1
            top_up()                         # keep the workers busy while we digest it
            yield tag, result
    finally:
        if pending:
            with contextlib.suppress(Exception):
                client.cancel(list(pending))
        with contextlib.suppress(Exception):
            ac.clear()


def _describe(tag) -> str:
    """A short name for a task's tag (ids a..b for an array of ids)."""
    try:
        import numpy as np
        a = np.asarray(tag)
        if a.ndim == 1 and a.size:
            return f"of ids {int(a.min())}..{int(a.max())}"
    except (TypeError, ValueError):
        pass
    return f"{tag}"


def _address(client) -> str:
    """The scheduler's address, for a message."""
    return str(getattr(getattr(client, "scheduler", None), "address", None) or "scheduler")


def _raise_task_error(exc, label: str, tag) -> None:
    distributed = _import_distributed()
    if isinstance(exc, distributed.KilledWorker):
        raise ClusterLost(
            f"the Dask {label} {_describe(tag)} ended every worker that ran it "
            f"({type(exc).__name__}); look at the workers' logs (memory, crashes), or run it "
            "without --dask") from None
    if isinstance(exc, SoftcloseError):
        raise exc
    if isinstance(exc, BaseException):
        raise exc
    raise NumericalError(f"the Dask {label} {_describe(tag)} failed: {exc!r}")


# -- the sweep's chunks --------------------------------------------------------------------
def _chunk_task(cfg_dict: dict, keys: list[str], ids, X, threads: int | None = None) -> dict:
    """One sweep chunk on a worker: :func:`softclose.sweeps.chunks.evaluate_chunk` with
    ``threads`` kernel threads (default: as many as the worker has)."""
    if threads is None:
        try:
            from distributed import get_worker
            threads = get_worker().state.nthreads
        except (ImportError, ValueError, AttributeError):
            threads = 1
    return evaluate_chunk(cfg_dict, keys, ids, X, threads=threads)


class _Mapper:
    """The sweep's mapper on a connected client (see :func:`mapper`). A :class:`ClusterLost`
    ends its iteration quietly -- the runner then keeps the chunks finished so far, as after
    Ctrl-C -- and is left in :attr:`lost` for the caller to report."""

    def __init__(self, client, threads: int | None):
        self.client, self.threads = client, threads
        self.lost: ClusterLost | None = None

    def __call__(self, cfg_dict: dict, keys: list, tasks, _threads=None):
        keys, threads = list(keys), self.threads
        try:
            yield from map_tasks(self.client, _chunk_task,
                                 ((c, (cfg_dict, keys, ids, X, threads))
                                  for c, ids, X in tasks), label="chunk")
        except ClusterLost as exc:
            self.lost = exc


@contextlib.contextmanager
def mapper(dask, threads: int | None = None):
    """A mapper for :func:`softclose.sweeps.run.run` that evaluates the chunks on Dask.

    ``dask`` is ``"local:N"``, a scheduler address or a ``distributed.Client``; the
    connection is made on entry (an unreachable address is a ConfigError here, before any
    work) and closed on exit. The mapper sends each chunk as plain values
    ``(cfg_dict, keys, ids, X)`` to :func:`softclose.sweeps.chunks.evaluate_chunk` on a
    worker (``threads`` kernel threads there; default: the worker's threads) and yields
    ``(c, columns)`` as chunks finish. If the cluster stops working it stops yielding: the
    run ends as an interrupted one (every finished chunk kept) and the mapper's ``lost``
    holds the :class:`ClusterLost` that says why (None otherwise)::

        with mapper("local:2") as m:
            result = run(cfg, space, mapper=m)
        if m.lost:
            ...   # result.interrupted: report m.lost, resume later
    """
    with connect(dask) as client:
        yield _Mapper(client, threads)


__all__ = ["mapper", "connect", "map_tasks", "parse_dask", "workers_of", "ClusterLost",
           "CONNECT_TIMEOUT", "NO_WORKERS_TIMEOUT"]
