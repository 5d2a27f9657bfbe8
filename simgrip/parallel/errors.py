"""The runner's errors: :class:`RunnerError` (the cluster failed, exit status 1) and :class:`SchedulerError`."""

from __future__ import annotations

__all__ = ["RunnerError", "SchedulerError"]


class RunnerError(RuntimeError):
    """The cluster failed (scheduler unreachable or gone, no workers, workers lost repeatedly); ``fn`` did not raise."""


class SchedulerError(RunnerError, ValueError):
    """The address or scheduler file given does not lead to a Dask scheduler (bad input: exit status 2).

    Both a :class:`RunnerError` (the cluster could not be used) and a
    ``ValueError`` (what the user typed is wrong: the command line names it
    and exits with status 2).
    """
