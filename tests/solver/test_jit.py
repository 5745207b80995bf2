"""solver.jit.njit: a cached kernel is compiled again when a module whose kernel it calls
changes, which numba's own cache misses (it checks the calling module's file only)."""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

from solver import curve_kernels
from solver.jit import callee_files

REPO = Path(__file__).resolve().parents[2]


def test_curve_kernels_depend_on_the_b_splines():
    # _curve calls bsplines.nurbs_eval: its cached code holds the B-spline evaluation
    assert [Path(f).name for f in callee_files(curve_kernels._curve.py_func)] == ["bsplines.py"]
    assert callee_files(curve_kernels._cross_into.py_func) == []


def _call(root: Path) -> str:
    env = {**os.environ, "PYTHONPATH": f"{root}{os.pathsep}{REPO}"}
    env.pop("NUMBA_CACHE_DIR", None)  # the cache beside the sources, in tmp_path
    code = "from pkg.b import g; print(g(1.0), g.stats.cache_hits.total())"
    return subprocess.run([sys.executable, "-c", code], env=env, check=True,
                          capture_output=True, text=True).stdout.split()


def test_an_edit_of_a_callees_module_recompiles_the_cached_caller(tmp_path):
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    callee = pkg / "a.py"
    callee.write_text(textwrap.dedent("""
        from solver.jit import njit

        @njit(cache=True)
        def f(x):
            return x + 1.0
    """))
    (pkg / "b.py").write_text(textwrap.dedent("""
        from solver.jit import njit
        from pkg.a import f

        @njit(cache=True)
        def g(x):
            return 2.0 * f(x)
    """))
    assert _call(tmp_path) == ["4.0", "0"]  # compiled
    assert _call(tmp_path) == ["4.0", "1"]  # loaded from the cache
    callee.write_text(callee.read_text().replace("x + 1.0", "x + 100.0"))
    st = callee.stat()  # a new modification time even on a coarse clock
    os.utime(callee, ns=(st.st_atime_ns, st.st_mtime_ns + 10**9))
    assert _call(tmp_path) == ["202.0", "0"]  # b.py unchanged, compiled again
