"""Spring kinds solved side by side: each kind after the first in a forked process.

:func:`~softclose.optimiser.optimiser.optimise` solves one multistart per spring kind
(``optimise.spring_kinds``), then polishes and verifies the best. The kinds' multistarts
are independent, so on a machine with two or more cores every kind after the first is
solved in a child process forked once the NLP is loaded -- the child inherits the model,
the tables and the compiled NLP, nothing is built again -- while this process solves the
first. With two kinds, the child first solves the last third of the first kind's starts
(this process polishes and verifies after its starts: the work is then about even) and
sends them. A child sends back its kind's unpolished answer and waits: told to finish, it
polishes and verifies that answer and sends the result; told to stop, it exits. This
process polishes and verifies the first kind as soon as its starts are in, without waiting
for the others (the best kind is usually the first listed; when it is not, that work was
done while the others were still solving).

The numbers are those of solving the kinds one after the other: the same code on the same
inputs, in another process. The kinds are solved one after the other instead where fork is
not available, with one core, with other threads running (a notebook's kernel: forking a
threaded process is unsafe), inside a child already, or with ``SOFTCLOSE_SIDE_BY_SIDE=0``.
A child that fails or dies is not fatal: its kind is solved here after all. Ctrl-C stops
the children (they ignore SIGINT; the parent ends them).
"""

from __future__ import annotations

import os
import pickle
import signal
import struct
import threading
import time

#: the environment variable that turns side-by-side solving off ("0")
ENV = "SOFTCLOSE_SIDE_BY_SIDE"
_IN_CHILD = False


def available(n_kinds: int) -> bool:
    """Whether ``n_kinds`` kinds would be solved side by side here."""
    return (n_kinds >= 2 and hasattr(os, "fork") and not _IN_CHILD
            and os.environ.get(ENV, "1") != "0" and (os.cpu_count() or 1) >= 2
            and threading.active_count() == 1)


def _send(fd: int, obj) -> None:
    data = pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
    view = memoryview(struct.pack("<Q", len(data)) + data)
    while view:
        view = view[os.write(fd, view):]


def _recv(fd: int):
    def exactly(n: int) -> bytes:
        out = bytearray()
        while len(out) < n:
            chunk = os.read(fd, n - len(out))
            if not chunk:
                raise EOFError("the kind's process ended without an answer")
            out += chunk
        return bytes(out)
    (n,) = struct.unpack("<Q", exactly(8))
    return pickle.loads(exactly(n))


class KindProcess:
    """One kind's multistart in a forked child: ``solve()`` -> ``(raw, later)`` there.

    ``before``: work the child does first, for the parent (some of the first kind's starts),
    returned by :meth:`before`.
    :meth:`raw` returns the kind's unpolished result (or raises what the child raised);
    :meth:`finish` asks the child to polish and verify it and returns that result;
    :meth:`close` stops the child (always call it: ``with`` does).
    """

    def __init__(self, solve, before=None):
        global _IN_CHILD
        up_r, up_w = os.pipe()        # child -> parent
        down_r, down_w = os.pipe()    # parent -> child
        pid = os.fork()
        if pid == 0:                  # the child: answer, wait, finish or stop
            _IN_CHILD = True
            code = 0
            try:
                signal.signal(signal.SIGINT, signal.SIG_IGN)
                os.close(up_r)
                os.close(down_w)
                if before is not None:      # work for the parent first
                    try:
                        _send(up_w, ("before", before()))
                    except Exception as exc:  # noqa: BLE001  (sent to the parent)
                        _send(up_w, ("error", exc))
                try:
                    raw, later = solve()
                    _send(up_w, ("raw", raw))
                except Exception as exc:      # noqa: BLE001  (sent to the parent)
                    _send(up_w, ("error", exc))
                    later = None
                if later is not None and _recv(down_r) == "finish":
                    try:
                        _send(up_w, ("done", later()))
                    except Exception as exc:  # noqa: BLE001
                        _send(up_w, ("error", exc))
            except BaseException:             # noqa: BLE001  (the parent's EOF tells)
                code = 1
            finally:
                os._exit(code)
        os.close(up_w)
        os.close(down_r)
        self.pid, self._up, self._down = pid, up_r, down_w
        self._closed = False

    def _answer(self, tag: str):
        kind, value = _recv(self._up)
        if kind == "error":
            raise value
        assert kind == tag, (kind, tag)
        return value

    def before(self):
        """What ``before()`` returned in the child (asked before :meth:`raw`)."""
        return self._answer("before")

    def raw(self):
        """The kind's unpolished result (what ``solve()`` returned first)."""
        return self._answer("raw")

    def finish(self):
        """The kind's polished and verified result (the child's ``later()``)."""
        _send(self._down, "finish")
        return self._answer("done")

    def close(self, wait: float = 1.0) -> None:
        """Stop the child: told to stop, it exits at once when it is waiting; one still
        working after ``wait`` seconds (or at once with ``wait=0``: Ctrl-C, an error
        here) is killed."""
        if self._closed:
            return
        self._closed = True
        try:
            _send(self._down, "stop")
        except OSError:
            pass
        for fd in (self._up, self._down):
            try:
                os.close(fd)
            except OSError:
                pass
        try:
            deadline = time.monotonic() + wait
            while True:
                pid, _ = os.waitpid(self.pid, os.WNOHANG)
                if pid:
                    return
                if time.monotonic() >= deadline:
                    os.kill(self.pid, signal.SIGKILL)
                    os.waitpid(self.pid, 0)
                    return
                time.sleep(0.001)
        except (ChildProcessError, ProcessLookupError):
            pass

    def __enter__(self):
        return self

    def __exit__(self, exc_type, *exc):
        self.close(wait=0.0 if exc_type is not None else 1.0)



def shared_starts(n: int) -> tuple:
    """Which of the first kind's ``n`` starts the other kind's process solves (before its
    own): the last third -- this process polishes and verifies after its starts, about as
    much work as two starts, and the other kinds' starts cost about as much as the first's."""
    return tuple(range(n - n // 3, n))


def ahead(later):
    """``later`` done now, kept for when it is asked for (an exception too: raised then)."""
    try:
        done = later()
    except Exception as exc:        # noqa: BLE001  (raised where the serial run raises it)
        err = exc                   # (the name of an except clause is deleted at its end)

        def again():
            raise err
        return again
    return lambda: done


__all__ = ["KindProcess", "available", "ENV", "shared_starts", "ahead"]
