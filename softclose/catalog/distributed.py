"""``select`` on a Dask cluster: the chunks of pairs as Dask tasks.

The same connection as a sweep's (:func:`softclose.sweeps.distributed.connect`: ``local:N``
or a scheduler address) and the same streaming of tasks
(:func:`softclose.sweeps.distributed.map_tasks`). What travels is plain values: the config
as a dict, the box (numpy arrays) and the catalog entries (frozen dataclasses); each worker
builds and caches its own simulators. The results are the local run's numbers.
"""

from __future__ import annotations

import contextlib
from ..sweeps.distributed import ClusterLost, connect, map_tasks
from .ranking import screen_chunk
from ..config.load import from_dict


def _select_task(cfg_dict: dict, box, a: int, chunk: list, every_sample: bool = False):
    """One chunk of pairs on a worker: :func:`softclose.catalog.ranking.screen_chunk`."""
    return screen_chunk(from_dict(cfg_dict), box, a, chunk, every_sample)


class _Mapper:
    def __init__(self, client):
        self.client = client
        self.lost = None

    def __call__(self, cfg, box, tasks, every_sample: bool = False):
        raw = {k: dict(v) for k, v in cfg.raw.items()}
        try:
            for _, result in map_tasks(self.client, _select_task,
                                       ((a, (raw, box, a, chunk, every_sample))
                                        for a, chunk in tasks),
                                       label="chunk of pairs"):
                yield result
        except ClusterLost as exc:
            self.lost = exc


@contextlib.contextmanager
def mapper(dask):
    """A mapper for :func:`softclose.catalog.select` that screens the chunks on Dask
    (``dask``: ``"local:N"``, a scheduler address or a ``distributed.Client``)."""
    with connect(dask) as client:
        yield _Mapper(client)
