"""The one way in and the one way out for the files softclose reads and writes.

**In** (:func:`read_text`): configs, design files, catalogs and fit data are read as UTF-8
text, a byte order mark (as some Windows editors write one) accepted and dropped. A file
that is missing, a folder, unreadable, binary or in another encoding is refused with one
line naming it and saying what to do (:class:`~softclose.errors.ConfigError`, exit 2).

**Out** (:func:`check_targets`, :func:`write_text`, :func:`write_with`): the files a command
will write are checked before its work starts -- a folder where a file must go, or a file
that cannot be replaced (read-only), is refused with one line (exit 2), so that nothing is
computed and then lost. Each file is written whole or not at all: into a temporary file
in the same folder (``.NAME.PID.tmpSUFFIX``), then renamed over the old one
(``os.replace``), so that a failure or an interrupt midway leaves the earlier file whole and
no partial file; the temporary file is removed on any failure.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

from ..errors import ConfigError

#: the bytes read to tell a binary file from text (a NUL byte among them: binary)
SNIFF_BYTES = 8192


def _why(exc: OSError) -> str:
    return exc.strerror or type(exc).__name__


def read_text(path, name: str | None = None, kind: str = "a text file") -> str:
    """The text of the file ``path`` (UTF-8; a leading byte order mark dropped).

    Refused with one line (ConfigError) naming the file as ``name`` (default: the path)
    and saying what to do: no such file, a folder, no permission, binary content, not UTF-8
    (where: line and column of the first byte that is not). ``kind`` says what was expected
    ("a TOML config file", "a CSV file").
    """
    name = str(path) if name is None else name
    p = Path(path)
    try:
        data = p.read_bytes()
    except FileNotFoundError:
        raise ConfigError(f"{name}: no such file (expected {kind})") from None
    except IsADirectoryError:
        raise ConfigError(f"{name}: is a folder, expected {kind}") from None
    except PermissionError as exc:
        raise ConfigError(f"{name}: cannot read ({_why(exc)}); check the file's "
                          "permissions") from None
    except OSError as exc:
        raise ConfigError(f"{name}: cannot read ({_why(exc)})") from None
    if b"\0" in data[:SNIFF_BYTES]:
        raise ConfigError(f"{name}: binary content, not text; expected {kind}")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        start = exc.start + (3 if data.startswith(b"\xef\xbb\xbf") else 0)
        head = data[:start]
        line = head.count(b"\n") + 1
        column = start - (head.rfind(b"\n") + 1) + 1
        raise ConfigError(f"{name}: not UTF-8 text (byte 0x{data[start]:02x} at line {line}, "
                          f"column {column}); save it as UTF-8") from None


# -- writing ----------------------------------------------------------------------------------

def check_targets(folder, names, option: str = "--out") -> None:
    """Refuse (ConfigError, one line) before any work: a name in ``names`` (paths relative
    to ``folder``) that is a folder where a file goes, lies under a file, or is a file that
    cannot be replaced (read-only). A name ending in ``/`` is a folder the command makes."""
    folder = Path(folder)
    for name in names:
        is_folder = str(name).endswith("/")
        path = folder / name
        for parent in reversed(path.relative_to(folder).parents[:-1]):
            if (folder / parent).exists() and not (folder / parent).is_dir():
                raise ConfigError(f"{option} {folder}: {folder / parent} is a file where "
                                  "softclose makes a folder; remove or rename it")
        if is_folder:
            if path.exists() and not path.is_dir():
                raise ConfigError(f"{option} {folder}: {path} is a file where softclose makes "
                                  "a folder; remove or rename it")
            continue
        if path.is_dir():
            raise ConfigError(f"{option} {folder}: {path} is a folder where softclose writes "
                              "a file; remove or rename it, or choose another folder")
        if path.exists() and not os.access(path, os.W_OK):
            raise ConfigError(f"{option} {folder}: {path} is read-only and would be replaced; "
                              "make it writable, remove it, or choose another folder")


def temporary(path) -> Path:
    """The temporary file of this process beside ``path`` (its suffix kept: writers such as
    matplotlib and Pillow choose the format by it)."""
    path = Path(path)
    return path.with_name(f".{path.stem}.{os.getpid()}.tmp{path.suffix}")


@contextlib.contextmanager
def replacing(path):
    """A block that writes the temporary file it yields; when the block ends normally, that
    file replaces ``path`` (``os.replace``); on any failure or interrupt it is removed and
    ``path`` is left as it was. A write that fails (a full disk, a folder put in the way
    meanwhile) is one line naming the file (ConfigError)."""
    path = Path(path)
    tmp = temporary(path)
    try:
        yield tmp
        os.replace(tmp, path)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            tmp.unlink()
        if isinstance(exc, OSError):
            raise ConfigError(f"{path}: cannot write ({_why(exc)}); nothing was written "
                              "there") from None
        raise


def write_with(path, writer) -> Path:
    """``writer(tmp)`` writes the file, which then replaces ``path`` whole
    (:func:`replacing`); ``path``."""
    with replacing(path) as tmp:
        writer(tmp)
    return Path(path)


def write_text(path, text: str) -> Path:
    """Write ``text`` (UTF-8) as ``path``, whole or not at all; ``path``."""
    return write_bytes(path, text.encode("utf-8"))


def write_bytes(path, data: bytes) -> Path:
    """Write ``data`` as ``path``, whole or not at all; ``path``."""
    with replacing(path) as tmp:
        with open(tmp, "wb") as f:
            f.write(data)
    return Path(path)


__all__ = ["read_text", "check_targets", "replacing", "write_with", "write_text",
           "write_bytes", "temporary"]
