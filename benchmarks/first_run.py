"""First-run benchmark: compiling the solver's kernels into numba's cache, cold and warm.

    python benchmarks/first_run.py [--model rotor] [--repeat 3] [--per-kernel] [--run]

Each repeat deletes the solver's kernels from numba's cache (the ``.nbi`` and ``.nbc`` files of
the solver's modules in the cache directory numba chose: ``solver/__pycache__`` in a writable
checkout) and times the model's warm-up (``bifilar compile --model MODEL``,
:func:`pipelines.kernels.warm_up_locally`): its parts on two processes at once (``cold``), in one
process after the other (``cold_serial``), and again with the cache full (``warm``).
``--per-kernel`` compiles the parts in this process and prints the kernels that take the
longest (numba's compile time of each, less that of the kernels it compiles along), and the
sums by module.
``--run`` also times ``bifilar run --model MODEL`` (the built-in study) from a cold and from a
warm cache, in a new process with its output in a temporary directory. Prints one JSON line
per measurement; the best of ``--repeat`` is what to quote, as another job on the same cores
slows any of them.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from pipelines.kernels import cache_dir, kernels, warm_up_locally
from studies.registry import resolve_model


def clear_cache() -> int:
    """Delete the solver's kernels from numba's cache; the number of files deleted."""
    found = kernels()
    modules = {name.rsplit(".", 1)[0].rsplit(".", 1)[-1] for name in found}
    dirs = {d for d in (cache_dir(k) for k in found.values()) if d}
    deleted = 0
    for d in dirs:
        for path in Path(d).glob("*.nb[ic]"):
            if path.name.split(".", 1)[0] in modules:
                path.unlink()
                deleted += 1
    return deleted


def warm_up(model: str, processes: int) -> float:
    """Wall seconds of the model's warm-up on ``processes`` processes."""
    start = time.perf_counter()
    results = warm_up_locally([model], lambda line: None, processes)
    errors = [r["error"] for r in results if r["error"]]
    if errors:
        raise SystemExit(f"warm-up failed: {errors}")
    return time.perf_counter() - start


def per_kernel(model: str, top: int) -> list[dict[str, Any]]:
    """Compile the model's warm-up parts in this process (cache cleared first) and return the
    ``top`` kernels by exclusive compile time."""
    from numba.core import event

    stack: list[list[Any]] = []
    totals: dict[str, float] = {}

    class Timer(event.Listener):
        def on_start(self, ev: Any) -> None:
            stack.append([ev.data["dispatcher"], time.perf_counter(), 0.0])

        def on_end(self, ev: Any) -> None:
            disp, t0, inner = stack.pop()
            took = time.perf_counter() - t0
            if stack:
                stack[-1][2] += took
            f = disp.py_func
            name = f"{f.__module__}.{f.__qualname__}"
            totals[name] = totals.get(name, 0.0) + took - inner

    clear_cache()
    with event.install_listener("numba:compile", Timer()):
        for part in resolve_model(model).warm_up:
            part()
    ranked = sorted(totals.items(), key=lambda kv: -kv[1])
    modules: dict[str, float] = {}
    for name, seconds in totals.items():
        # numba's own functions (its NumPy implementations) together, the solver's by module
        module = "numba" if name.startswith("numba.") else name.split(".<locals>")[0]
        module = module if module == "numba" else module.rsplit(".", 1)[0]
        modules[module] = modules.get(module, 0.0) + seconds
    by_module = sorted(modules.items(), key=lambda kv: -kv[1])
    return ([{"kernel": k, "compile_s": round(s, 2)} for k, s in ranked[:top]]
            + [{"module": m, "compile_s": round(s, 2)} for m, s in by_module]
            + [{"kernel": "all", "compile_s": round(sum(totals.values()), 2),
                "count": len(totals)}])


def run_study(model: str, cold: bool) -> float:
    """Wall seconds of ``bifilar run --model MODEL`` in a new process."""
    if cold:
        clear_cache()
    out = Path(tempfile.mkdtemp(prefix="first-run-"))
    try:
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "pipelines.cli", "run", "--model", model,
                        "--out", str(out)], check=True, stdout=subprocess.DEVNULL)
        return time.perf_counter() - start
    finally:
        shutil.rmtree(out, ignore_errors=True)


def main() -> None:
    a = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    a.add_argument("--model", default="rotor")
    a.add_argument("--repeat", type=int, default=3)
    a.add_argument("--per-kernel", action="store_true")
    a.add_argument("--top", type=int, default=12)
    a.add_argument("--run", action="store_true", help="also time the built-in study")
    args = a.parse_args()
    for _ in range(args.repeat):
        clear_cache()
        cold = warm_up(args.model, 2)
        warm = warm_up(args.model, 2)
        clear_cache()
        serial = warm_up(args.model, 1)
        print(json.dumps({"model": args.model, "cold_s": round(cold, 1),
                          "cold_serial_s": round(serial, 1), "warm_s": round(warm, 1)}),
              flush=True)
        if args.run:
            print(json.dumps({"model": args.model,
                              "run_cold_s": round(run_study(args.model, True), 1),
                              "run_warm_s": round(run_study(args.model, False), 1)}),
                  flush=True)
    if args.per_kernel:
        for row in per_kernel(args.model, args.top):
            print(json.dumps(row))


if __name__ == "__main__":
    main()
