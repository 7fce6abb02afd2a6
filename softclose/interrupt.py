"""Ctrl-C (or SIGTERM) that ends a command wherever it lands: one line, exit code 130.

Python turns SIGINT into :class:`KeyboardInterrupt` between bytecodes. Raised inside a
CasADi call (a compiled solver that checks for signals, or Python code CasADi calls back),
CasADi catches it and carries on or reports an error of its own. So the command line runs
every command inside :func:`guard`, whose handler of SIGINT and SIGTERM (a supervisor's or
a job scheduler's request to stop, sent to the process alone: handled as Ctrl-C is, so that
what the command started -- a C compiler -- is ended and its files removed)

- notes that Ctrl-C was pressed (:func:`interrupted`, a flag), so that an error raised
  because of it is reported as the interruption it is;
- raises KeyboardInterrupt at once in plain Python code, as Python's own handler does;
- inside a solver call (:func:`solving`: an Ipopt solve, a CVODES integration) only notes
  it: Ipopt stops at its next iteration through the documented ``iteration_callback``
  option of ``nlpsol`` (:func:`ipopt_options`: a :class:`casadi.Callback` returning 1 once
  the flag is set; the solve ends with ``User_Requested_Stop``), a CVODES call ends its few
  milliseconds, and the KeyboardInterrupt is raised when the call returns;
- while an interrupt is pending, drops what is written to ``sys.stderr``, so that the only
  line left is the command line's own; and notes whether the last line written there is
  unfinished (a progress line: :func:`line_open`), so that line starts on a new line.

:func:`check` lets a long loop stop at a safe point (between solves, between chunks);
:func:`sigint_handler` swaps the SIGINT handler for a block (the sweep wants Python's plain
KeyboardInterrupt, Dask's local worker processes are started with SIGINT ignored).
"""

from __future__ import annotations

import contextlib
import signal
import sys
import threading
from typing import NoReturn

_pending = threading.Event()     # Ctrl-C was pressed under the current guard
_quiet = threading.Event()       # the guarded command has ended
_depth = [0]                     # solver calls the main thread is in (:func:`solving`)
_signal = ["Ctrl-C"]             # what interrupted the command
_tail = ["\n"]                   # the last character written to stderr under the guard


def signal_name() -> str:
    """What interrupted the last guarded command: "Ctrl-C" (SIGINT) or "SIGTERM"."""
    return _signal[0]


def line_open() -> bool:
    """Whether the last line written to stderr under the last :func:`guard` is unfinished
    (a progress line, ``building the NLP ... ``): a message then starts on a new line."""
    return _tail[0] != "\n"


def interrupted() -> bool:
    """Was Ctrl-C pressed while the last :func:`guard` was active?"""
    return _pending.is_set()


def stop_requested() -> bool:
    """Should a solver stop now (Ctrl-C pressed under a guard that is still active)?"""
    return _pending.is_set() and not _quiet.is_set()


def check() -> None:
    """Raise KeyboardInterrupt if Ctrl-C was pressed (noted during a solver call)."""
    if _pending.is_set() and not _quiet.is_set():
        raise KeyboardInterrupt


class _Solving:
    """The context of :func:`solving` (a class: entered thousands of times a command)."""

    __slots__ = ("main",)

    def __enter__(self):
        self.main = threading.current_thread() is threading.main_thread()
        if self.main:
            _depth[0] += 1
        return self

    def __exit__(self, kind, value, tb):
        if self.main:
            _depth[0] -= 1
            if kind is None:
                check()
        return False


def solving() -> _Solving:
    """A block that calls a CasADi solver (Ipopt, CVODES): a Ctrl-C inside it is noted, not
    raised into CasADi (which would swallow it); Ipopt stops at its next iteration
    (:func:`ipopt_options`), and KeyboardInterrupt is raised as the block ends."""
    return _Solving()


_callbacks: dict = {}


def ipopt_options(nx: int, ng: int, np_: int) -> dict:
    """The ``nlpsol`` options that stop Ipopt at its next iteration once Ctrl-C is pressed:
    ``iteration_callback``, a :class:`casadi.Callback` of an NLP with ``nx`` variables,
    ``ng`` constraints and ``np_`` parameters that returns 1 (stop) when
    :func:`stop_requested`. Kept for the process (a solver holds it; one per size)."""
    key = (int(nx), int(ng), int(np_))
    cb = _callbacks.get(key)
    if cb is None:
        cb = _callbacks[key] = _stopper(*key)
    return {"iteration_callback": cb}


def _stopper(nx: int, ng: int, np_: int):
    import casadi as ca

    sizes = {"x": nx, "f": 1, "g": ng, "lam_x": nx, "lam_g": ng, "lam_p": np_}

    class StopOnCtrlC(ca.Callback):
        """Ipopt's iteration callback: 1 (stop) once Ctrl-C was pressed, else 0."""

        def __init__(self):
            ca.Callback.__init__(self)
            self.construct(f"softclose_stop_{nx}_{ng}_{np_}", {})

        def get_n_in(self):
            return ca.nlpsol_n_out()

        def get_n_out(self):
            return 1

        def get_name_in(self, i):
            return ca.nlpsol_out(i)

        def get_name_out(self, i):
            return "stop"

        def get_sparsity_in(self, i):
            return ca.Sparsity.dense(sizes[ca.nlpsol_out(i)], 1)

        def get_sparsity_out(self, i):
            return ca.Sparsity.dense(1, 1)

        def eval(self, arg):
            return [1.0 if stop_requested() else 0.0]

    return StopOnCtrlC()


class _QuietStderr:
    """sys.stderr that drops writes once an interrupt is pending (solver noise)."""

    def __init__(self, stream):
        self._stream = stream

    def write(self, s):
        if _pending.is_set():
            return len(s)
        if s:
            _tail[0] = s[-1]
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


def _handler(signum, frame):
    if _quiet.is_set():                    # the command has ended
        return
    if not _pending.is_set():
        _signal[0] = "SIGTERM" if signum == signal.SIGTERM else "Ctrl-C"
    _pending.set()
    if _depth[0] == 0:                     # plain Python: at once, as Python's own handler
        raise KeyboardInterrupt
    # inside a solver call: noted; the solver stops (iteration callback), and the
    # KeyboardInterrupt is raised when the call returns (:func:`solving`)


def handle_until_exit() -> None:
    """For a program that runs one guarded command and exits (the command line): SIGINT and
    SIGTERM go to the guard's handler from now on, also once the command has ended, so that
    a signal landing while the program prints its outcome or exits is ignored -- the exit
    code stays the command's -- instead of killing it or raising a traceback there."""
    if threading.current_thread() is threading.main_thread():
        _quiet.clear()
        signal.signal(signal.SIGINT, _handler)
        signal.signal(signal.SIGTERM, _handler)


def exit_program(code: int) -> NoReturn:
    """End the program (the command line) with exit code ``code``, whatever was interrupted.

    CPython remembers a KeyboardInterrupt raised inside code that ``exec()`` or ``eval()`` ran
    from a string -- the methods a dataclass generates while a module is imported -- even when
    the command caught it, and then ends the program by SIGINT instead of with its exit code
    (a Ctrl-C during the first imports exited -2, not 130). So the command line ends here: the
    exit functions run (``atexit``, as at a normal exit), the streams are flushed, and the
    process exits with ``code``. The command has ended every thread and process it started.
    """
    import atexit
    import os
    try:
        atexit._run_exitfuncs()
    finally:
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except Exception:       # a closed pipe: nothing more can be said there
                pass
        os._exit(int(code))


@contextlib.contextmanager
def guard():
    """Run a command so that Ctrl-C ends it even inside a compiled solver (module docstring).

    A no-op outside the main thread (only the main thread receives signals).
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _pending.clear()
    _quiet.clear()
    _depth[0] = 0
    _signal[0], _tail[0] = "Ctrl-C", "\n"
    previous = signal.signal(signal.SIGINT, _handler)
    previous_term = signal.signal(signal.SIGTERM, _handler)
    stderr = sys.stderr
    sys.stderr = _QuietStderr(stderr)
    try:
        yield
    finally:
        _quiet.set()
        signal.signal(signal.SIGINT, previous)
        signal.signal(signal.SIGTERM, previous_term)
        if isinstance(sys.stderr, _QuietStderr):
            sys.stderr = stderr


__all__ = ["guard", "interrupted", "check", "solving", "ipopt_options", "stop_requested",
           "sigint_handler", "signal_name", "line_open", "handle_until_exit", "exit_program"]
