"""How a fragile task's episode ended, from its last ``info`` (issue 18): one word per outcome.

Its own module so that the baselines harness (:mod:`simgrip.envs.baselines`) and the learners' evaluation
(:mod:`simgrip.envs.evaluation`) count the same way without importing each other.
"""

from __future__ import annotations

__all__ = ["outcome"]


def outcome(info: dict) -> str:
    """How an episode ended, from its last ``info``: ``"success"`` (``is_success``), ``"crushed"``,
    ``"dropped"``, ``"knocked_over"`` (the first of these keys that is true), else ``"timeout"``."""
    for key in ("is_success", "crushed", "dropped", "knocked_over"):
        if info.get(key):
            return "success" if key == "is_success" else key
    return "timeout"
