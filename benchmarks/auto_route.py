"""The route ``backend="auto"`` picks for the chain maps, against the fastest one (issue 33: never 3x slower).

    python benchmarks/auto_route.py                 # every family, one orbit and 50 orbits, ~1 min
    python benchmarks/auto_route.py --batch 1 --steps 300,3000

For every family (rational, trigonometric, elliptic; a chain of M = 3 components), each batch size and step count,
prints the measured seconds of the NumPy route and of the compiled route (kernels loaded in this process: the set-up
of a fresh process, loading or compiling them, is the estimate of ``jetgaudin.gaudin._backend``, printed beside),
the measured NumPy step against the cost model's estimate, the route AUTO picks with the kernels loaded, cached and
cold, and the ratio of the picked route's time to the fastest (must be < 3).  Wall time (``time.perf_counter``) on a
machine that may be shared: run it on a quiet one.
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np

from jetgaudin.gaudin import GaudinModel
from jetgaudin.gaudin import _backend as rule

SITES = [(-0.5, 1), (0.4, 2)]
MODELS = {
    "rational": GaudinModel(1.0, SITES),
    "trigonometric": GaudinModel(1.0, SITES, family="trigonometric", gamma=1.0),
    "elliptic": GaudinModel(0.0, SITES, family="elliptic", modulus=0.6),
}
ETA = 1.5 + 0.2j


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--batch", default="1,50", help="orbits per call, comma-separated")
    ap.add_argument("--steps", default="30,300,3000", help="steps per call, comma-separated")
    return ap


def seconds(B, X, steps: int, backend: str) -> float:
    m = B.with_backend(backend)
    m.advance(X, None, 1)  # compiled or loaded: not in the time
    t = time.perf_counter()
    m.advance(X, None, steps)
    return time.perf_counter() - t


def main(argv=None) -> None:
    args = parser().parse_args(argv)
    batches = [int(v) for v in args.batch.split(",")]
    steps_list = [int(v) for v in args.steps.split(",")]
    print(f"machine: {platform.processor() or platform.machine()}; M = 3 (sites {SITES}), eta = {ETA}")
    print(f"{'family':14s} {'B':>4s} {'steps':>6s} {'numpy s':>9s} {'est.':>9s} {'compiled s':>10s} "
          f"{'setup cached/cold (est.)':>25s} {'auto: loaded cached cold':>26s} {'worst ratio':>11s}")
    rng = np.random.default_rng(0)
    for name, model in MODELS.items():
        B = model.two_point_backlund(ETA)
        for batch in batches:
            X = 0.3 * rng.normal(size=(batch, model.n_state)) if batch > 1 else 0.3 * rng.normal(size=model.n_state)
            for steps in steps_list:
                t_np = seconds(B, X, steps, "numpy")
                t_c = seconds(B, X, steps, "compiled")
                picks, worst = [], 1.0
                setups = []
                for state in ("loaded", "cached", "cold"):
                    cost = rule.route_costs(model.family, model.M, batch, steps, state)
                    setups.append(cost.setup)
                    c = "compiled" if cost.compiled <= cost.numpy else "numpy"
                    picks.append(c)
                    real = {"numpy": t_np, "compiled": t_c + cost.setup}  # the set-up is the model's estimate
                    worst = max(worst, real[c] / min(real.values()))
                est = rule.route_costs(model.family, model.M, batch, steps, "loaded").numpy
                print(f"{name:14s} {batch:4d} {steps:6d} {t_np:9.3g} {est:9.3g} {t_c:10.3g} "
                      f"{setups[1]:12.2g}/{setups[2]:<12.2g} {' '.join(picks):>26s} {worst:11.2f}", flush=True)


if __name__ == "__main__":
    main()
