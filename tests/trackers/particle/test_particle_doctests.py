"""The docstring examples of the particle tracker's modules run (and say what they show)."""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import pytest

import worldtrack.trackers.particle as package

MODULES = ["worldtrack.foreground.shadows", package.__name__] + sorted(
    m.name for m in pkgutil.walk_packages(package.__path__, package.__name__ + "."))


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples_run(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.failed == 0


def test_the_package_and_its_steps_have_examples():
    attempted = {name: doctest.testmod(importlib.import_module(name)).attempted for name in MODULES}
    for name in (package.__name__, package.__name__ + ".config", package.__name__ + ".likelihood.column",
                 package.__name__ + ".resample", package.__name__ + ".split", package.__name__ + ".region"):
        assert attempted[name] > 0, name
