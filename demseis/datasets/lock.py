"""The writer lock of a demseis store: one writing command at a time.

Every command that writes a store (``generate``, ``render`` into a store, anything that calls
:func:`~demseis.datasets.create.create_store` as the driver) holds :func:`writer_lock` for its
whole run. The lock is a small JSON file **beside** the store, ``<store>.lock`` (for
``out/t.zarr``: ``out/t.zarr.lock``), not inside it: zarr lists every entry of a store
directory and warns about files it does not know, and ``overwrite`` deletes the store
directory, lock included.

Protocol
--------
- Acquire: create the file with ``O_CREAT | O_EXCL`` (atomic on local filesystems and on NFSv3+)
  and write the holder: host, pid, the process start time, the command, a random token.
- A second writer finds the file and is refused with :class:`StoreError` naming the holder.
- Stale lock: the holder is on this host and its pid is not alive (or the pid now belongs to a
  process with another start time: the pid was reused). It is taken over safely: under a
  second ``O_EXCL`` file (``<store>.lock.break``), re-read the lock, delete it only if it still
  holds the same token, release the breaker, then create a new lock with ``O_EXCL`` as usual.
  Two processes that both see the stale lock cannot both win: only one creates the new file.
- A lock held from another host is never judged stale (its pid cannot be checked from here);
  the message says to delete the file by hand once that host's command is known to be gone.
- Release: delete the file if it still holds our token.

Dask clusters and shared filesystems: only the driver (the process running ``generate``)
holds the lock. The workers write their shards without touching it: shard tasks write disjoint
files (see ``docs/store.md``), and the driver is the only process that creates arrays, writes
attributes or consolidates. On NFS, ``O_EXCL`` creation is atomic from NFSv3 on; on
filesystems without it (NFSv2) two drivers could both acquire the lock.
"""

from __future__ import annotations

import json
import os
import secrets
import socket
import sys
import time
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from demseis.errors import StoreError

_BREAK_SUFFIX = ".break"


def lock_path(store: str | Path) -> Path:
    """The lock file of ``store``: ``<store>.lock`` beside it (trailing separators ignored)."""
    p = Path(os.path.abspath(store))
    return p.with_name(p.name + ".lock")


def _process_start(pid: int) -> str | None:
    """Start time of ``pid`` in clock ticks since boot (Linux ``/proc/<pid>/stat`` field 22)."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as fh:
            stat = fh.read().decode("ascii", "replace")
    except OSError:
        return None
    # the command name (field 2) may contain spaces and parentheses: split after the last ')'
    fields = stat.rsplit(")", 1)[-1].split()
    return fields[19] if len(fields) > 19 else None


def pid_alive(pid: int) -> bool:
    """True when a process with this pid exists on this host."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by another user
        return True
    return True


def is_stale(holder: dict[str, Any]) -> bool:
    """True when the holder of a lock is certainly gone.

    Only a holder on this host can be checked: its pid is not alive, or the pid is alive but
    started at another time than the holder recorded (the pid was reused).
    """
    if holder.get("host") != socket.gethostname():
        return False
    try:
        pid = int(holder["pid"])
    except (KeyError, TypeError, ValueError):
        return False
    if not pid_alive(pid):
        return True
    recorded, now = holder.get("proc_start"), _process_start(pid)
    return recorded is not None and now is not None and recorded != now


def _read(path: Path) -> dict[str, Any] | None:
    """The holder recorded in ``path``; None if the file is gone; {} if it is unreadable."""
    try:
        text = path.read_text()
    except FileNotFoundError:
        return None
    except OSError:
        return {}
    try:
        data = json.loads(text)
    except ValueError:
        return {}
    return data if isinstance(data, dict) else {}


def _create(path: Path, holder: dict[str, Any]) -> bool:
    """Create ``path`` exclusively holding ``holder``; False if it exists."""
    try:
        fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
    except FileExistsError:
        return False
    except OSError as exc:
        raise StoreError(f"cannot create the store lock {str(path)!r}: {exc.strerror or exc}") from None
    try:
        os.write(fd, (json.dumps(holder) + "\n").encode())
        os.fsync(fd)
    finally:
        os.close(fd)
    return True


def _describe(holder: dict[str, Any]) -> str:
    if not holder:
        return "an unknown holder (the lock file is unreadable)"
    return (f"pid {holder.get('pid')} on host {holder.get('host')!r}, started "
            f"{holder.get('started')} ({holder.get('command', '?')})")


class StoreLock:
    """The writer lock of one store (see the module docstring). Use as a context manager.

    Parameters
    ----------
    store : the store directory (it need not exist yet).
    command : what holds the lock, shown to a refused writer (e.g. ``"demseis generate"``).
    """

    def __init__(self, store: str | Path, command: str | None = None) -> None:
        self.store = Path(store)
        self.path = lock_path(store)
        self.command = command or " ".join(Path(a).name if i == 0 else a
                                           for i, a in enumerate(sys.argv)) or "python"
        self.holder: dict[str, Any] | None = None

    def acquire(self) -> StoreLock:
        """Take the lock; :class:`StoreError` naming the holder if another writer has it."""
        if self.holder is not None:
            return self
        me = {
            "host": socket.gethostname(),
            "pid": os.getpid(),
            "proc_start": _process_start(os.getpid()),
            "started": datetime.now(timezone.utc).isoformat(timespec="seconds"),
            "command": self.command,
            "token": secrets.token_hex(8),
        }
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)  # zarr would create it anyway
        except OSError as exc:
            raise StoreError(f"cannot lock store {str(self.store)!r}: cannot create "
                             f"{str(self.path.parent)!r}: {exc.strerror or exc}") from None
        for _ in range(50):
            if _create(self.path, me):
                self.holder = me
                return self
            holder = _read(self.path)
            for _ in range(50):  # just created by another writer, content not written yet
                if holder != {}:
                    break
                time.sleep(0.02)
                holder = _read(self.path)
            if holder is None:  # released meanwhile: try again
                continue
            if not is_stale(holder):
                raise StoreError(
                    f"store {str(self.store)!r} is being written by {_describe(holder)}; wait for "
                    f"it to finish (or, if that process is gone, delete {str(self.path)!r})"
                )
            self._break(holder)
        raise StoreError(f"cannot take the lock {str(self.path)!r}: it keeps changing hands")

    def _break(self, stale: dict[str, Any]) -> None:
        """Delete the stale lock ``stale`` if it is still the one in place (under a breaker)."""
        breaker = self.path.with_name(self.path.name + _BREAK_SUFFIX)
        me = {"host": socket.gethostname(), "pid": os.getpid(),
              "proc_start": _process_start(os.getpid())}
        if not _create(breaker, me):
            other = _read(breaker)
            if other and is_stale(other):  # a breaker that died while breaking
                breaker.unlink(missing_ok=True)
            else:
                time.sleep(0.05)  # another process is breaking the lock right now
            return
        try:
            now = _read(self.path)
            if now is not None and now.get("token") == stale.get("token"):
                self.path.unlink(missing_ok=True)
        finally:
            breaker.unlink(missing_ok=True)

    def release(self) -> None:
        """Delete the lock file if it is still ours."""
        if self.holder is None:
            return
        now = _read(self.path)
        if now is not None and now.get("token") == self.holder["token"]:
            self.path.unlink(missing_ok=True)
        self.holder = None

    def __enter__(self) -> StoreLock:
        return self.acquire()

    def __exit__(self, *exc: object) -> None:
        self.release()


def writer_lock(store: str | Path, command: str | None = None) -> StoreLock:
    """The writer lock of ``store``, to use as ``with writer_lock(out): ...``."""
    return StoreLock(store, command)
