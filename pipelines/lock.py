"""The lock file that keeps two sweeps out of one output directory.

Two sweeps writing into one ``--out`` would each consolidate ``archive.nc`` from the other's
half-written case set, and the last one to finish silently replaces the other's archive. The
sweep therefore holds ``<out>/sweep.lock`` for its whole life. The file is created with
``O_CREAT | O_EXCL`` (atomic on local file systems and on NFS v3 and later) and holds the
owner's process id, host name, start time and command as JSON.

A lock whose process no longer runs on this host (a sweep killed with ``kill -9`` or by a
power cut) is stale: the next sweep says so and takes it over. A lock of another host cannot be
checked from here; the message names the host and process so that the user can decide to
delete it.
"""

from __future__ import annotations

import contextlib
import json
import os
import socket
import time
from collections.abc import Callable, Iterator
from datetime import UTC, datetime
from pathlib import Path

from pipelines.checks import InputError, process_alive

LOCK_NAME = "sweep.lock"
# A lock file that is empty or unreadable is one being written right now, unless it is older
# than this (s): then its writer died between creating and filling it.
UNFINISHED_LOCK_AGE = 10.0


def _read(path: Path) -> dict[str, object] | None:
    try:
        owner = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return owner if isinstance(owner, dict) else None


def _stale(path: Path, owner: dict[str, object] | None) -> str | None:
    """Why the lock at ``path`` is stale, or ``None`` if its owner may be running."""
    if owner is None:
        try:
            age = time.time() - path.stat().st_mtime
        except FileNotFoundError:
            return "removed meanwhile"
        if age > UNFINISHED_LOCK_AGE:
            return f"an unfinished lock file {age:.0f} s old"
        return None
    pid, host = owner.get("pid"), owner.get("host")
    if host == socket.gethostname() and isinstance(pid, int) and not process_alive(pid):
        return f"process {pid} on {host} no longer runs"
    return None


def _describe(owner: dict[str, object] | None) -> str:
    if owner is None:
        return "a process that is creating the lock file now"
    return (f"process {owner.get('pid')} on {owner.get('host')}, started "
            f"{owner.get('started')}: {owner.get('command')}")


@contextlib.contextmanager
def sweep_lock(out_dir: str | os.PathLike[str], command: str,
               say: Callable[[str], None] = lambda line: None) -> Iterator[Path]:
    """Hold ``out_dir/sweep.lock`` for the duration of the ``with`` block.

    Parameters
    ----------
    out_dir
        The sweep's output directory (it exists).
    command
        The command line, written into the lock so that a refused user sees who holds it.
    say
        Receives the line that reports the takeover of a stale lock.

    Yields
    ------
    pathlib.Path
        The lock file.

    Raises
    ------
    pipelines.checks.InputError
        If another sweep that may still run holds the lock (nothing has run).
    """
    path = Path(out_dir) / LOCK_NAME
    owner_text = json.dumps({
        "pid": os.getpid(), "host": socket.gethostname(),
        "started": datetime.now(UTC).isoformat(timespec="seconds"), "command": command,
    })
    for _ in range(3):  # a stale lock is removed once; a racing taker may win it meanwhile
        try:
            fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            owner = _read(path)
            reason = _stale(path, owner)
            if reason is None:
                raise InputError(
                    f"--out {Path(out_dir)}: another sweep is writing into this directory "
                    f"({_describe(owner)}); wait for it, choose another --out, or delete "
                    f"{path} if that sweep no longer runs"
                ) from None
            say(f"taking over the stale lock {path} ({reason})")
            with contextlib.suppress(FileNotFoundError):
                path.unlink()
            continue
        except OSError as exc:
            raise InputError(f"--out {Path(out_dir)}: cannot create the lock file {path} "
                             f"({exc.strerror or type(exc).__name__})") from None
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(owner_text)
        break
    else:
        raise InputError(f"--out {Path(out_dir)}: cannot take the lock {path}: another sweep "
                         "keeps taking it")
    try:
        yield path
    finally:
        # Remove the lock only while it is still ours (never another sweep's).
        owner = _read(path)
        if owner is not None and owner.get("pid") == os.getpid() \
                and owner.get("host") == socket.gethostname():
            with contextlib.suppress(FileNotFoundError):
                path.unlink()
