"""Running many independent tasks: in-process, on a local Dask cluster, or on an existing one.

:mod:`simgrip.parallel.runner` is the one runner that ``simgrip sweep``,
``bench``, ``stress`` and ``figures`` use; :mod:`simgrip.parallel.dask_cluster`
starts, reaches and stops the clusters; :mod:`simgrip.parallel.cli_cluster`
starts a ``dask scheduler`` + ``dask worker`` cluster on 127.0.0.1 (tests and
``sweep --throughput``).
"""
