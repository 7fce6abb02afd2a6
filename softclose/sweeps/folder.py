"""A sweep written to a folder (what ``softclose sweep --out DIR`` does): the manifest first,
then the chunks (CSV at the end, or Parquet parts as they finish), then the maps, and the
manifest marked complete. Ctrl-C keeps every finished chunk; the folder is resumed with
``done`` (the chunks on disk). The maps are drawn in this process after the table, one after
the other (matplotlib is imported in a thread while the kernel runs): nothing is left
running when it returns, and an interrupted sweep draws no maps (resuming it does)."""

from __future__ import annotations

import contextlib
import shlex
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

from . import store
from .run import _no_interrupt
from .run import run as run_sweep


@dataclass(frozen=True)
class FolderSweep:
    """A sweep written to ``out``: the result, the files, the seconds of each stage,
    whether it was interrupted (then ``resume`` is the command that finishes it) and, on a
    Dask cluster that stopped working, what was lost."""

    result: object
    out: Path
    fmt: str
    files: tuple
    stages: dict
    interrupted: bool
    resume: str | None = None
    lost: object = field(default=None, repr=False)

    def to_json(self) -> dict:
        payload = self.result.to_json()
        payload.update(stages=self.stages, format=self.fmt, out=str(self.out),
                       resume=self.resume, files=[str(f) for f in self.files])
        payload["interrupted"] = self.interrupted
        if self.lost is not None:
            payload["error"] = self.error
        return payload

    @property
    def error(self) -> str | None:
        if self.lost is None:
            return None
        return f"{self.lost}; the finished chunks are kept, resume with: {self.resume}"

    def text(self) -> str:
        from .text import sweep_text
        return sweep_text(self.result, self.to_json(), list(self.files), self.resume)


def write_maps(res, out: Path, figure_format: str = "png",
               figure_style: str | None = None) -> list[Path]:
    """Draw and save the maps of ``res`` in ``out`` (this process, one after the other) as
    ``figure_format`` in ``figure_style``; their paths."""
    from ..present.figures.sweep import map_names, plot_maps, save_maps
    names = map_names(res)
    if names:
        figs = plot_maps(res, only=names)
        if figure_format == "png" and figure_style is None:
            save_maps(figs, out)
        else:
            save_maps(figs, out, figure_format, figure_style)
    return [Path(out) / f"{n}.{figure_format}" for n in names]


def _import_outputs(parquet: bool) -> None:
    with contextlib.suppress(Exception):
        if parquet:
            import pyarrow.parquet  # noqa: F401
        else:
            import pyarrow.csv  # noqa: F401
        from ..present.figures import sweep  # noqa: F401  (matplotlib)


def sweep_to_folder(cfg, space, out, fmt: str, chunk: int, manifest: dict, *,
                    resume: bool = False, replace: bool = False, mapper_context=None,
                    threads: int | None = None, progress: bool = False,
                    figure_format: str = "png", figure_style: str | None = None
                    ) -> FolderSweep:
    """Run the sweep of ``space`` into the folder ``out`` (which exists): ``fmt`` "csv" or
    "parquet", ``chunk`` designs a chunk, ``manifest`` (:func:`store.manifest`) written
    first; ``resume``: only the chunks not on disk; ``replace``: a finished earlier sweep
    there is cleared; ``mapper_context``: a context manager giving the chunk mapper (a Dask
    cluster), entered before anything is written."""
    out = Path(out)
    t0 = time.perf_counter()
    parquet = fmt == "parquet"
    keys = list(space.keys)
    done = ()
    if resume:
        if parquet:
            done = store.parquet_chunks(out, keys, space.n, chunk)
        elif (out / store.CSV).exists():
            done = store.chunks_of(store.read_csv(out / store.CSV, keys), space.n, chunk)
    # the table's library and matplotlib are imported while the kernel runs (its threads
    # leave the interpreter free); the maps are drawn here once the table is written
    prefetch = threading.Thread(target=_import_outputs, args=(parquet,),
                                name="softclose-imports", daemon=True)
    prefetch.start()
    try:
        # connected (a Dask cluster answers): only now is the folder written
        with (mapper_context or contextlib.nullcontext(None)) as mapper:
            if replace:
                store.clear(out)         # a finished earlier sweep is replaced
            store.write_manifest(out, manifest, complete=False)
            sink = store.ParquetSink(out, keys) if parquet else None
            res = run_sweep(cfg, space, progress=progress, threads=threads, chunk=chunk,
                            keep=not parquet, sink=sink, done=done, mapper=mapper,
                            dataset=str(out / store.DATASET) if parquet else None)
    finally:
        prefetch.join()                  # no import half done
    stages = dict(res.stages)
    files: list[Path] = []
    interrupted = res.interrupted
    try:
        if parquet:
            files.append(out / store.DATASET)
        else:
            tw = time.perf_counter()
            # the finished chunks are written whatever happens (a second Ctrl-C waits)
            with _no_interrupt(reraise=not interrupted):
                files.append(store.write_csv(res.columns, keys, out / store.CSV))
            stages["csv"] = time.perf_counter() - tw
        if not interrupted:
            tm = time.perf_counter()
            if res.computed > 0:
                files += write_maps(res, out, figure_format, figure_style)
            store.write_manifest(out, manifest, complete=True)
            stages["maps"] = time.perf_counter() - tm
    except KeyboardInterrupt:            # the table is whole; resuming draws the maps
        interrupted = True
    stages["total"] = time.perf_counter() - t0
    files.append(out / store.MANIFEST)
    again = f"softclose sweep --resume {shlex.quote(str(out))}" if interrupted else None
    return FolderSweep(res, out, fmt, tuple(files), stages, interrupted, again,
                       getattr(mapper, "lost", None))


__all__ = ["FolderSweep", "sweep_to_folder", "write_maps"]
