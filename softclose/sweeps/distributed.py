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
designs streams. A task that kills workers repeatedly (``distributed.KilledWorker``) is a
:class:`~softclose.errors.NumericalError` naming it. Progress is the caller's own line
(:class:`softclose.progress.Progress`, fed as results arrive from ``as_completed``): Dask's
``progress`` does not combine with ``as_completed`` (dask/distributed#2423).
"""

from __future__ import annotations

import contextlib
import logging
import re
import time
import uuid
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from ..errors import ConfigError, NumericalError, SoftcloseError

#: seconds to wait for a scheduler to answer before the address is refused
CONNECT_TIMEOUT = 5.0
#: tasks kept in flight per worker thread (enough to keep every worker busy while results
#: travel back; few enough that a long sweep's inputs are not all held by the scheduler)
IN_FLIGHT_PER_THREAD = 3
#: the largest local cluster (``local:N``) accepted
MAX_LOCAL_WORKERS = 512

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


def _import_distributed():
    try:
        import distributed
    except ImportError:
        raise ConfigError("--dask needs dask.distributed, which is not installed: "
                          "pip install 'softclose[dask]'") from None
    return distributed


def _worker_version() -> str:
    """Run on each worker: the softclose version it imports (checks that it can)."""
    import softclose
    return softclose.__version__


@contextlib.contextmanager
def connect(dask) -> Iterator[Any]:
    """A ``distributed.Client`` for ``dask`` (see the module docstring); a Client passed in
    is used as it is and left open. A local cluster is closed on exit."""
    distributed = _import_distributed()
    if isinstance(dask, distributed.Client):
        yield dask
        return
    where, n = parse_dask(dask)
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
    try:
        client = distributed.Client(where, timeout=CONNECT_TIMEOUT)
    except (OSError, ValueError, TimeoutError) as exc:
        why = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ConfigError(f"--dask {where}: no Dask scheduler answered ({why}); start one "
                          "(`dask scheduler`) or give its address") from None
    try:
        _check_workers(client, where)
        yield client
    finally:
        client.close()


def _workers_ignore_ctrl_c():
    """Start local worker processes with SIGINT ignored (they inherit it): Ctrl-C in a
    terminal reaches the whole process group, and only this process should act on it (it
    cancels the tasks and closes the cluster); otherwise every worker prints a traceback.
    A Ctrl-C during the second or so of start-up is therefore not seen."""
    import signal

    from ..interrupt import sigint_handler
    return sigint_handler(signal.SIG_IGN)


def _check_workers(client, where: str) -> None:
    """The workers present must import this softclose (same version): say so if not."""
    import softclose
    try:
        versions = client.run(_worker_version, on_error="return")
    except Exception as exc:  # noqa: BLE001 - a scheduler that fails here is unusable
        raise ConfigError(f"--dask {where}: the scheduler did not run a check on its workers "
                          f"({type(exc).__name__}: {exc})") from None
    for worker, v in versions.items():
        if isinstance(v, BaseException):
            raise ConfigError(f"--dask {where}: worker {worker} cannot import softclose "
                              f"({type(v).__name__}: {v}); install it on the workers")
        if v != softclose.__version__:
            raise ConfigError(f"--dask {where}: worker {worker} has softclose {v}, this "
                              f"process {softclose.__version__}; install the same version")


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
    exception raised by ``fn`` is re-raised here (a ConfigError stays one); the tasks still
    queued are cancelled however the iteration ends (exhausted, an error, Ctrl-C, close()).
    """
    distributed = _import_distributed()
    run = uuid.uuid4().hex[:12]
    it = iter(enumerate(tasks))
    pending: dict = {}                       # future -> tag
    ac = distributed.as_completed(with_results=True, raise_errors=False)
    asked = [-1e9, 0]                        # (when, threads)

    def threads() -> int:
        now = time.perf_counter()
        if now - asked[0] > 1.0:
            asked[:] = [now, workers_of(client)[1]]
        return asked[1]

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
            fut, result = next(ac)
            if fut not in pending:           # yielded twice (never expected): once only
                continue
            tag = pending.pop(fut)
            if fut.status == "error":
                _raise_task_error(result, label, tag)
            if fut.status == "cancelled":
                raise NumericalError(f"Dask cancelled the {label} {_describe(tag)} (the "
                                     "scheduler restarted or the cluster closed); run again")
            fut.release()                    # the result is ours: the cluster may forget it
            del fut
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


def _raise_task_error(exc, label: str, tag) -> None:
    distributed = _import_distributed()
    if isinstance(exc, distributed.KilledWorker):
        raise NumericalError(
            f"the Dask {label} {_describe(tag)} ended every worker that ran it "
            f"({type(exc).__name__}); look at the workers' logs (memory, crashes) and run the "
            "sweep again, or without --dask") from None
    if isinstance(exc, SoftcloseError):
        raise exc
    if isinstance(exc, BaseException):
        raise exc
    raise NumericalError(f"the Dask {label} {_describe(tag)} failed: {exc!r}")


# -- the sweep's chunks --------------------------------------------------------------------
def _chunk_task(cfg_dict: dict, keys: list[str], ids, X, threads: int | None = None) -> dict:
    """One sweep chunk on a worker: :func:`softclose.sweeps.chunks.evaluate_chunk` with
    ``threads`` kernel threads (default: as many as the worker has)."""
    from .chunks import evaluate_chunk
    if threads is None:
        try:
            from distributed import get_worker
            threads = get_worker().state.nthreads
        except (ImportError, ValueError, AttributeError):
            threads = 1
    return evaluate_chunk(cfg_dict, keys, ids, X, threads=threads)


@contextlib.contextmanager
def mapper(dask, threads: int | None = None):
    """A mapper for :func:`softclose.sweeps.run.run` that evaluates the chunks on Dask.

    ``dask`` is ``"local:N"``, a scheduler address or a ``distributed.Client``; the
    connection is made on entry (an unreachable address is a ConfigError here, before any
    work) and closed on exit. The mapper sends each chunk as plain values
    ``(cfg_dict, keys, ids, X)`` to :func:`softclose.sweeps.chunks.evaluate_chunk` on a
    worker (``threads`` kernel threads there; default: the worker's threads) and yields
    ``(c, columns)`` as chunks finish::

        with mapper("local:2") as m:
            result = run(cfg, space, mapper=m)
    """
    with connect(dask) as client:
        def dask_map(cfg_dict: dict, keys: list, tasks, _threads=None):
            keys = list(keys)
            yield from map_tasks(client, _chunk_task,
                                 ((c, (cfg_dict, keys, ids, X, threads))
                                  for c, ids, X in tasks), label="chunk")
        yield dask_map

__all__ = ["mapper", "connect", "map_tasks", "parse_dask", "workers_of", "CONNECT_TIMEOUT"]
