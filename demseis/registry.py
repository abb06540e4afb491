"""Named registries: the engines, the imaging modes and the sample arrays of demseis.

A :class:`Registry` maps names to objects. Built-in entries may be given as
``"module:attribute"`` strings, loaded on first use (like entry points), so that this module,
on the ground floor of the package, can list the engines and imaging modes that higher layers
implement without importing them. A parameter whose values are the names of a registry
(``engine``, ``imaging``) declares the registry as its ``choices``, so a name registered at run
time (a plug-in, a test's toy engine) is a valid config value at once.

This module imports only the standard library and :mod:`demseis.errors`.
"""

from __future__ import annotations

import contextlib
import importlib
from collections.abc import Iterator
from typing import Any, Generic, TypeVar

from demseis.errors import InputError

T = TypeVar("T")


class Registry(Generic[T]):
    """An ordered name → object table; registration order is the order of the names.

    Parameters
    ----------
    kind : what the entries are, for error messages (``"engine"``, ``"imaging mode"``).
    builtins : name → object, or name → ``"module:attribute"`` to import on first use.
    """

    def __init__(self, kind: str, builtins: dict[str, T | str] | None = None) -> None:
        self.kind = kind
        self._entries: dict[str, T | str] = dict(builtins or {})

    def register(self, name: str, obj: T | str, *, replace: bool = False) -> T | str:
        """Add ``obj`` under ``name`` (after the existing names); returns ``obj``.

        Raises
        ------
        InputError
            ``name`` is not a non-empty string, or is taken and ``replace`` is False.
        """
        if not isinstance(name, str) or not name:
            raise InputError(f"a {self.kind} name must be a non-empty string, got {name!r}")
        if name in self._entries and not replace:
            raise InputError(f"a {self.kind} called {name!r} is already registered")
        self._entries[name] = obj
        return obj

    def unregister(self, name: str) -> None:
        """Remove ``name`` (an :class:`InputError` if it is not registered)."""
        if name not in self._entries:
            raise InputError(f"no {self.kind} called {name!r} is registered")
        del self._entries[name]

    @contextlib.contextmanager
    def registered(self, name: str, obj: T) -> Iterator[T]:
        """Register ``obj`` for the duration of a ``with`` block (tests, experiments)."""
        self.register(name, obj)
        try:
            yield obj
        finally:
            self._entries.pop(name, None)

    def get(self, name: str) -> T:
        """The object registered as ``name``, imported if it was given as a path.

        Raises
        ------
        InputError
            No such name; the message lists the registered ones.
        """
        try:
            obj = self._entries[name]
        except (KeyError, TypeError):
            raise InputError(f"unknown {self.kind} {name!r}: expected one of "
                             f"{', '.join(map(repr, self._entries))}") from None
        if isinstance(obj, str):
            module, _, attr = obj.partition(":")
            obj = getattr(importlib.import_module(module), attr)
            self._entries[name] = obj
        return obj

    def names(self) -> tuple[str, ...]:
        """The registered names, in registration order."""
        return tuple(self._entries)

    def index(self, name: str) -> int:
        """Position of ``name`` among :meth:`names` (the integer code a store holds)."""
        return self.names().index(name)

    def items(self) -> list[tuple[str, T]]:
        """(name, object) pairs in registration order, every entry loaded."""
        return [(n, self.get(n)) for n in self.names()]

    def __contains__(self, name: object) -> bool:
        return name in self._entries

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())

    def __len__(self) -> int:
        return len(self._entries)

    def __getitem__(self, index: Any) -> str:
        """The name at ``index`` (so a registry reads like a tuple of choices)."""
        return self.names()[index]

    def __repr__(self) -> str:
        return f"Registry({self.kind!r}, {list(self._entries)})"


#: the engines that turn a run's parameters into geological states (demseis.generator.engines)
ENGINES: Registry[Any] = Registry("engine", {
    "dem": "demseis.generator.engines.dem:ENGINE",
    "kinematic": "demseis.generator.engines.kinematic:ENGINE",
    "planar": "demseis.generator.engines.planar:ENGINE",
})

#: the imaging modes that turn property grids into sections (demseis.seismic.imaging)
IMAGING: Registry[Any] = Registry("imaging mode", {
    "1d": "demseis.seismic.imaging:ONE_D",
    "psf": "demseis.seismic.imaging:PSF",
})
