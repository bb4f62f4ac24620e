"""One writer per store: a lock file created with ``O_EXCL``.

The lock is a hidden file beside the store, ``.NAME.ideas_hpc.lock`` for a
store ``NAME`` (beside, not inside: zarr warns about foreign files in a
hierarchy, and a lock beside the store can be taken before the store is
created, so creation and the run are one critical section). It holds one JSON line: host, pid,
the pid's start time (so a recycled pid is not mistaken for the owner) and
when the lock was taken. A second campaign on the same store is refused with
a clear :class:`StoreLockedError`. A lock left behind by a killed campaign is
*stale* when it names this host and its pid is dead (or now belongs to a
different process); a stale lock is taken over. A lock from another host is
never taken over automatically: the error says which host and how to remove it.

Workers never take the lock; only the client that submits the chunk tasks does.
"""

from __future__ import annotations

import json
import os
import socket
import time
from pathlib import Path

from ideas_hpc.base.errors import InputError

LOCK_SUFFIX = ".ideas_hpc.lock"

# Locks this process holds, path -> nesting depth: a campaign that holds the
# lock may call code that takes it again (run_campaign -> run_chunks).
_HELD: dict[str, int] = {}


def lock_path(store: str | os.PathLike) -> Path:
    """Where the lock of ``store`` lives: ``<parent>/.<name>.ideas_hpc.lock``."""
    store = Path(store).absolute()
    return store.parent / f".{store.name}{LOCK_SUFFIX}"


class StoreLockedError(InputError):
    """Another live campaign holds the store's lock."""


def _host() -> str:
    return socket.gethostname()


def _pid_start_time(pid: int) -> str | None:
    """Start time of ``pid`` in clock ticks since boot (``/proc/PID/stat`` field 22), or None."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as fh:
            stat = fh.read().decode(errors="replace")
    except OSError:
        return None
    # The command name (field 2) may contain spaces and parentheses: split after the last ')'.
    rest = stat.rsplit(")", 1)[-1].split()
    return rest[19] if len(rest) > 19 else None


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def read_lock(store: str | os.PathLike) -> dict | None:
    """The lock record of ``store`` (dict), ``{}`` if unreadable, or None when unlocked."""
    path = lock_path(store)
    try:
        text = path.read_text()
    except FileNotFoundError:
        return None
    except OSError:
        return {}
    try:
        rec = json.loads(text)
        return rec if isinstance(rec, dict) else {}
    except ValueError:
        return {}


def lock_is_stale(rec: dict) -> bool:
    """True when ``rec`` names this host and its process is gone (or its pid was recycled).

    An empty or unparsable record (a writer killed between ``open`` and
    ``write``) is stale when the file is older than a few seconds.
    """
    if not rec:
        return True
    if rec.get("host") != _host():
        return False
    try:
        pid = int(rec["pid"])
    except (KeyError, TypeError, ValueError):
        return True
    if not _pid_alive(pid):
        return True
    start = rec.get("start")
    return start is not None and _pid_start_time(pid) not in (None, start)


class StoreLock:
    """Exclusive writer lock on a store directory; use as a context manager.

    Parameters
    ----------
    store : path
        The store directory (its parent must exist; the store itself need not).

    Raises
    ------
    StoreLockedError
        When a live process (or a process on another host) holds the lock.
    """

    def __init__(self, store: str | os.PathLike):
        self.store = Path(store)
        self.path = lock_path(store)
        self.held = False

    def _record(self) -> bytes:
        pid = os.getpid()
        return (json.dumps({"host": _host(), "pid": pid, "start": _pid_start_time(pid),
                            "time": time.strftime("%Y-%m-%dT%H:%M:%S%z")}) + "\n").encode()

    def _try_create(self) -> bool:
        try:
            fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        except FileExistsError:
            return False
        try:
            os.write(fd, self._record())
            os.fsync(fd)
        finally:
            os.close(fd)
        return True

    def acquire(self) -> StoreLock:
        key = str(self.path)
        if _HELD.get(key):
            _HELD[key] += 1
            self.held = True
            return self
        if not self.path.parent.is_dir():
            raise InputError(f"folder {self.path.parent} does not exist", field="store")
        for _ in range(3):
            if self._try_create():
                self.held = True
                _HELD[key] = 1
                return self
            rec = read_lock(self.store)
            if rec is None:
                continue  # released meanwhile: try again
            if rec == {}:
                # A writer may be between O_EXCL and write(): give it a moment.
                try:
                    age = time.time() - self.path.stat().st_mtime
                except FileNotFoundError:
                    continue
                if age < 5.0:
                    time.sleep(0.2)
                    continue
            if lock_is_stale(rec):
                # Move the stale file aside under a unique name first, so that two
                # processes taking over at once cannot both delete a fresh lock.
                aside = self.path.with_name(f"{self.path.name}.stale.{os.getpid()}")
                try:
                    os.rename(self.path, aside)
                    os.unlink(aside)
                except FileNotFoundError:
                    pass
                continue
            raise StoreLockedError(
                f"store {self.store} is being written by another campaign "
                f"(pid {rec.get('pid')} on host {rec.get('host')}, since {rec.get('time')}); "
                f"wait for it to finish, or if that process is gone remove {self.path}",
                field="store")
        raise StoreLockedError(f"could not take the lock {self.path}", field="store")

    def release(self) -> None:
        if not self.held:
            return
        key = str(self.path)
        self.held = False
        _HELD[key] = _HELD.get(key, 1) - 1
        if _HELD[key] > 0:
            return
        del _HELD[key]
        rec = read_lock(self.store)
        if rec and rec.get("pid") == os.getpid() and rec.get("host") == _host():
            try:
                self.path.unlink()
            except FileNotFoundError:
                pass

    def __enter__(self) -> StoreLock:
        return self.acquire()

    def __exit__(self, *exc) -> None:
        self.release()
