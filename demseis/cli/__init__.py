"""The ``demseis`` command line: one module per command group, each thin over the library.

- :mod:`demseis.cli.generate`: ``generate``, ``render``, ``relabel``, ``params``
- :mod:`demseis.cli.store`: ``info``, ``validate``, ``export-segy``, ``migrate``
- :mod:`demseis.cli.plots`: ``plot``, ``preview``
- :mod:`demseis.cli.evaluate`: ``score``, ``baseline``, ``fit``, ``realism``
- :mod:`demseis.cli.model`: ``train``, ``predict``

Each of these modules holds parsers only: ``register(sub)`` adds its commands to ``sub``, the
top-level subparsers object, and names each command's handler ``"group:function"``
(``parser.set_defaults(func="generate:cmd_generate")``). The handlers, ``func(args) -> int``,
are in :mod:`demseis.cli.commands` (one module per group), which import what they run (the
library, NumPy, dask, torch, matplotlib) at their top; :func:`handler` imports the group of the
command that runs, so ``--help`` imports none of them and stays fast.

Any :class:`demseis.errors.DemseisError` becomes one line on stderr and its exit code (2 for
usage and input errors); argparse's own usage errors also exit 2.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import os
import sys
import warnings
from collections.abc import Callable, Sequence
from typing import NoReturn

from demseis import __version__, interrupts
from demseis.errors import DemseisError

#: commands that write a store: an interrupted one resumes when run again
WRITING_COMMANDS = frozenset({"generate", "render", "relabel", "migrate"})


class _Parser(argparse.ArgumentParser):
    """argparse's parser whose usage errors are one line (exit 2), as every other bad input;
    the subcommands' parsers are of this class too (argparse makes them of the parent's)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see `{self.prog} --help`)\n")


def build_parser() -> argparse.ArgumentParser:
    """The full argument parser with every subpackage's subcommands registered."""
    # imported here so that main() also turns a Ctrl-C during these imports into its message
    from demseis.cli import evaluate, generate, model, plots, store

    parser = _Parser(
        prog="demseis",
        description="Labelled synthetic seismic from discrete-element fault models.",
    )
    parser.add_argument("--version", action="version", version=f"demseis {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in (generate, store, plots, evaluate, model):
        module.register(sub)
    _describe(sub)
    return parser


def handler(name: str) -> Callable[[argparse.Namespace], int]:
    """The handler a parser names ``"group:function"``: ``function`` of
    :mod:`demseis.cli.commands.<group>`, imported now (only the command that runs pays for what
    its handlers import)."""
    group, _, function = name.partition(":")
    return getattr(importlib.import_module(f"demseis.cli.commands.{group}"), function)


def _describe(sub: argparse._SubParsersAction) -> None:
    """Give every command (and sub-command) without a description its one-line help as one,
    so that ``demseis COMMAND --help`` says what the command does."""
    for choice in sub._choices_actions:
        parser = sub.choices[choice.dest]
        if not parser.description and choice.help:
            parser.description = choice.help[0].upper() + choice.help[1:] + "."
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                _describe(action)


def _path_arg(args: argparse.Namespace | None) -> str:
    """The output (or store) path of a command, to name in a filesystem error without one."""
    for name in ("out", "store"):
        value = getattr(args, name, None)
        if value:
            return str(value)
    return "(path unknown)"


def _quiet_pending_tasks() -> None:
    """Silence what asyncio says at exit of tasks left on zarr's event loop ("Task was
    destroyed but it is pending!", "coroutine ... was never awaited")."""
    logging.getLogger("asyncio").setLevel(logging.CRITICAL)
    warnings.filterwarnings("ignore", message="coroutine .* was never awaited")


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; returns the process exit code."""
    # Ctrl-C is recorded as well as raised: one swallowed where it landed (a __del__, a weakref
    # callback) is raised by the next check of a long loop, or reported below at the latest
    with interrupts.installed():
        return _main(argv)


def _stdout_closed() -> int:
    """The reader of our stdout went away (``demseis info S | head -1``): say nothing, send the
    rest of the output nowhere (so the interpreter's last flush does not fail too), and exit as
    a program killed by SIGPIPE does (141)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):  # no real stdout (a test's capture): nothing to redirect
        pass
    return 141


def _main(argv: Sequence[str] | None) -> int:
    try:
        parser = build_parser()  # imports the command modules: Ctrl-C may land here too
        args = parser.parse_args(argv)
        if not getattr(args, "func", None):
            parser.print_help()
            return 2
        code = int(handler(args.func)(args) or 0)
        if interrupts.interrupted():  # swallowed where it landed, and the command completed
            raise interrupts.Finished
        sys.stdout.flush()  # a closed pipe is found here, not at the interpreter's exit
        return code
    except BrokenPipeError:
        return _stdout_closed()
    except DemseisError as exc:
        # a store read that failed (a damaged chunk) leaves its sibling reads pending on
        # zarr's event loop: their "Task was destroyed" at exit is noise after the one line
        _quiet_pending_tasks()
        print(f"demseis: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except OSError as exc:  # read-only or full filesystem, a path under /proc, permissions
        where = exc.filename if exc.filename is not None else _path_arg(locals().get("args"))
        print(f"demseis: error: {where}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    except (KeyboardInterrupt, RuntimeError) as exc:
        # Python 3.11 wraps a Ctrl-C that lands while a class is being created (an import of
        # dask's expression classes at a sweep's start) as "RuntimeError: Error calling
        # __set_name__", the KeyboardInterrupt as its cause
        if isinstance(exc, RuntimeError):
            if not isinstance(exc.__cause__, KeyboardInterrupt):
                raise
            exc = exc.__cause__
        interrupts.clear()
        # an interrupted zarr call leaves a task on zarr's event loop. What was written is
        # consistent (a shard counts only once its done flag is set), so that is noise.
        _quiet_pending_tasks()
        command = getattr(locals().get("args"), "command", None)
        if isinstance(exc, interrupts.Finished):
            print("demseis: interrupted after the work was done: nothing to resume",
                  file=sys.stderr)
        elif command in WRITING_COMMANDS:
            print("demseis: interrupted; run the same command to resume", file=sys.stderr)
        else:  # a read-only command has nothing to resume
            print("demseis: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
