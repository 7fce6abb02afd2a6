"""The runner: hands the chunks of a grid or sample to a mapper, keeps what comes back.

A *mapper* is any callable ``mapper(cfg_dict, keys, tasks, threads)`` that evaluates the
``tasks`` -- an iterator of ``(c, ids, X)``: chunk number, design ids, swept values -- with
:func:`softclose.sweeps.chunks.evaluate_chunk` and yields ``(c, columns)`` as chunks finish,
in any order. :func:`local_map` evaluates them in this process, as many at once as it has
kernel threads; a distributed mapper sends the same plain values to workers.

For each finished chunk the runner updates the :class:`~softclose.sweeps.tally.Tally` and
the :class:`~softclose.sweeps.tally.Bins`, hands the rows to a ``sink`` (a Parquet part
file) and/or keeps them in memory, and advances the progress line. Ctrl-C stops it between
chunks: every finished chunk is kept and the result says ``interrupted``.
"""

from __future__ import annotations

import collections
import signal
import threading
import time
from contextlib import contextmanager
from typing import Callable, Iterable, Iterator

import numpy as np

from ..errors import ConfigError
from ..problem import categorise, PARAM_DEFAULTS, params_of
from .chunks import CHUNK, PARAM_COLUMNS, columns, empty, evaluate_chunk
from .result import SweepResult
from .tally import Bins, Tally
from ..model.elements import SEED
from ..present.progress import Progress
from ..simulation.kernel.binding import kernel_threads

#: most designs a result keeps in memory (larger sweeps: stream them to a Parquet dataset)
MAX_IN_MEMORY = 20_000_000

Mapper = Callable[[dict, list, Iterable, "int | None"], Iterator[tuple[int, dict]]]


def local_map(cfg_dict: dict, keys: list[str], tasks, threads: int | None = None):
    """Evaluate the chunks here, several at once, each in a thread of its own; yields them
    in task order. ``threads``: the kernel threads in all (default: one per core, at most
    ``softclose.simulation.kernel.binding.MAX_THREADS``).

    A chunk spends about two thirds of its CPU time in the kernel, which releases the GIL,
    and the rest in Python (the statics, the reasons, the columns). One chunk at a time with
    the kernel on every core leaves all but one core idle while its Python runs. So as many
    chunks as threads are evaluated at once, one kernel thread each: while one chunk's
    Python runs the others' strokes are integrated, and the caller stores the last finished
    chunk meanwhile. Where fewer chunks are left than threads, they share the threads (a
    sweep of one chunk has them all)."""
    total = kernel_threads(threads)
    tasks = iter(tasks)
    ahead: collections.deque = collections.deque()      # tasks drawn, not started
    flight: collections.deque = collections.deque()     # (thread, box) in task order

    def start() -> None:
        while len(ahead) < total:               # (look ahead: how many chunks are left)
            task = next(tasks, None)
            if task is None:
                break
            ahead.append(task)
        if not ahead:
            return
        task = ahead.popleft()
        share = max(1, total // min(total, len(flight) + 1 + len(ahead)))
        box: list = []

        def work():
            try:
                box.append((task[0], evaluate_chunk(cfg_dict, keys, task[1], task[2],
                                                    threads=share)))
            except BaseException as exc:   # noqa: BLE001  (raised in the caller's thread)
                box.append(exc)
        t = threading.Thread(target=work, daemon=True)
        t.start()
        flight.append((t, box))

    for _ in range(total):
        start()
    while flight:
        t, box = flight.popleft()
        t.join()
        got = box[0]
        if isinstance(got, BaseException):
            raise got
        start()
        yield got


def chunk_ids(c: int, n: int, chunk: int) -> np.ndarray:
    return np.arange(c * chunk, min(n, (c + 1) * chunk), dtype=np.int64)


def n_chunks(n: int, chunk: int) -> int:
    return -(-n // chunk)


@contextmanager
def _no_interrupt(reraise: bool = True):
    """Hold Ctrl-C while a finished chunk is recorded (written and counted together); raise
    it afterwards (``reraise``) or drop it. Only where Ctrl-C is Python's plain
    KeyboardInterrupt (another handler is left alone)."""
    if threading.current_thread() is not threading.main_thread() or \
            signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield
        return
    caught = []
    old = signal.signal(signal.SIGINT, lambda *a: caught.append(a))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)
        if caught and reraise:
            raise KeyboardInterrupt


def run(cfg, space, *, progress: bool = False, threads: int | None = None,
        chunk: int = CHUNK, keep: bool = True, sink=None, done=(),
        mapper: Mapper | None = None, dataset: str | None = None) -> SweepResult:
    """Evaluate every design of ``space`` (a Grid or Sample) not in ``done``.

    ``done`` yields ``(c, columns)`` of chunks computed before (a resumed sweep); ``keep``
    keeps the rows in memory (the result's ``columns``); ``sink.write(c, columns)`` stores
    each new chunk. Returns the :class:`SweepResult` (``interrupted`` after Ctrl-C).
    """
    if isinstance(chunk, bool) or not isinstance(chunk, (int, np.integer)) or chunk < 1:
        raise ConfigError(f"chunk: expected a positive whole number of designs, got {chunk!r}")
    chunk = int(chunk)
    n, keys = space.n, list(space.keys)
    if keep and n > MAX_IN_MEMORY:
        raise ConfigError(f"{n} designs are more than {MAX_IN_MEMORY} kept in memory; "
                          "stream them to a Parquet dataset (softclose sweep --format parquet)")
    t0 = time.perf_counter()
    tally, bins = Tally(keys, n), Bins(space)
    kept: dict[int, dict] = {}
    stages = {"evaluate": 0.0, "evaluated": 0, "write": 0.0, "summarise": 0.0, "resumed": 0}

    def absorb(c, cols):
        ts = time.perf_counter()
        cat = categorise(cols["status"], cols["reason"])
        tally.update(cols, cat)
        bins.update(cols, cat)
        if keep:
            kept[c] = cols
        stages["summarise"] += time.perf_counter() - ts

    have = set()
    for c, cols in done:
        absorb(c, cols)
        have.add(c)
        stages["resumed"] += len(cols["id"])
    todo = [c for c in range(n_chunks(n, chunk)) if c not in have]
    tasks = ((c, ids, space.points(ids)) for c in todo for ids in [chunk_ids(c, n, chunk)])
    mapper = mapper or local_map
    bar = Progress(sum(len(chunk_ids(c, n, chunk)) for c in todo), "sweep", enabled=progress)
    interrupted = False
    new = 0
    try:
        results = mapper(cfg.raw, keys, tasks, threads)
        while True:
            te = time.perf_counter()
            try:
                c, cols = next(results)
            except StopIteration:
                break
            stages["evaluate"] += time.perf_counter() - te
            with _no_interrupt():
                if sink is not None:
                    tw = time.perf_counter()
                    sink.write(c, cols)
                    stages["write"] += time.perf_counter() - tw
                absorb(c, cols)
                new += len(cols["id"])
                stages["evaluated"] = new
            bar.update(new)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        bar.update(new, force=True)
        bar.close()
    cols = None
    if keep:
        parts = [kept[c] for c in sorted(kept)]
        cols = {k: np.concatenate([p[k] for p in parts]) for k in columns(keys)} if parts \
            else empty(keys, 0)
    return SweepResult(space=space, points=n, computed=tally.computed, feasible=tally.feasible,
                       reasons=tally.reasons(), best=tally.best, bins=bins.freeze(),
                       seconds=time.perf_counter() - t0, stages=stages, chunk=chunk,
                       interrupted=interrupted or tally.computed < n, columns=cols,
                       dataset=dataset,
                       fixed={k: _value(getattr(getattr(cfg, k.split(".")[0]), k.split(".")[1]))
                              for k in PARAM_COLUMNS if k not in keys and _says(cfg, k)})


def _says(cfg, key: str) -> bool:
    """Does a design key not swept say something about the rows: one of the seed's four
    (k, l0, c, c_rot), or another at a value other than its default?"""
    i = PARAM_COLUMNS[key]
    return key.removeprefix("design.") in SEED or params_of(cfg)[i] != PARAM_DEFAULTS[i]


def _value(v):
    """A design value as a result states it: a number as a float, a word (a kind) as is."""
    return v if isinstance(v, str) else float(v)


__all__ = ["run", "local_map", "chunk_ids", "n_chunks", "MAX_IN_MEMORY"]
