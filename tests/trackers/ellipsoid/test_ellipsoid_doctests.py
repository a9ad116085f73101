"""The docstring examples of the ellipsoid tracker's modules run (and say what they print)."""

import doctest
import importlib
from pathlib import Path

import pytest

import worldtrack.trackers.ellipsoid as package

MODULES = sorted(p.stem for p in Path(package.__file__).parent.glob("*.py"))


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples_run(name):
    module = package if name == "__init__" else importlib.import_module(f"worldtrack.trackers.ellipsoid.{name}")
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.failed == 0
