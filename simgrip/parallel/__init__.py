"""Running many independent tasks: in-process, on a local Dask cluster, or on an existing one.

:mod:`simgrip.parallel.runner` is the one runner that ``simgrip sweep``,
``bench``, ``stress`` and ``figures`` use; :mod:`simgrip.parallel.dask_cluster`
starts and stops the local cluster (and caps its worker processes);
:mod:`simgrip.parallel.remote` reaches an existing scheduler within one
connect timeout or names why not; :mod:`simgrip.parallel.helper_thread` runs
distributed's blocking calls so that the calling thread stays interruptible;
:mod:`simgrip.parallel.errors` holds the runner's errors;
:mod:`simgrip.parallel.cli_cluster` starts a ``dask scheduler`` +
``dask worker`` cluster on 127.0.0.1 (tests and ``sweep --throughput``).
"""
