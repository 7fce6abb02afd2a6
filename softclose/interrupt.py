"""Ctrl-C that ends a command wherever it lands: one line, exit code 130.

Python turns SIGINT into :class:`KeyboardInterrupt` between bytecodes. Inside a compiled
solver that checks for signals, CasADi catches that exception and carries on: an Ipopt solve
ends with ``NonIpopt_Exception_Thrown`` and a ``WARNING("KeyboardInterruptException")`` line
on stderr, a CVODES integration fails with a RuntimeError after printing ``rhs failed:
KeyboardInterrupt``. Left alone, a multistart would run its remaining starts, and a reference
simulation would be reported as a numerical failure (exit 3).

:func:`guard` (the command line runs every command inside it) therefore

- remembers that Ctrl-C was pressed (:func:`interrupted`), so that an error raised because of
  it is reported as the interruption it is;
- sees when the KeyboardInterrupt was raised inside a CasADi call (the frame the signal
  handler runs in belongs to CasADi), and then sends SIGINT again as soon as the main thread
  is back in Python code, or after :data:`RESEND` seconds in another CasADi call (which a
  signal ends at its next iteration) -- only then, so that an interrupt that propagates
  normally is never raised a second time into the clean-up it runs (``finally`` blocks that
  keep what was finished);
- while an interrupt is pending, drops what the solvers write to ``sys.stderr``, so that the
  only line left is the command line's own.

:func:`check` lets a long loop stop at a safe point (between solves, between chunks);
:func:`sigint_handler` swaps the SIGINT handler for a block (the sweep wants Python's plain
KeyboardInterrupt, Dask's local worker processes are started with SIGINT ignored).
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
import time

#: seconds a CasADi call may run on after a swallowed Ctrl-C before SIGINT is sent into it
RESEND = 0.2
#: seconds between looks at where the main thread is, while a swallowed interrupt is pending
POLL = 0.002
_CASADI = os.path.join("casadi", "casadi.py")

_pending = threading.Event()     # Ctrl-C was pressed under the current guard
_swallowed = threading.Event()   # ... and the last KeyboardInterrupt was raised into CasADi
_quiet = threading.Event()       # the guarded command has ended


def interrupted() -> bool:
    """Was Ctrl-C pressed while the last :func:`guard` was active?"""
    return _pending.is_set()


def check() -> None:
    """Raise KeyboardInterrupt if Ctrl-C was pressed (a solver may have swallowed it)."""
    if _pending.is_set() and not _quiet.is_set():
        raise KeyboardInterrupt


def _in_casadi(frame) -> bool:
    return frame is not None and frame.f_code.co_filename.endswith(_CASADI)


class _QuietStderr:
    """sys.stderr that drops writes once an interrupt is pending (solver noise)."""

    def __init__(self, stream):
        self._stream = stream

    def write(self, s):
        if _pending.is_set():
            return len(s)
        return self._stream.write(s)

    def __getattr__(self, name):
        return getattr(self._stream, name)


@contextlib.contextmanager
def sigint_handler(handler):
    """Handle SIGINT with ``handler`` (a function, ``signal.SIG_IGN``, ``signal.SIG_DFL`` or
    ``signal.default_int_handler``) inside the block, then restore the handler it replaced.

    A no-op outside the main thread: only the main thread may set signal handlers (and only
    it receives signals), so a block run in another thread keeps whatever is there.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


@contextlib.contextmanager
def guard():
    """Run a command so that Ctrl-C ends it even inside a compiled solver (module docstring).

    A no-op outside the main thread (only the main thread receives signals).
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    for flag in (_pending, _swallowed, _quiet):
        flag.clear()
    stop = threading.Event()
    main_id = threading.main_thread().ident
    resender: list[threading.Thread] = []

    def resend():
        frame, since = None, 0.0
        while not stop.wait(POLL):
            if not _swallowed.is_set():
                continue
            top = sys._current_frames().get(main_id)
            if _in_casadi(top):
                if top is not frame:          # a new CasADi call: give it RESEND seconds
                    frame, since = top, time.monotonic()
                if time.monotonic() - since < RESEND:
                    continue
            frame = None
            _swallowed.clear()
            os.kill(os.getpid(), signal.SIGINT)

    def handler(signum, frame):
        if _quiet.is_set():                    # the command has ended: a late re-send
            return
        _pending.set()
        if _in_casadi(frame):
            _swallowed.set()
            if not resender:
                t = threading.Thread(target=resend, name="softclose-interrupt", daemon=True)
                resender.append(t)
                t.start()
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGINT, handler)
    stderr = sys.stderr
    sys.stderr = _QuietStderr(stderr)
    try:
        yield
    finally:
        _quiet.set()
        stop.set()
        for t in resender:
            t.join()
        # a re-sent signal may be tripped but not handled yet: let it reach the quiet
        # handler (the loop's backward jumps run pending handlers) before restoring
        for _ in range(3):
            pass
        signal.signal(signal.SIGINT, previous)
        if isinstance(sys.stderr, _QuietStderr):
            sys.stderr = stderr


__all__ = ["guard", "interrupted", "check", "sigint_handler", "RESEND"]
