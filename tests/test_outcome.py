"""outcome (simgrip.envs.outcome): one word per way an episode ends, the first true key winning."""

import pytest

from simgrip.envs import evaluation
from simgrip.envs.outcome import outcome


@pytest.mark.parametrize("info, word", [
    ({"is_success": True, "crushed": False}, "success"),
    ({"is_success": False, "crushed": True, "dropped": True}, "crushed"),  # a crush outranks the drop it causes
    ({"dropped": True, "knocked_over": True}, "dropped"),
    ({"knocked_over": True}, "knocked_over"),
    ({"is_success": False, "crushed": False, "dropped": False}, "timeout"),
    ({}, "timeout"),
])
def test_outcome_names_the_first_true_key(info, word):
    assert outcome(info) == word


def test_evaluation_counts_with_the_same_function():
    assert evaluation.outcome is outcome
