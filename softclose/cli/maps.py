"""The maps of ``softclose sweep`` as files, drawn by other processes while this one works.

matplotlib takes about a third of a second of CPU to import, and each map about as much to
draw; the kernel and the table need this process. So the command line forks a *drawer* as
soon as it reads as a sweep (:func:`start_early`, before parsing): on the core the start-up
leaves idle, it imports matplotlib and waits. When the sweep is done the command sends it
the result (:meth:`Drawer.draw`, a pickle through a pipe, written by a thread so that the
table is written meanwhile); the drawer forks helpers so that there are as many drawing
processes as cores plus one, each drawing a share of the maps. :meth:`Drawer.finish` waits
for it and returns the maps it saved; if it failed (or where no process can be forked) the
command draws them itself (:func:`write_maps`).

The drawer runs in its own process group, writes nothing to the terminal and ignores
Ctrl-C: the command handles it, and :meth:`Drawer.cancel` (an interrupted sweep, an error,
bad input) ends the drawer and its helpers at once. An interrupted sweep draws no maps.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import select
import signal
import threading
import time
from pathlib import Path

#: seconds the command waits for its drawer before it ends it and draws the maps itself
#: (drawing takes about 0.4 s a map; matplotlib's first use on a machine builds its font
#: cache, tens of seconds)
DRAWER_TIMEOUT = 300.0


def _cores() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else \
        (os.cpu_count() or 1)


def _draw_share(res, out, names: list[str]) -> None:
    from ..figures.sweep import plot_maps, save_maps
    from .common import FIGURES
    if names:
        figs = plot_maps(res, only=names)
        if FIGURES["format"] == "png" and FIGURES["style"] is None:
            save_maps(figs, out)
        else:
            save_maps(figs, out, FIGURES["format"], FIGURES["style"])


def _draw_in_processes(res, out: Path, processes: int) -> list[str]:
    """Draw the maps of ``res`` in ``processes`` processes: this one and forked helpers
    (map ``i`` by process ``i % processes``, this one last); a helper that fails has its
    share drawn here. Returns the maps' file stems."""
    from ..figures.sweep import map_names
    names = map_names(res)
    processes = max(1, min(processes, len(names)))
    pids = [_fork(lambda part=part: _draw_share(res, out, names[part::processes]))
            for part in range(processes - 1)]
    try:
        _draw_share(res, out, names[processes - 1::processes])
    finally:
        failed = [part for part, pid in enumerate(pids) if os.waitpid(pid, 0)[1] != 0]
    for part in failed:
        _draw_share(res, out, names[part::processes])
    return names


def _fork(work) -> int:
    """Fork a child that runs ``work()`` and leaves: exit status 0 when it returned, 1 when
    it raised (its parent then does that work itself). Returns the child's pid."""
    pid = os.fork()
    if pid == 0:
        code = 1
        try:
            work()
            code = 0
        except BaseException:  # noqa: BLE001  (reported by the exit status)
            pass
        finally:
            os._exit(code)
    return pid


class Drawer:
    """A process forked early that imports matplotlib, then draws the maps it is sent."""

    def __init__(self, pid: int, fd: int, back: int):
        self.pid, self._fd, self._back = pid, fd, back
        self._writer: threading.Thread | None = None

    @classmethod
    def start(cls) -> "Drawer | None":
        """Fork the drawer; None where there is no ``fork`` or a single core (the command
        then draws the maps itself)."""
        if not hasattr(os, "fork") or _cores() < 2:
            return None
        r, w = os.pipe()                               # the result, to the drawer
        br, bw = os.pipe()                             # the stems of the maps it saved, back

        def drawer():
            os.close(w)
            os.close(br)
            os.setpgid(0, 0)                           # its own group: cancel() ends it all
            signal.signal(signal.SIGINT, signal.SIG_IGN)
            quiet = os.open(os.devnull, os.O_WRONLY)   # (not a foreground process: it never
            os.dup2(quiet, 1)                          # writes to the terminal)
            os.dup2(quiet, 2)
            from ..figures import sweep  # noqa: F401  (matplotlib, while the kernel runs)
            with os.fdopen(r, "rb") as f:
                data = f.read()
            if data:                                   # (none: nothing to draw)
                res, out, figures = pickle.loads(data)
                from .common import FIGURES
                FIGURES.update(figures)          # (forked before the options were read)
                names = _draw_in_processes(res, Path(out), _cores() + 1)
                with os.fdopen(bw, "w") as f:
                    f.write("\n".join(names))
        try:
            pid = _fork(drawer)
        except OSError:
            for fd in (r, w, br, bw):
                os.close(fd)
            return None
        os.close(r)
        os.close(bw)
        with contextlib.suppress(OSError):
            os.setpgid(pid, pid)                       # (set on both sides: no race)
        return cls(pid, w, br)

    def draw(self, res, out: Path) -> None:
        """Send the result; the drawer starts drawing as soon as it has read it (a thread
        writes it, so the caller goes on meanwhile)."""
        from .common import FIGURES
        data = pickle.dumps((res, str(out), dict(FIGURES)), protocol=pickle.HIGHEST_PROTOCOL)
        fd, self._fd = self._fd, None

        def send():
            try:
                with os.fdopen(fd, "wb") as f:
                    f.write(data)
            except OSError:                            # the drawer is gone: finish() says so
                pass
        self._writer = threading.Thread(target=send, name="softclose-maps", daemon=True)
        self._writer.start()

    def finish(self, timeout: float = DRAWER_TIMEOUT) -> list[str] | None:
        """Wait for the drawer: the stems of the maps it saved; None if it failed or took
        longer than ``timeout`` seconds (then it is ended)."""
        deadline = time.monotonic() + timeout
        if self._writer is not None:
            self._writer.join(timeout)
        self._close()
        back, self._back = self._back, None
        chunks: list[bytes] = []
        late = False
        if back is not None:
            try:
                while True:                            # its answer, then end of file
                    left = deadline - time.monotonic()
                    if left <= 0 or not select.select([back], [], [], left)[0]:
                        late = True
                        break
                    data = os.read(back, 65536)
                    if not data:
                        break
                    chunks.append(data)
            finally:
                os.close(back)
        if late:                                       # too long: end it (and its helpers)
            self.cancel()
            return None
        ok = self._wait()
        names = b"".join(chunks).decode()
        return [n for n in names.split("\n") if n] if ok else None

    def cancel(self) -> None:
        """Nothing (more) to draw -- interrupted, an error, or a command that draws no maps:
        the drawer and its helpers leave at once."""
        self._close()
        if self._back is not None:
            with contextlib.suppress(OSError):
                os.close(self._back)
            self._back = None
        if self.pid is not None:
            with contextlib.suppress(OSError):
                os.killpg(self.pid, signal.SIGTERM)
        self._wait()

    def _close(self) -> None:
        fd, self._fd = self._fd, None
        if fd is not None:                             # nothing was sent: it leaves
            with contextlib.suppress(OSError):
                os.close(fd)

    def _wait(self) -> bool:
        if self.pid is None:
            return False
        try:
            status = os.waitpid(self.pid, 0)[1]
        except ChildProcessError:
            status = 1
        self.pid = None
        return status == 0


#: the drawer forked by :func:`start_early`, until the command takes it
_early: Drawer | None = None


def start_early(argv: list[str]) -> None:
    """Fork the drawer as soon as the command line reads as a sweep that draws maps (before
    the arguments are even parsed: more of matplotlib's import overlaps the start-up)."""
    global _early
    if argv[:1] == ["sweep"] and not {"-h", "--help", "--optimise"} & set(argv):
        _early = Drawer.start()


def take_drawer() -> Drawer | None:
    """The drawer of this command: the one forked early, else a new one."""
    global _early
    drawer, _early = _early, None
    return drawer if drawer is not None else Drawer.start()


def cancel_early() -> None:
    """End a drawer forked early that the command did not take (bad input, an error)."""
    global _early
    drawer, _early = _early, None
    if drawer is not None:
        drawer.cancel()


def write_maps(res, out: Path, parallel: bool = True) -> list[Path]:
    """Draw and save the maps of ``res`` in ``out`` here (in forked processes when
    ``parallel``: as many as cores plus this one)."""
    processes = _cores() + 1 if parallel and hasattr(os, "fork") else 1
    from .common import figure_path
    return [figure_path(Path(out) / f"{n}.png")
            for n in _draw_in_processes(res, Path(out), processes)]


__all__ = ["Drawer", "write_maps", "start_early", "take_drawer", "cancel_early"]
