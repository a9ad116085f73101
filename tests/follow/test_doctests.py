"""The follower's docstring examples run under ``make test`` (pytest does not collect doctests here)."""

import doctest
import importlib

import pytest

MODULES = ["worldtrack.follow", "worldtrack.follow.colour", "worldtrack.follow.config", "worldtrack.follow.dissimilarity",
           "worldtrack.follow.kalman", "worldtrack.follow.others", "worldtrack.follow.pid", "worldtrack.follow.planview",
           "worldtrack.follow.reid", "worldtrack.follow.silhouette", "worldtrack.follow.stereo", "worldtrack.follow.templates",
           "worldtrack.follow.tracker", "worldtrack.follow.loop", "worldtrack.eval.follow"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
