"""The compiler of the solver's kernels: numba's ``njit``, or a clear error if numba is missing.

Every compiled kernel module imports ``njit`` from here, so the dependency and its message are
stated once.

A kernel compiled with ``cache=True`` is kept in numba's on-disk cache and recompiled when the
source file of its own module changes (numba compares the file's modification time and size).
Its cached machine code also holds the kernels it calls from other modules, which numba does
not check: after an edit of ``solver/bsplines.py`` alone, ``solver/curve_kernels.py``'s kernels
would keep the old B-spline code. This ``njit`` therefore adds the source files of the kernels
that a kernel calls from other modules (and of those they call) to its cache's freshness
stamp, so that an edit of any of them compiles it again.
"""

from __future__ import annotations

import os
import types
from collections.abc import Callable
from typing import Any

try:
    import numba
    from numba.core.dispatcher import Dispatcher
except ImportError as exc:  # a hard dependency: say how to get it
    raise ImportError("bifilar's compiled kernels need numba: pip install 'numba>=0.59' "
                      "(a wheel for every supported platform is on PyPI)") from exc

__all__ = ["njit"]


def njit(*args: Any, **options: Any) -> Any:
    """``numba.njit`` (same arguments, bare or called), whose on-disk cache of a kernel is
    also invalidated by an edit of a module whose kernels it calls."""
    if args and callable(args[0]):  # @njit
        return _tie_cache(numba.njit(*args, **options))
    decorate = numba.njit(*args, **options)

    def wrap(func: Callable[..., Any]) -> Any:
        return _tie_cache(decorate(func))

    return wrap


def _names(code: types.CodeType) -> set[str]:
    """The global names a function's code (and the code of functions nested in it) uses."""
    names = set(code.co_names)
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            names |= _names(const)
    return names


def callee_files(func: Callable[..., Any], _seen: set[int] | None = None) -> list[str]:
    """The source files of the kernels ``func`` calls, directly or through other kernels,
    sorted; ``func``'s own module left out."""
    seen = set() if _seen is None else _seen
    seen.add(id(func))
    found: set[str] = set()
    for name in _names(func.__code__):
        obj = func.__globals__.get(name)
        if isinstance(obj, Dispatcher) and id(obj.py_func) not in seen:
            found.add(obj.py_func.__code__.co_filename)
            found.update(callee_files(obj.py_func, seen))
    found.discard(func.__code__.co_filename)
    return sorted(found)


def _stamp(path: str) -> tuple[str, float, int] | None:
    try:
        st = os.stat(path)
    except OSError:
        return None
    return (os.path.basename(path), st.st_mtime, st.st_size)


def _tie_cache(dispatcher: Any) -> Any:
    """Make ``dispatcher``'s cache freshness stamp (which numba stores in the cache index and
    compares on loading) include the source stamps of the kernels it calls from other modules.

    The callees are looked up when numba first reads the stamp (the kernel's first call), not
    here: a kernel may call one defined further down its module. The stamp is a private
    attribute of numba's cache file: with a numba that lays it out otherwise, nothing is
    changed (the cache then works as numba's own).
    """
    cache_file = getattr(getattr(dispatcher, "_cache", None), "_cache_file", None)
    if cache_file is None or "_source_stamp" not in vars(cache_file):
        return dispatcher  # not cached, or another numba
    cache_file._own_stamp = vars(cache_file).pop("_source_stamp")
    cache_file._py_func = dispatcher.py_func
    cache_file.__class__ = _tied_class(type(cache_file))
    return dispatcher


_TIED: dict[type, type] = {}


def _tied_class(base: type) -> type:
    """``base`` (numba's cache file class) with a ``_source_stamp`` that adds the callees'."""
    if base not in _TIED:

        def get(self: Any) -> Any:
            files = callee_files(self._py_func)
            if not files:
                return self._own_stamp
            return (self._own_stamp, tuple(_stamp(path) for path in files))

        def put(self: Any, value: Any) -> None:
            self._own_stamp = value

        _TIED[base] = type(f"Tied{base.__name__}", (base,),
                           {"_source_stamp": property(get, put)})
    return _TIED[base]
