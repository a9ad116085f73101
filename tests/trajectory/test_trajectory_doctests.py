"""The examples in the docstrings of seed 002's modules run (pytest does not collect doctests here)."""

import doctest
import importlib

import pytest

MODULES = ["worldtrack.trajectory.model", "worldtrack.trajectory.observation", "worldtrack.trajectory.estimate",
           "worldtrack.trajectory.uncertainty", "worldtrack.trajectory.windows", "worldtrack.trajectory.coarse",
           "worldtrack.trajectory.lookahead", "worldtrack.trajectory.settle",
           "worldtrack.synth.observations"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples_run(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
