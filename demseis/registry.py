"""Named registries: the engines, the imaging modes and the sample arrays of demseis.

A :class:`Registry` maps names to objects. Built-in entries may be given as
``"module:attribute"`` strings, loaded on first use (like entry points), so that this module,
on the ground floor of the package, can list the engines and imaging modes that higher layers
implement without importing them. A parameter whose values are the names of a registry
(``engine``, ``imaging``) declares the registry as its ``choices``, so a name registered at run
time (a plug-in, a test's toy engine) is a valid config value at once.

Plug-ins reach every process of a sweep (its dask workers re-read the config) in three ways:

- an installed distribution's entry points in the registry's group (``demseis.engines``,
  ``demseis.imaging``, ``demseis.arrays``, ``demseis.renderings``, ``demseis.fault_styles``,
  ``demseis.label_methods``), read on first use in each process;
- a ``"module:attribute"`` name used where a registered name is expected (``[model] engine =
  "mypkg.engines:FLAT"``, ``[output] rendering``, ``[labels] fault_style`` and ``method``): it
  is imported and registered under that name on first use;
- the config's top-level ``plugins = ["mypkg.labels"]``: modules imported (by
  :func:`load_plugins`) before the rest of the config is read, which register what they
  define when imported.

This module imports only the standard library and :mod:`demseis.errors`.
"""

from __future__ import annotations

import contextlib
import importlib
import importlib.metadata
import re
from collections.abc import Iterable, Iterator
from typing import Any, Generic, TypeVar

from demseis.errors import InputError

T = TypeVar("T")


class Registry(Generic[T]):
    """An ordered name → object table; registration order is the order of the names.

    Parameters
    ----------
    kind : what the entries are, for error messages (``"engine"``, ``"imaging mode"``).
    builtins : name → object, or name → ``"module:attribute"`` to import on first use.
    group : entry-point group whose entries join (after the built-ins, lazily) on first use.
    paths : a ``"module:attribute"`` name that is not registered is imported and registered
        (engines and imaging modes; not sample arrays, whose names are store array names).
    """

    def __init__(self, kind: str, builtins: dict[str, T | str] | None = None,
                 group: str | None = None, paths: bool = True) -> None:
        self.kind = kind
        self.group = group
        self.paths = paths
        self._entries: dict[str, T | str] = dict(builtins or {})
        self._entry_points_read = group is None

    def _read_entry_points(self) -> None:
        """Add the installed entry points of ``self.group`` once (names taken are skipped: a
        built-in or a run-time registration wins)."""
        if self._entry_points_read:
            return
        self._entry_points_read = True
        for ep in sorted(importlib.metadata.entry_points(group=self.group), key=lambda e: e.name):
            self._entries.setdefault(ep.name, ep.value)

    @property
    def _table(self) -> dict[str, T | str]:
        self._read_entry_points()
        return self._entries

    def register(self, name: str, obj: T | str, *, replace: bool = False) -> T | str:
        """Add ``obj`` under ``name`` (after the existing names); returns ``obj``.

        Raises
        ------
        InputError
            ``name`` is not a non-empty string, or is taken and ``replace`` is False.
        """
        if not isinstance(name, str) or not name:
            raise InputError(f"a {self.kind} name must be a non-empty string, got {name!r}")
        # the entries registered so far (entry points are read at the first look-up, after the
        # built-ins a module registers at import, and skip names taken by then)
        if name in self._entries and not replace:
            raise InputError(f"a {self.kind} called {name!r} is already registered")
        self._entries[name] = obj
        return obj

    def unregister(self, name: str) -> None:
        """Remove ``name`` (an :class:`InputError` if it is not registered)."""
        if name not in self._table:
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
            obj = self._table[name]
        except (KeyError, TypeError):
            if self.paths and isinstance(name, str) and _PATH.fullmatch(name):
                return self._register_path(name)
            raise InputError(f"unknown {self.kind} {name!r}: expected one of "
                             f"{', '.join(map(repr, self._entries))}"
                             + (", or a 'module:attribute' path" if self.paths else "")) from None
        if isinstance(obj, str):
            obj = _import_path(obj, f"{self.kind} {name!r}")
            self._entries[name] = obj
        return obj

    def _register_path(self, path: str) -> T:
        """Import ``"module:attribute"`` and register the object under that name."""
        obj = _import_path(path, self.kind)
        self._entries[path] = obj
        return obj

    def names(self) -> tuple[str, ...]:
        """The registered names, in registration order."""
        return tuple(self._table)

    def index(self, name: str) -> int:
        """Position of ``name`` among :meth:`names` (the integer code a store holds)."""
        return self.names().index(name)

    def items(self) -> list[tuple[str, T]]:
        """(name, object) pairs in registration order, every entry loaded."""
        return [(n, self.get(n)) for n in self.names()]

    def __contains__(self, name: object) -> bool:
        """Registered, or a ``"module:attribute"`` path that imports (it is registered then;
        one that does not import raises its InputError, which says why)."""
        if name in self._table:
            return True
        if self.paths and isinstance(name, str) and _PATH.fullmatch(name):
            self._register_path(name)
            return True
        return False

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())

    def __len__(self) -> int:
        return len(self._table)

    def __getitem__(self, index: Any) -> str:
        """The name at ``index`` (so a registry reads like a tuple of choices)."""
        return self.names()[index]

    def __repr__(self) -> str:
        return f"Registry({self.kind!r}, {list(self._table)})"


#: ``package.module:attribute`` (dotted identifiers on both sides)
_PATH = re.compile(r"[A-Za-z_][\w]*(\.[A-Za-z_][\w]*)*:[A-Za-z_][\w]*(\.[A-Za-z_][\w]*)*")


def _import_path(path: str, what: str) -> Any:
    """The object at ``"module:attribute"`` (attribute may be dotted); InputError naming
    ``what`` and the path if the module does not import or lacks the attribute."""
    module, _, attr = path.partition(":")
    try:
        obj: Any = importlib.import_module(module)
    except ImportError as exc:
        raise InputError(f"{what}: cannot import {module!r} of {path!r} ({exc})") from None
    for part in attr.split("."):
        try:
            obj = getattr(obj, part)
        except AttributeError:
            raise InputError(f"{what}: module {module!r} has no {attr!r} ({path!r})") from None
    return obj


def load_plugins(modules: Iterable[str]) -> None:
    """Import each plug-in module (``"package.module"``; a ``"module:attribute"`` imports the
    module and checks the attribute), so that what it registers on import exists in this
    process; InputError naming the one that fails."""
    for name in modules:
        if not isinstance(name, str) or not (_PATH.fullmatch(name) or
                                             _PATH.fullmatch(name + ":x")):
            raise InputError(f"plugins: {name!r} is not a module name ('package.module')")
        if ":" in name:
            _import_path(name, "plugins")
        else:
            _import_path(name + ":__name__", "plugins")


#: the engines that turn a run's parameters into geological states (demseis.generator.engines)
ENGINES: Registry[Any] = Registry("engine", {
    "dem": "demseis.generator.engines.dem:ENGINE",
    "kinematic": "demseis.generator.engines.kinematic:ENGINE",
    "planar": "demseis.generator.engines.planar:ENGINE",
}, group="demseis.engines")

#: the imaging modes that turn property grids into sections (demseis.seismic.imaging)
IMAGING: Registry[Any] = Registry("imaging mode", {
    "1d": "demseis.seismic.imaging:ONE_D",
    "psf": "demseis.seismic.imaging:PSF",
}, group="demseis.imaging")

#: how a state becomes the property columns the imaging reads (demseis.generator.render.section:
#: ``Rendering``); the ``[output] rendering`` values
RENDERINGS: Registry[Any] = Registry("rendering", {
    "elements": "demseis.generator.render.section:ELEMENTS",
    "strata": "demseis.generator.render.section:STRATA",
}, group="demseis.renderings")

#: how the stored fault label is drawn on the output grid (demseis.generator.render.section:
#: ``FaultStyle``); the ``[labels] fault_style`` values
FAULT_STYLES: Registry[Any] = Registry("fault style", {
    "picks": "demseis.generator.render.section:PICKS",
    "traces": "demseis.generator.render.section:TRACES",
}, group="demseis.fault_styles")

#: how the fault targets are found in a snapshot's elements (demseis.labels.maps:
#: ``LabelMethod``); the ``[labels] method`` values
LABEL_METHODS: Registry[Any] = Registry("label method", {
    "slip_trace": "demseis.labels.maps:SLIP_TRACE",
    "strain_band": "demseis.labels.maps:STRAIN_BAND",
}, group="demseis.label_methods")
