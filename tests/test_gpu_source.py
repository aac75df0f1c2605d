"""A check of the GPU kernels' source that needs no GPU and no numba-cuda.

Numba's CUDA target compiles no NumPy ufunc (``np.sqrt`` in a kernel fails at its first launch with
``KeyError: <ufunc 'sqrt'>``), but the CUDA simulator the other GPU tests run on executes the kernels as Python, where
NumPy works: such a call passes every simulator test and breaks every run on a device. That happened (the resident
route's ``fold`` kernel, found on a lent H200 on 27 November 2026; ``docs/performance.md``). So every function in
``jetgaudin.gpu`` decorated with ``cuda.jit`` is read here and must name no attribute of NumPy (``math`` has what they
need).
"""

from __future__ import annotations

import ast
from pathlib import Path

import jetgaudin

GPU = Path(jetgaudin.__file__).parent / "gpu"


def cuda_functions(tree: ast.AST):
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef) and any(
            "cuda" in ast.unparse(d) and "jit" in ast.unparse(d) for d in node.decorator_list
        ):
            yield node


def numpy_names(fn: ast.FunctionDef) -> set[str]:
    return {ast.unparse(n) for n in ast.walk(fn)
            if isinstance(n, ast.Attribute) and isinstance(n.value, ast.Name) and n.value.id in ("np", "numpy")}


def test_no_numpy_inside_a_cuda_kernel():
    found, bad = 0, {}
    for path in sorted(GPU.glob("*.py")):
        for fn in cuda_functions(ast.parse(path.read_text())):
            found += 1
            if names := numpy_names(fn):
                bad[f"{path.name}:{fn.name}"] = sorted(names)
    assert found >= 8  # the kernels and device functions of _kernels.py and _health.py: the scan sees them
    assert not bad, f"NumPy inside CUDA-compiled functions (use math): {bad}"


def test_the_scan_sees_a_planted_numpy_call():
    """The check itself bites: the bug it is for, planted in a copy of the health kernels' source."""
    src = (GPU / "_health.py").read_text()
    assert "math.sqrt(" in src
    planted = ast.parse(src.replace("math.sqrt(", "np.sqrt(", 1))
    assert any("np.sqrt" in numpy_names(fn) for fn in cuda_functions(planted))
