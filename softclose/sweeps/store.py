"""Sweep tables on disk: CSV, a Parquet dataset written chunk by chunk, and the manifest
that makes a sweep resumable.

- ``sweep.csv``: the whole table, written column-wise by pyarrow (full-precision numbers,
  empty cells for undefined metrics, ``true``/``false``), atomically (a temporary file
  renamed), with the finished chunks after Ctrl-C.
- ``sweep.parquet/part-NNNNNN.parquet``: one part file per finished chunk (chunk NNNNNN
  holds ids ``NNNNNN * chunk`` onwards), each written to a temporary name and renamed, so a
  part file is either whole or absent. Read it with ``pandas.read_parquet(folder)``.
- ``manifest.json``: what the sweep is -- the config, the grid or sample, the chunk size,
  the format, the softclose version and a hash of the stroke kernel. ``--resume`` compares
  it with the sweep asked for and refuses a folder of another sweep, naming what differs.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Iterator

import numpy as np

from ..errors import ConfigError
from ..files import write_text
from .chunks import columns
from ..problem import METRIC_KEYS, word_code, WORD_PARAMS, word_text
from ..jsonio import jsonable
from ..config import to_dict
from ..version import __version__
from ..simulation.kernel.library import source_bytes

MANIFEST = "manifest.json"
CSV = "sweep.csv"
DATASET = "sweep.parquet"
FORMATS = ("csv", "parquet")
#: version of the folder layout
LAYOUT = 1


def kernel_hash() -> str | None:
    """Hash of the stroke kernel's source (a changed kernel may change the numbers)."""
    try:
        return hashlib.sha256(source_bytes()).hexdigest()[:16]
    except OSError:
        return None


def manifest(cfg, space, chunk: int, fmt: str) -> dict:
    """Plain values that identify a sweep (JSON round-tripped, so they compare exactly)."""
    m = {"softclose_sweep": LAYOUT, "version": __version__, "kernel": kernel_hash(),
         "format": fmt, "chunk": int(chunk), "points": int(space.n), "space": space.spec(),
         "config": to_dict(cfg), "raw": cfg.raw}
    return json.loads(json.dumps(jsonable(m), allow_nan=False))


def write_manifest(out: Path, m: dict, complete: bool) -> Path:
    path = Path(out) / MANIFEST
    return write_text(path, json.dumps({**m, "complete": bool(complete)}, indent=1))


def read_manifest(out: Path) -> dict | None:
    path = Path(out) / MANIFEST
    if not path.exists():
        return None
    try:
        m = json.loads(path.read_text())
    except (OSError, ValueError):
        raise ConfigError(f"{path}: not a readable sweep manifest") from None
    if not isinstance(m, dict) or m.get("softclose_sweep") is None:
        raise ConfigError(f"{path}: not a sweep manifest")
    return m


def _flat(d, prefix=""):
    if isinstance(d, dict):
        out = {}
        for k, v in d.items():
            out.update(_flat(v, f"{prefix}{k}."))
        return out
    return {prefix[:-1]: d}


def differences(old: dict, new: dict) -> list[str]:
    """What differs between the manifest in a folder (``old``) and the sweep asked for."""
    out = []
    for key, what in (("softclose_sweep", "folder layout"), ("version", "softclose version"),
                      ("kernel", "stroke kernel"), ("format", "format"),
                      ("chunk", "chunk size")):
        if old.get(key) != new.get(key):
            out.append(f"{what}: {old.get(key)!r} in the folder, {new.get(key)!r} here")
    so, sn = old.get("space", {}), new.get("space", {})
    if so != sn:
        if so.get("kind") != sn.get("kind"):
            out.append(f"a {so.get('kind')} in the folder, a {sn.get('kind')} here")
        elif sn.get("kind") == "grid":
            ko = [a["key"] for a in so["axes"]]
            kn = [a["key"] for a in sn["axes"]]
            if ko != kn:
                out.append(f"grid keys {ko} in the folder, {kn} here")
            else:
                for a, b in zip(so["axes"], sn["axes"]):
                    if a != b:
                        out.append(f"grid values of {a['key']} differ ({len(a['values'])} "
                                   f"values {a['values'][0]:g}..{a['values'][-1]:g} in the "
                                   f"folder, {len(b['values'])} values "
                                   f"{b['values'][0]:g}..{b['values'][-1]:g} here)")
        else:
            for k in ("n", "sampler", "seed"):
                if so.get(k) != sn.get(k):
                    out.append(f"sample {k}: {so.get(k)!r} in the folder, {sn.get(k)!r} here")
            if so.get("ranges") != sn.get("ranges"):
                out.append(f"sample ranges: {so.get('ranges')} in the folder, "
                           f"{sn.get('ranges')} here")
    fo, fn = _flat(old.get("config", {})), _flat(new.get("config", {}))
    for k in sorted(set(fo) | set(fn)):
        if fo.get(k) != fn.get(k):
            out.append(f"config key {k}: {fo.get(k)!r} in the folder, {fn.get(k)!r} here")
    return out


# -- Arrow tables ----------------------------------------------------------------------------
def _schema(keys, words: bool = False):
    """The table's Arrow schema; ``words``: a word key's column (a spring's kind) as its
    words (CSV), not the numbers p holds (Parquet, memory)."""
    import pyarrow as pa
    fields = [pa.field("id", pa.int64())] + [
        pa.field(k, pa.string() if words and k in WORD_PARAMS else pa.float64()) for k in keys]
    fields += [pa.field(k, pa.bool_() if k == "closed" else pa.float64()) for k in METRIC_KEYS]
    fields += [pa.field("objective", pa.float64()), pa.field("feasible", pa.bool_()),
               pa.field("status", pa.string()), pa.field("reason", pa.string())]
    return pa.schema(fields)


def arrow_table(cols: dict, keys, nulls: bool = False, words: bool = False):
    """The chunk ``cols`` as a pyarrow Table (``nulls``: NaN as null, for CSV; ``words``: word
    keys as words)."""
    import pyarrow as pa
    schema = _schema(keys, words)
    if words:
        cols = as_words(cols, keys)
    arrays = [_arrow(np.asarray(cols[f.name]), f.type, nulls) for f in schema]
    return pa.Table.from_arrays(arrays, schema=schema)


def _arrow(x: np.ndarray, t, nulls: bool):
    """One column as an Arrow array, built from its buffers (``pyarrow.array`` on numpy
    input imports pandas, a fifth of a second the command line does not need)."""
    import pyarrow as pa
    n = len(x)
    if pa.types.is_string(t):
        offsets = np.zeros(n + 1, np.int32)
        try:                           # (all str and ASCII, the usual case: one join)
            values = x.tolist()
            data = "".join(values)
            if not data.isascii():
                raise TypeError
            data = data.encode("ascii")
            np.cumsum(np.fromiter(map(len, values), np.int32, count=n), out=offsets[1:])
        except TypeError:
            b = [str(v).encode() for v in x]
            np.cumsum(np.fromiter(map(len, b), np.int32, count=n), out=offsets[1:])
            data = b"".join(b)
        return pa.Array.from_buffers(t, n, [None, pa.py_buffer(offsets), pa.py_buffer(data)])
    if pa.types.is_boolean(t):
        bits = np.packbits(np.asarray(x, bool), bitorder="little")
        return pa.Array.from_buffers(t, n, [None, pa.py_buffer(bits)])
    data = np.ascontiguousarray(x, np.int64 if pa.types.is_integer(t) else np.float64)
    valid = None
    if nulls and pa.types.is_floating(t):
        nan = np.isnan(data)
        if nan.any():            # NaN as null (an empty CSV cell)
            valid = pa.py_buffer(np.packbits(~nan, bitorder="little"))
    return pa.Array.from_buffers(t, n, [valid, pa.py_buffer(data)],
                                 null_count=int(nan.sum()) if valid is not None else 0)


def _numpy(table) -> dict[str, np.ndarray]:
    import pyarrow as pa
    out = {}
    for name in table.column_names:
        col = table.column(name)
        if pa.types.is_string(col.type) or pa.types.is_large_string(col.type):
            out[name] = np.array(col.fill_null("").to_pylist(), dtype=object)
        elif pa.types.is_floating(col.type):
            out[name] = col.to_numpy(zero_copy_only=False).astype(float)
        else:
            out[name] = col.to_numpy(zero_copy_only=False)
    return out


def as_words(cols: dict, keys) -> dict:
    """``cols`` with each word key's numbers (p's codes) as its words."""
    coded = [k for k in keys if k in WORD_PARAMS]
    if not coded:
        return cols
    out = dict(cols)
    for k in coded:
        x = np.asarray(cols[k], float)
        out[k] = np.array(["" if np.isnan(v) else word_text(k, v) for v in x], dtype=object)
    return out


def as_codes(cols: dict, keys) -> dict:
    """The inverse of :func:`as_words`."""
    out = dict(cols)
    for k in keys:
        if k in WORD_PARAMS:
            out[k] = np.array([word_code(k, w) if w else np.nan for w in cols[k]], float)
    return out


# -- CSV ---------------------------------------------------------------------------------------
def write_csv(cols: dict, keys, path: Path) -> Path:
    """``sweep.csv`` column-wise (pyarrow), via a temporary file renamed into place."""
    import pyarrow.csv as pcsv
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp")
    pcsv.write_csv(arrow_table(cols, keys, nulls=True, words=True), tmp,
                   pcsv.WriteOptions(quoting_style="needed"))
    os.replace(tmp, path)
    return path


def read_csv(path: Path, keys=None) -> dict[str, np.ndarray]:
    """The columns of a ``sweep.csv`` (floats with NaN for empty cells)."""
    import pyarrow as pa
    import pyarrow.csv as pcsv
    path = Path(path)
    with open(path) as fh:
        header = [h.strip().strip('"') for h in fh.readline().rstrip("\n").split(",")]
    keys = keys if keys is not None else header[1:header.index("closed")]
    schema = _schema(keys, words=True)
    types = {f.name: f.type for f in schema}
    conv = pcsv.ConvertOptions(column_types=types, strings_can_be_null=False,
                               true_values=["true"], false_values=["false"])
    try:
        t = pcsv.read_csv(path, convert_options=conv)
    except (pa.ArrowInvalid, OSError) as exc:
        raise ConfigError(f"{path}: not a sweep table ({str(exc).splitlines()[0]})") from None
    if t.column_names != columns(keys):
        raise ConfigError(f"{path}: its columns are not those of this sweep")
    try:
        return as_codes(_numpy(t), keys)
    except ValueError as exc:
        raise ConfigError(f"{path}: {exc}") from None


def chunks_of(cols: dict, n: int, chunk: int) -> Iterator[tuple[int, dict]]:
    """The complete chunks among rows ``cols`` (a chunk missing a row is left out)."""
    ids = np.asarray(cols["id"], np.int64)
    if len(ids) == 0:
        return
    order = np.argsort(ids, kind="stable")
    ids = ids[order]
    c_of = ids // chunk
    starts = np.flatnonzero(np.r_[True, c_of[1:] != c_of[:-1]])
    ends = np.r_[starts[1:], len(ids)]
    for a, b in zip(starts, ends):
        c = int(c_of[a])
        lo, hi = c * chunk, min(n, (c + 1) * chunk)
        if b - a == hi - lo and ids[a] == lo and ids[b - 1] == hi - 1 \
                and np.all(np.diff(ids[a:b]) == 1):
            rows = order[a:b]
            yield c, {k: np.asarray(v)[rows] for k, v in cols.items()}


# -- Parquet dataset ---------------------------------------------------------------------------
def part_path(out: Path, c: int) -> Path:
    return Path(out) / DATASET / f"part-{c:06d}.parquet"


#: the columns a part file stores dictionary-encoded: the status (a few words). Every other
#: column plain: Parquet's default tries a dictionary on each and gives it up on numbers that
#: hardly repeat (or on the reasons, each its own), which took half the time of a part's
#: write and made it 12 % larger (16,384 rows of the placement sample: 16 -> 8 ms, 1.52 ->
#: 1.35 MB)
DICTIONARY = ["status"]


class ParquetSink:
    """Writes each finished chunk as one part file of the dataset ``out/sweep.parquet``."""

    def __init__(self, out: Path, keys):
        self.dir = Path(out) / DATASET
        self.dir.mkdir(parents=True, exist_ok=True)
        self.keys = list(keys)

    def write(self, c: int, cols: dict) -> Path:
        import pyarrow.parquet as pq
        path = part_path(self.dir.parent, c)
        tmp = path.with_name(f".{path.name}.tmp")
        pq.write_table(arrow_table(cols, self.keys), tmp, use_dictionary=DICTIONARY)
        os.replace(tmp, path)
        return path


def parquet_chunks(out: Path, keys, n: int, chunk: int) -> Iterator[tuple[int, dict]]:
    """The finished chunks of the dataset in ``out`` (a part that is not whole is removed
    and computed again)."""
    import pyarrow.parquet as pq
    d = Path(out) / DATASET
    if not d.is_dir():
        return
    for tmp in d.glob(".part-*.tmp"):
        tmp.unlink()
    for path in sorted(d.glob("part-*.parquet")):
        try:
            c = int(path.stem.split("-")[1])
            t = pq.read_table(path)
        except (ValueError, OSError, Exception):  # noqa: BLE001  (unreadable: recompute)
            path.unlink()
            continue
        expect = min(n, (c + 1) * chunk) - c * chunk
        if t.num_rows != expect or t.column_names != columns(keys):
            path.unlink()
            continue
        yield c, _numpy(t)


def clear(out: Path) -> None:
    """Remove the tables and part files of a finished earlier sweep in ``out``."""
    d = Path(out) / DATASET
    if d.is_dir():
        for p in list(d.glob("part-*.parquet")) + list(d.glob(".part-*.tmp")):
            p.unlink()
    for name in (CSV,):
        p = Path(out) / name
        if p.exists():
            p.unlink()


def resume_spec(folder, cfg, asked=None, config_given: bool = False, fmt: str | None = None,
                chunk: int | None = None):
    """The sweep to finish in ``folder`` (``softclose sweep --resume``): its config (the
    folder's own unless ``config_given``), its space (``asked``, a space, or the folder's),
    format and chunk, checked against the folder's manifest: a folder of another sweep is
    refused naming what differs. Returns (cfg, space, fmt, chunk, folder, manifest)."""
    from ..config import from_dict
    from .space import space_from_spec
    folder = Path(folder)
    if not folder.is_dir():
        raise ConfigError(f"--resume {folder}: no such folder")
    old = read_manifest(folder)
    if old is None:
        raise ConfigError(f"--resume {folder}: no sweep there ({MANIFEST} missing)")
    space = asked if asked is not None else space_from_spec(old["space"])
    if not config_given:
        cfg = from_dict(old["raw"])      # the folder's config unless one is given
    fmt = fmt or old["format"]
    chunk = chunk or old["chunk"]
    diff = differences(old, manifest(cfg, space, chunk, fmt))
    if diff:
        more = f" (and {len(diff) - 2} more)" if len(diff) > 2 else ""
        raise ConfigError(f"--resume {folder}: the folder holds a different sweep: "
                          f"{'; '.join(diff[:2])}{more}")
    return cfg, space, fmt, chunk, folder, old


__all__ = ["MANIFEST", "CSV", "DATASET", "FORMATS", "manifest", "write_manifest",
           "read_manifest", "resume_spec", "differences", "write_csv", "read_csv", "chunks_of",
           "ParquetSink", "parquet_chunks", "clear", "arrow_table"]
