"""The top as a one-site model (issue 33): its two-point map at the top's speed, side by side in one run.

Three calls of the compiled two-point map on the same orbits (Appendix 2: N = 3, b = 1, η = 5 + 0.1i), each the
public call a user makes (``iterate``, every row returned):

* ``top``   -- ``jg.TwoPointBacklund(b, η, backend="compiled")``;
* ``model`` -- ``jg.GaudinTop(3, b).model.two_point_backlund(η, backend="compiled")``: the one-site model, which
  takes the top's kernels as a route (``GaudinModel.is_top``, ``docs/architecture.md``);
* ``chain kernel`` -- the same model on the chains' rational kernel (``gaudin/_kernels.py``), the route it took
  before: what the route-table entry buys.

One orbit of ``steps`` steps (CPU time of this thread) and a batch of ``orbits`` orbits (wall time: it may use
several threads), ``harness.timed``, the routes interleaved, median of ``repeat``; the kernels are compiled (or
loaded) before the timing.  Ratios are against ``top`` in the same run;
the target is ``model`` within ±10 % of ``top``.  ``python benchmarks/top_as_model.py [repeat]``
"""

from __future__ import annotations

import importlib.util
import platform
import sys
import time
from pathlib import Path

import numpy as np

import jetgaudin as jg

HERE = Path(__file__).resolve().parent
_spec = importlib.util.spec_from_file_location("_bench_harness", HERE / "harness.py")
harness = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = harness
assert _spec.loader is not None
_spec.loader.exec_module(harness)


def _chain_kernel(model_map, X, steps):
    """The model's map on the chains' own rational kernel (the route before the top entry)."""
    name, _, run = model_map._kernel()
    assert name == "_kernels"
    Xb = np.atleast_2d(X)
    nu = model_map._compiled_start(Xb)
    return [run(np.ascontiguousarray(x), complex(n), steps, 1) for x, n in zip(Xb, nu, strict=True)]


def main(repeat: int = 7, steps: int = 100_000, orbits: int = 64) -> None:
    b, eta = harness.B_APPENDIX2, harness.ETA_APPENDIX2
    X0 = harness.X0_APPENDIX2
    rng = np.random.default_rng(0)
    Xb = X0 * (1 + 0.01 * rng.standard_normal((orbits, X0.size)))
    top = jg.TwoPointBacklund(b, eta, backend="compiled")
    model = jg.GaudinTop(3, b).model.two_point_backlund(eta, backend="compiled")
    assert np.array_equal(top.iterate(X0, 10), model.iterate(X0, 10))  # the same route: the same bits
    cases = {"one orbit": (X0, steps), f"{orbits} orbits": (Xb, steps // 100)}
    print(f"machine: {harness.machine_info().get('Model name', platform.machine())}; repeat {repeat}")
    print(f"{'call':<12} {'route':<14} {'median s':>10} {'ratio to top':>13}")
    for label, (X, n) in cases.items():
        calls = {"top": lambda X=X, n=n: top.iterate(X, n), "model": lambda X=X, n=n: model.iterate(X, n),
                 "chain kernel": lambda X=X, n=n: _chain_kernel(model, X, n)}
        for f in calls.values():
            f()  # compile / load outside the timing
        clock = time.thread_time if X.ndim == 1 else time.perf_counter  # a batch may run on several threads
        times: dict[str, list] = {k: [] for k in calls}
        names = list(calls)
        for r in range(repeat):  # interleaved, the order rotated: load changes and warm-ups touch every route alike
            for k in names[r % 3:] + names[:r % 3]:
                times[k].extend(harness.timed(calls[k], 1, clock))
        ref = float(np.median(times["top"]))
        for route, t in times.items():
            med = float(np.median(t))
            print(f"{label:<12} {route:<14} {med:>10.4g} {med / ref:>13.3f}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 7)
