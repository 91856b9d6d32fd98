"""copi's kernels are cached by numba under a stamp of every copi file that holds kernels
(copi._kernel_cache): a callee's edit in another file recompiles its callers; a file
without kernels does not count; functions outside copi keep numba's own stamps."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

from copi._kernel_cache import ROOT, kernels_stamp
from copi.learning.kernels import safety_of
from copi.online._learnt_kernels import decide_learnt_rows
from copi.world._crowd_kernels import scan_agents


def _locator(dispatcher: object) -> str:
    return type(dispatcher._cache._impl._locator).__name__  # type: ignore[attr-defined]


def test_copi_s_kernels_are_stamped_by_every_kernel_file() -> None:
    for kernel in (safety_of, decide_learnt_rows, scan_agents):
        assert _locator(kernel).startswith("Copi"), kernel
        assert kernel._cache._impl._locator.get_source_stamp() == kernels_stamp()  # type: ignore[attr-defined]
    assert kernels_stamp() == kernels_stamp(ROOT)


def test_the_stamp_follows_the_kernel_files_only(tmp_path: Path) -> None:
    (tmp_path / "a.py").write_text("from numba import njit\n@njit(cache=True)\ndef f(x):\n"
                                   "    return g(x)\n")  # fmt: skip
    (tmp_path / "b.py").write_text("from numba import njit\n@njit(cache=True)\ndef g(x):\n"
                                   "    return x\n")  # fmt: skip
    (tmp_path / "c.py").write_text("X = 1\n")
    first = kernels_stamp(tmp_path)
    from copi import _kernel_cache

    def fresh() -> str:
        _kernel_cache._stamps.pop(tmp_path, None)
        return kernels_stamp(tmp_path)

    assert fresh() == first  # the same files, the same stamp
    (tmp_path / "c.py").write_text("X = 2\n")
    assert fresh() == first  # no kernel there
    (tmp_path / "b.py").write_text("from numba import njit\n@njit(cache=True)\ndef g(x):\n"
                                   "    return x + 1\n")  # fmt: skip
    assert fresh() != first  # the callee changed: a.py's kernel must recompile too


def test_functions_outside_copi_keep_numba_s_own_stamps(tmp_path: Path) -> None:
    path = tmp_path / "outside_copi_kernel.py"
    path.write_text("from numba import njit\n@njit(cache=True)\ndef h(x):\n    return x\n")
    spec = importlib.util.spec_from_file_location("outside_copi_kernel", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["outside_copi_kernel"] = module
    try:
        spec.loader.exec_module(module)
        assert not _locator(module.h).startswith("Copi")
        assert not path.resolve().is_relative_to(ROOT)
    finally:
        del sys.modules["outside_copi_kernel"]
