"""Ctrl-C that is never lost.

Python's default SIGINT handler raises KeyboardInterrupt in whatever the main thread is
running at that moment. When that is a weak-reference callback or a ``__del__`` (the garbage
collector runs them at any bytecode), the exception cannot propagate: Python prints
"Exception ignored in: ..." and carries on. A 100,000-run sweep interrupted at such a moment
ran on for minutes (seen once in CI: no exit 120 s after the signal).

:func:`installed` puts in a handler that also *records* the interrupt (the CLI, for its whole
run; :func:`watched`, for a sweep run from a script). Long loops call
:func:`raise_if_interrupted` between units of work, so an interrupt that was swallowed is
raised there, and the unraisable hook of :func:`installed` keeps the swallowed one from
printing a traceback. :func:`clear` marks it handled (the CLI's ``except KeyboardInterrupt``).
Only the main thread's handler is touched; a handler someone else installed (a notebook
kernel's) is left alone by :func:`watched`.
"""

from __future__ import annotations

import contextlib
import signal
import sys
import threading
from collections.abc import Iterator
from types import FrameType
from typing import Any

_state = {"pending": False}
_previous_hook: list[Any] = []


class Finished(KeyboardInterrupt):
    """A Ctrl-C that came after the interrupted work had completed (a sweep whose every run
    was written and whose store was finalized): there is nothing to resume."""


def _handler(signum: int, frame: FrameType | None) -> None:
    """SIGINT: record it, then raise KeyboardInterrupt as Python's default handler does."""
    _state["pending"] = True
    raise KeyboardInterrupt


def _unraisable(args: Any) -> None:
    """Drop a recorded KeyboardInterrupt that could not propagate (it is raised later by
    :func:`raise_if_interrupted`); hand everything else to the previous hook."""
    if issubclass(args.exc_type, KeyboardInterrupt) and _state["pending"]:
        return
    (_previous_hook[0] if _previous_hook else sys.__unraisablehook__)(args)


@contextlib.contextmanager
def installed() -> Iterator[bool]:
    """The recording SIGINT handler and unraisable hook for the block (main thread only; yields
    whether they are in place), then what was there before. Ctrl-C raises KeyboardInterrupt as
    with Python's default handler; an ignored SIGINT (a background job) stays ignored."""
    if threading.current_thread() is not threading.main_thread() or \
            signal.getsignal(signal.SIGINT) in (signal.SIG_IGN, _handler):
        yield False
        return
    old_handler = signal.signal(signal.SIGINT, _handler)
    _previous_hook[:] = [sys.unraisablehook]
    sys.unraisablehook = _unraisable
    try:
        yield True
    finally:
        signal.signal(signal.SIGINT, old_handler)
        sys.unraisablehook = _previous_hook[0]
        _previous_hook.clear()


def interrupted() -> bool:
    """A recorded Ctrl-C not yet marked handled."""
    return _state["pending"]


def raise_if_interrupted() -> None:
    """Raise KeyboardInterrupt if a Ctrl-C was recorded and not handled (it may have been
    swallowed where it landed); a no-op otherwise."""
    if _state["pending"]:
        raise KeyboardInterrupt


def clear() -> None:
    """Mark the recorded Ctrl-C handled."""
    _state["pending"] = False


@contextlib.contextmanager
def watched() -> Iterator[None]:
    """The recording handler for a block of library work where the process uses Python's
    default one (the library called from a script); a swallowed Ctrl-C is raised at the block's
    end at the latest. Where another handler is in place (the CLI's, which is this one, or a
    notebook's), it only adds the check at the end: a Ctrl-C swallowed in a block that then
    completed is raised as :class:`Finished`."""
    ours = signal.getsignal(signal.SIGINT) is signal.default_int_handler
    with contextlib.ExitStack() as stack:
        if ours:
            ours = stack.enter_context(installed())
        try:
            yield
            if interrupted():  # swallowed, and the block's work completed all the same
                raise Finished
        except KeyboardInterrupt:
            if ours:  # the CLI marks its own handled where it reports it
                clear()
            raise
