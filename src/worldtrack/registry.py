"""Named implementations of a protocol, chosen once at construction (configs name them).

A method's variants — motion models, likelihoods, resamplers, foreground models, trackers — are
classes registered under the names the configuration uses; the tracker looks the name up once and
the per-frame path calls the object, with no ``if`` on a config string.

>>> from typing import Protocol
>>> class Resampler(Protocol):
...     def __call__(self, weights, n, rng): ...
>>> RESAMPLERS: Registry[Resampler] = Registry("resampling")
>>> @RESAMPLERS.register("systematic")
... def systematic(weights, n, rng):
...     return "drawn"
>>> RESAMPLERS["systematic"](None, 3, None)
'drawn'
>>> RESAMPLERS["multinomial"]
Traceback (most recent call last):
...
worldtrack.errors.InputError: resampling: expected one of systematic, got 'multinomial'
"""

from __future__ import annotations

import importlib
from typing import Callable, Generic, Iterator, TypeVar

from worldtrack.errors import InputError

T = TypeVar("T")


class Registry(Generic[T]):
    """Implementations of one protocol by name.

    Parameters
    ----------
    what : str — the setting that names them (used in errors)
    """

    def __init__(self, what: str):
        self.what = what
        self._items: dict[str, T | str] = {}

    def register(self, name: str) -> Callable[[T], T]:
        """Decorator: register the decorated class or function under ``name``."""
        def add(item: T) -> T:
            self._items[name] = item
            return item
        return add

    def add_lazy(self, name: str, target: str) -> None:
        """Register ``"package.module:attribute"``, imported when first looked up (keeps heavy
        modules out of start-up)."""
        self._items[name] = target

    def __getitem__(self, name: str) -> T:
        if name not in self._items:
            raise InputError(f"{self.what}: expected one of {', '.join(self._items)}, got {name!r}")
        item = self._items[name]
        if isinstance(item, str):
            module, attr = item.split(":")
            item = getattr(importlib.import_module(module), attr)
            self._items[name] = item
        return item  # type: ignore[return-value]

    def __contains__(self, name: object) -> bool:
        return name in self._items

    def __iter__(self) -> Iterator[str]:
        return iter(self._items)

    def names(self) -> tuple[str, ...]:
        return tuple(self._items)


__all__ = ["Registry"]
