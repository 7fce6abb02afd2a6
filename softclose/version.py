"""The version of softclose, stated once: the package exports it, a sweep's manifest records
it and a Dask run checks that every worker has the same."""

__version__ = "0.2.0"
