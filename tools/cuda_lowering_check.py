"""Lower the chains' GPU kernel (``gpu/_kernels.chain_kernel``: ``gaudin/_family_kernel.orbit_loop`` as a CUDA
device function) with Numba's CUDA front end on a machine without a GPU.

The CUDA simulator (``tests/test_gpu.py``) runs the kernels as Python and the loops as the CPU's compiled code, so it
cannot see what only the CUDA target refuses -- a NumPy ufunc (``np.sqrt``: ``KeyError: <ufunc 'sqrt'>`` on a real
H200), an allocation, an unsupported call.  Here the kernel is typed and lowered for compute capability 9.0 (the
device query stubbed); where the CUDA toolkit's NVRTC library is missing (no GPU toolkit installed) it stops after
lowering, which is the part that refuses such code.  Exit status 0: lowered (and PTX printed in size where NVRTC is
there); 1: the front end refused the kernel (the error printed).  Run with the simulator off:

``NUMBA_ENABLE_CUDASIM=0 PYTHONPATH=src python tools/cuda_lowering_check.py``
"""

from __future__ import annotations

import sys
import types as _pytypes


def main() -> int:
    from numba import cuda
    from numba import types as t
    from numba.cuda import dispatcher
    from numba.cuda.cudadrv import nvrtc

    from jetgaudin.gpu import _kernels as K

    # no device: its compute capability stubbed (9.0, the H100/H200), and the toolkit's list of targets
    dispatcher.get_current_device = lambda: _pytypes.SimpleNamespace(compute_capability=(9, 0))
    nvrtc.get_supported_ccs = lambda: [(9, 0)]
    K._bind()
    kernel = K.chain_kernel()
    f64, c128, i64 = t.float64, t.complex128, t.int64
    sig = (t.Array(f64, 2, "C"), f64, t.Array(c128, 1, "C"), t.Array(c128, 2, "C"), i64, t.Array(c128, 1, "C"),
           t.Array(c128, 4, "C"), t.Array(i64, 2, "C"), t.Array(i64, 1, "C"), t.Array(i64, 1, "C"), i64, i64,
           t.Array(f64, 3, "A"), t.Array(f64, 2, "C"), t.Array(c128, 1, "C"))
    try:
        ptx, _ = cuda.compile_ptx(kernel.py_func, sig, cc=(9, 0))
    except Exception as exc:  # noqa: BLE001  (the front end's errors have many types)
        if "nvrtc" in str(exc).lower() and type(exc).__name__ == "DynamicLibNotFoundError":
            print("chain kernel: typed and lowered for CUDA (cc 9.0); no NVRTC library here, so no PTX")
            return 0
        print(f"chain kernel: refused by Numba's CUDA front end: {type(exc).__name__}: {exc}")
        return 1
    print(f"chain kernel: PTX for cc 9.0, {len(ptx)} characters")
    return 0


if __name__ == "__main__":
    sys.exit(main())
