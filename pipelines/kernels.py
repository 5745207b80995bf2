"""The solver's compiled kernels on a first run: compiled once, in parallel, before the cases.

numba compiles a kernel at its first call and keeps it in its on-disk cache: ``__pycache__``
beside the solver's modules when that directory is writable (an editable or a user install),
else the user's cache directory (``~/.cache/numba`` on Linux), or ``NUMBA_CACHE_DIR`` when it
is set. A kernel is compiled again when its module's source file changes (numba compares the
file's modification time and size). Left to the cases, every dask worker of a first run would
compile the same kernels at the same time (2 × 25 s of CPU on a 2-core machine for the rotor).

Instead, before the cases start, :func:`warm_up_workers` runs the model's warm-up parts
(:attr:`studies.parameters.ModelSpec.warm_up`: tiny runs of the model, a small build and a few
steps, which call the very kernels its cases call, so that no kernel signature is listed by
hand) one per worker, at the same time: each worker compiles its part into the cache and the
cases then load all of it. A warm cache makes them cost a fraction of a second. ``bifilar
compile`` does the same without a sweep (:func:`warm_up_locally`), e.g. once after installing
on a cluster whose workers share the file system.
"""
from __future__ import annotations

import contextlib
import importlib
import multiprocessing
import pkgutil
import time
import uuid
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor
from typing import Any

from pipelines.worker import COMPILE_SECONDS, compile_notice, one_line
from studies.registry import resolve_model

# Dask event topic prefix of the warm-up's lines; one topic per warm-up.
WARM_UP_TOPIC = "bifilar-warm-up"


def kernels(package: str = "solver") -> dict[str, Any]:
    """Every numba-compiled function of ``package``'s modules, by ``module.name``.

    Imports the package's modules (what their kernels need), not the kernels' compilation.
    """
    from numba.core.dispatcher import Dispatcher

    found: dict[str, Any] = {}
    root = importlib.import_module(package)
    for info in pkgutil.iter_modules(root.__path__, f"{package}."):
        module = importlib.import_module(info.name)
        for name, obj in vars(module).items():
            # a kernel imported from another module is listed under its own module only
            if isinstance(obj, Dispatcher) and obj.py_func.__module__ == info.name:
                found[f"{info.name}.{name}"] = obj
    return found


def cache_dir(kernel: Any) -> str | None:
    """The directory where numba caches ``kernel`` (``None`` for a kernel it does not
    cache)."""
    return kernel.stats.cache_path


@contextlib.contextmanager
def counting_compiles() -> Iterator[list[int]]:
    """Count the kernels numba compiles (cache misses) in this process inside the block.

    Yields a one-element list, the count so far (numba raises its ``numba:compile`` event only
    for a kernel it does not load from its cache). numba's own functions that it compiles
    along (its implementations of NumPy's) are not counted.
    """
    from numba.core import event

    count = [0]

    class Counter(event.Listener):
        def on_start(self, ev: Any) -> None:
            module = getattr(ev.data["dispatcher"].py_func, "__module__", "") or ""
            if not module.startswith("numba."):
                count[0] += 1

        def on_end(self, ev: Any) -> None:
            pass

    with event.install_listener("numba:compile", Counter()):
        yield count


def warm_up_part(model_ref: str, index: int,
                 say: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Run the model's warm-up part ``index`` (:attr:`ModelSpec.warm_up`) in this process.

    Never raises for the part itself: a failure is returned as its message, and the cases
    then compile what the part did not (a warm-up only saves time).

    Parameters
    ----------
    model_ref
        Registry name or ``"module:attribute"`` of the model (resolved in this process).
    index
        Which part.
    say
        Told :func:`first_line` once, when numba starts compiling (a cold cache).

    Returns
    -------
    dict
        ``compiled`` (kernels compiled, 0 when the cache was warm), ``seconds`` (the part's
        wall time), ``error`` (``""`` or the failure in one line) and ``cache`` (numba's cache
        directory of the solver's kernels, or ``None``).
    """
    start = time.perf_counter()
    error = ""
    with counting_compiles() as count, \
            compile_notice(say if say is not None else (lambda line: None), first_line()):
        try:
            resolve_model(model_ref).warm_up[index]()
        except Exception as exc:  # a warm-up only saves time: the cases still run
            error = one_line(exc)
    return {"compiled": count[0], "seconds": time.perf_counter() - start, "error": error,
            "cache": _solver_cache_dir()}


def _solver_cache_dir() -> str | None:
    with contextlib.suppress(Exception):  # only for the progress line
        from solver.system import _scatter_add

        return cache_dir(_scatter_add)
    return None


def _report(results: Sequence[dict[str, Any]], elapsed: float,
            say: Callable[[str], None]) -> None:
    """The warm-up's closing line: how long the compilation took and where the kernels are
    (nothing when every part loaded its kernels from the cache)."""
    errors = [r["error"] for r in results if r["error"]]
    for error in errors:
        say(f"warning: compiling kernels ahead failed ({error}); the cases compile them")
    compiled = sum(r["compiled"] for r in results)
    if compiled:
        where = next((r["cache"] for r in results if r["cache"]), None)
        # (no count: two parts at once may both compile a kernel they share)
        say(f"kernels compiled in {elapsed:.1f} s"
            + (f", cached in {where}" if where else "") + " for the next runs")


def first_line() -> str:
    """The line that says numba has started to compile the kernels."""
    return (f"compiling kernels (first run only, about {COMPILE_SECONDS} s on an idle "
            "2-core machine)...")


def warm_up_workers(client: Any, model_ref: str, say: Callable[[str], None]) -> None:
    """Run the model's warm-up parts on the cluster's workers, one part per worker at the same
    time, and wait for them; the sweep's cases then load the kernels from numba's cache.

    Says ``compiling kernels (first run only …)`` when a worker starts compiling, and at the
    end how many seconds the compilation took. Does nothing for a model without
    warm-up parts. On workers that do not share a file system, each part's kernels are cached
    only where it ran, and the other workers compile them in their first case.

    Parameters
    ----------
    client
        The sweep's ``distributed.Client``.
    model_ref
        The study's model (registry name or ``"module:attribute"``).
    say
        Prints a progress line.
    """
    parts = len(resolve_model(model_ref).warm_up)
    workers = sorted(client.scheduler_info().get("workers", {}))
    if not parts or not workers:
        return
    topic = f"{WARM_UP_TOPIC}-{uuid.uuid4().hex[:12]}"
    told = False

    def handle(event: tuple[float, Any]) -> None:
        nonlocal told
        if not told:  # one line for all the parts
            told = True
            say(str(event[1].get("message", first_line())))

    client.subscribe_topic(topic, handle)
    start = time.perf_counter()
    futures = [client.submit(_warm_up_task, model_ref, i, topic,
                             workers=[workers[i % len(workers)]], allow_other_workers=True,
                             pure=False, key=f"bifilar-warm-up-{i}-{uuid.uuid4().hex[:8]}")
               for i in range(parts)]
    try:
        results = []
        for future in futures:
            try:
                results.append(future.result())
            except Exception as exc:  # the worker died: the cases will say what they can
                results.append({"compiled": 0, "seconds": float("nan"), "cache": None,
                                "error": one_line(exc)})
    finally:
        for future in futures:
            future.release()
        client.unsubscribe_topic(topic)
    _report(results, time.perf_counter() - start, say)


def _warm_up_task(model_ref: str, index: int, topic: str) -> dict[str, Any]:
    """:func:`warm_up_part` as a dask task: the first compile is sent on ``topic``."""
    from distributed import get_worker

    worker = get_worker()
    return warm_up_part(model_ref, index,
                        lambda line: worker.log_event(topic, {"message": line}))


def warm_up_locally(model_refs: Sequence[str], say: Callable[[str], None],
                    processes: int = 2) -> list[dict[str, Any]]:
    """Run the warm-up parts of ``model_refs`` in ``processes`` new processes at the same time
    (``bifilar compile``); the kernels are then in numba's cache for every later run.

    Returns
    -------
    list of dict
        Each part's :func:`warm_up_part` result, with ``model`` and ``part``.
    """
    jobs: list[tuple[str, int]] = []
    seen: list[Callable[[], None]] = []
    for ref in model_refs:
        for i, part in enumerate(resolve_model(ref).warm_up):
            if part not in seen:  # models share parts (the bifilars' of the hub and pendulum)
                seen.append(part)
                jobs.append((ref, i))
    if not jobs:
        return []
    start = time.perf_counter()
    # spawned, not forked: a fork of a process that has numba's compiler loaded is unsafe
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=max(1, min(processes, len(jobs))),
                             mp_context=context) as pool:
        say(f"loading or compiling the kernels of {', '.join(model_refs)} "
            f"({len(jobs)} parts on {min(processes, len(jobs))} processes)...")
        results = [{**r, "model": ref, "part": i}
                   for (ref, i), r in zip(jobs, pool.map(_warm_up_job, jobs), strict=True)]
    elapsed = time.perf_counter() - start
    _report(results, elapsed, say)
    if not any(r["compiled"] for r in results):
        say(f"every kernel was in the cache already ({elapsed:.1f} s)")
    return results


def _warm_up_job(job: tuple[str, int]) -> dict[str, Any]:
    return warm_up_part(*job)
