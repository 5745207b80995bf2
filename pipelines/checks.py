"""Checks of the command-line inputs that are not model parameters: output paths, the number of
workers and the scheduler address. Each raises :class:`InputError` with one line naming the
option and the value, before any work starts.
"""

from __future__ import annotations

import contextlib
import os
import re
import tempfile
from pathlib import Path

# Transports a dask scheduler address may name (distributed.comm registers these).
SCHEDULER_SCHEMES = ("tcp", "tls", "ws", "wss", "ucx", "inproc")
_HOST = re.compile(r"^(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9]([A-Za-z0-9.\-_]*[A-Za-z0-9])?)$")


# Most worker processes a local cluster may start: four per CPU core. The solver holds a core
# per worker, so more workers than cores only share them; far more (``--workers 100000``)
# exhaust the machine's memory and process table while the cluster starts.
WORKERS_PER_CORE = 4


class InputError(ValueError):
    """A command-line input (path, address) is unusable; the message names it."""


def max_workers() -> int:
    """The most worker processes a local cluster may start on this machine."""
    return WORKERS_PER_CORE * (os.cpu_count() or 1)


def check_workers(workers: int) -> int:
    """Check a number of local worker processes: 1 to :func:`max_workers`.

    Raises
    ------
    InputError
        If ``workers`` is below 1 or above the limit.
    """
    limit = max_workers()
    if not 1 <= workers <= limit:
        raise InputError(
            f"--workers {workers}: outside the valid range [1, {limit}] ({WORKERS_PER_CORE} per "
            f"CPU core, {os.cpu_count() or 1} cores here; for more workers start them on other "
            "machines and give --scheduler)"
        )
    return workers


def check_not_empty(path: str | os.PathLike[str], option: str = "--out") -> None:
    """Refuse an empty path: it would silently mean the current directory."""
    if not os.fspath(path).strip():
        raise InputError(f"{option} {os.fspath(path)!r}: an empty path; give a directory or "
                         "file name (use . for the current directory)")


def _existing_ancestor(path: Path, option: str, shown: Path) -> Path:
    """The nearest existing ancestor of ``path``, which must be a directory."""
    for parent in path.parents:
        if parent.exists():
            if not parent.is_dir():
                raise InputError(f"{option} {shown}: {parent} is a file, not a directory")
            return parent
    return Path(".")  # unreachable for absolute paths; relative ones resolve against cwd


def _probe(directory: Path, option: str, shown: Path) -> None:
    """Create and delete a file in ``directory`` (the only reliable test: root passes
    ``os.access`` on read-only or virtual file systems such as /proc)."""
    try:
        fd, tmp = tempfile.mkstemp(dir=directory, prefix=".bifilar-write-test-")
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise InputError(f"{option} {shown}: cannot write in {directory} ({reason})") from None
    os.close(fd)
    with contextlib.suppress(OSError):
        os.unlink(tmp)


def check_output_dir(path: str | os.PathLike[str], option: str = "--out") -> Path:
    """Make sure ``path`` is, or can be created as, a writable directory.

    The directory is created (with its parents) and a file is written and deleted in it.

    Parameters
    ----------
    path
        The output directory.
    option
        The option that gave it, for the message.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    InputError
        If ``path`` or one of its parents is a file, or the directory cannot be created or
        written.
    """
    check_not_empty(path, option)
    shown = Path(path)
    path = Path(os.path.abspath(path))
    if path.exists() and not path.is_dir():
        raise InputError(f"{option} {shown}: is a file, not a directory")
    _existing_ancestor(path, option, shown)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise InputError(f"{option} {shown}: cannot create the directory ({reason})") from None
    _probe(path, option, shown)
    return Path(shown)


def check_output_file(path: str | os.PathLike[str], option: str = "--out") -> Path:
    """Make sure a file can be written at ``path`` (its directory is created if needed).

    Raises
    ------
    InputError
        If ``path`` is a directory, a parent is a file, or its directory cannot be created or
        written.
    """
    check_not_empty(path, option)
    shown = Path(path)
    path = Path(os.path.abspath(path))
    if path.is_dir():
        raise InputError(f"{option} {shown}: is a directory, expected a file name")
    if path.exists() and not os.access(path, os.W_OK):
        raise InputError(f"{option} {shown}: the file exists and is not writable")
    _existing_ancestor(path, option, shown)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise InputError(f"{option} {shown}: cannot create {path.parent} ({reason})") from None
    _probe(path.parent, option, shown)
    return Path(shown)


def check_scheduler_address(address: str) -> str:
    """Check the form of a dask scheduler address: ``[PROTOCOL://]HOST:PORT``.

    Parameters
    ----------
    address
        E.g. ``tcp://node12:8786``, ``tls://10.0.0.5:8786``, ``localhost:8786``.

    Returns
    -------
    str
        ``address`` unchanged.

    Raises
    ------
    InputError
        If the protocol is unknown, the host is empty or malformed, or the port is not a number
        in 1-65535.
    """
    hint = "expected PROTOCOL://HOST:PORT, e.g. tcp://node12:8786"
    scheme, sep, rest = address.partition("://")
    if not sep:
        scheme, rest = "tcp", address
    if scheme not in SCHEDULER_SCHEMES:
        raise InputError(f"--scheduler {address!r}: unknown protocol {scheme!r} (one of "
                         f"{', '.join(SCHEDULER_SCHEMES)}); {hint}")
    if scheme == "inproc":
        return address
    host, colon, port = rest.rpartition(":")
    if not colon or not host or not _HOST.match(host):
        raise InputError(f"--scheduler {address!r}: not a scheduler address; {hint}")
    if not port.isdigit() or not 1 <= int(port) <= 65535:
        raise InputError(f"--scheduler {address!r}: port {port!r} is not a number in "
                         f"1-65535; {hint}")
    return address


def check_target_file(path: str | os.PathLike[str], option: str = "--out") -> Path:
    """Make sure an output file inside a checked directory can be replaced: it is absent or a
    regular file (not a directory or a device, which the final rename would fail on after
    all the work).

    Raises
    ------
    InputError
        If ``path`` exists and is not a regular file.
    """
    path = Path(path)
    if path.exists() and not path.is_file():
        kind = "a directory" if path.is_dir() else "not a regular file"
        raise InputError(f"{option} {path.parent}: {path} is {kind}; the sweep writes its "
                         "archive there: move it away or choose another --out")
    return path


def process_alive(pid: int) -> bool:
    """Whether a process ``pid`` exists on this host (signal 0 checks without sending)."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by another user
        return True
    return True
