"""The benchmark harness of jetgaudin: timings of the compiled Bäcklund kernels against the NumPy route, heyoka
and Dask, in one run on one machine, as a table of medians (and best-of) with ratios.

Run it as ``python benchmarks/bench_backlund.py`` (writes the Markdown table of ``docs/performance.md``) or
``jetgaudin bench`` from a source checkout (the command loads this file).  Single-thread timings use the
thread's CPU time (:func:`time.thread_time`, robust to other processes on a shared machine); multi-thread
timings use wall time.  No mathematics here: everything numerical comes from the public API and
:mod:`jetgaudin.backlund.kernels`.  Parts needing heyoka or Dask are skipped with a note when those are missing.

Parts: (a) one orbit, compiled vs NumPy; (b) Appendix 2 work vs heyoka; (c, d) ensembles on 1 and 2 threads (and
in 2 processes × 1 thread at once: the two-core ceiling) and the flop rate; (e) N = 1..5; (f) the main job in a
fresh process; (g) memory of a long run; (h) the fixed cost of short calls; (i) first-use compile time; (j) Dask
LocalCluster vs threads (h-j: ``speed_parts.py``); (k) the parts of a call's per-orbit set-up and (l) cold compile
kernel by kernel (``setup_parts.py``); (m) per-step accuracy of the compiled N = 3 and generic routes against the
NumPy route (``speed_parts.py``).
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import time
from dataclasses import dataclass, field

import numpy as np

__all__ = ["PARTS", "Row", "timed", "run_benchmarks", "machine_info", "rows_to_markdown", "rows_to_text"]

#: the letters of the parts, in order
PARTS = "abcdefghijklm"

X0_APPENDIX2 = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1.0, 0.0, 0.0])
B_APPENDIX2 = 1.0
ETA_APPENDIX2 = 5 + 0.1j


@dataclass
class Row:
    part: str
    what: str
    value: float
    unit: str
    note: str = ""
    extra: dict = field(default_factory=dict)


def timed(fn, repeat: int, clock=time.thread_time) -> np.ndarray:
    """The durations of ``repeat`` calls of ``fn()`` on ``clock``: :func:`time.thread_time` (CPU time of this
    thread: single-thread work, robust to other processes) or :func:`time.perf_counter` (wall: work on several
    threads or processes).  The one timing loop of the benchmarks; callers take the median and the best."""
    out = []
    for _ in range(repeat):
        t = clock()
        fn()
        out.append(clock() - t)
    return np.array(out)


def machine_info() -> dict:
    """CPU model, core count, frequency and load from ``lscpu`` / ``/proc`` (Linux)."""
    info = {"python": sys.version.split()[0], "platform": platform.platform()}
    try:
        lscpu = subprocess.run(["lscpu"], capture_output=True, text=True, timeout=10).stdout
        for line in lscpu.splitlines():
            k, _, v = line.partition(":")
            if k.strip() in (
                "Model name",
                "CPU(s)",
                "Thread(s) per core",
                "L1d cache",
                "L2 cache",
                "L3 cache",
                "Hypervisor vendor",
            ):
                info[k.strip()] = v.strip()
        info["avx512f"] = "avx512f" in lscpu
        info["fma"] = " fma " in lscpu
    except (OSError, subprocess.SubprocessError):
        pass
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("cpu MHz"):
                    info["MHz"] = float(line.split(":")[1])
                    break
        info["loadavg"] = os.getloadavg()
    except OSError:
        pass
    import numba

    import jetgaudin

    info["numba"] = numba.__version__
    info["numpy"] = np.__version__
    info["jetgaudin"] = jetgaudin.__version__
    return info


def _peak_gflops(info, cores) -> float:
    """Double-precision peak: cores × GHz × flops/cycle (AVX-512 with two FMA units: 32; AVX2+FMA: 16)."""
    per_cycle = 32 if info.get("avx512f") else (16 if info.get("fma") else 4)
    return cores * info.get("MHz", 2000.0) / 1000.0 * per_cycle


def bench_single(rows, steps=10**6, numpy_steps=2000, repeat=5):
    """(a) one orbit, N = 3: compiled (N = 3 kernel and generic route) vs the NumPy route."""
    import jetgaudin as jg

    B = jg.TwoPointBacklund(B_APPENDIX2, ETA_APPENDIX2)
    B.iterate(X0_APPENDIX2, 10, kernel="compiled")  # load / compile
    t3 = timed(lambda: B.iterate(X0_APPENDIX2, steps, save_every=1000, kernel="compiled"), repeat)
    from jetgaudin.backlund import kernels as _kernels

    nu0 = _kernels.nu_default(X0_APPENDIX2[None], [B.b], [B.eta])[0]
    _kernels.iterate_single(X0_APPENDIX2, B.b, B.eta, nu0, False, 10, 10, specialise=False)
    tg = timed(
        lambda: _kernels.iterate_single(X0_APPENDIX2, B.b, B.eta, nu0, False, steps, 1000, specialise=False), repeat
    )
    tn = timed(lambda: B.iterate(X0_APPENDIX2, numpy_steps, kernel="numpy"), 3)
    per_np = np.median(tn) / numpy_steps
    r3 = steps / np.median(t3)
    rows.append(
        Row(
            "a",
            f"N=3 kernel, {steps:.0e} steps",
            r3,
            "steps/s",
            f"best {steps / t3.min():.3g}; median of {repeat}; {np.median(t3):.3f} s",
        )
    )
    rows.append(Row("a", "N=3 generic route", steps / np.median(tg), "steps/s", f"best {steps / tg.min():.3g}"))
    rows.append(
        Row(
            "a",
            "NumPy route",
            1 / per_np,
            "steps/s",
            f"measured on {numpy_steps} steps, extrapolated per step to {steps:.0e}: {per_np * steps:.0f} s",
        )
    )
    rows.append(Row("a", "ratio compiled / NumPy", r3 * per_np, "x", "median vs median"))


def bench_appendix2(rows, repeat=50):
    """(b) Appendix 2 work: 1000 samples of the flow of G_η: the map vs heyoka's propagate_grid."""
    import heyoka as hy

    import jetgaudin as jg
    from jetgaudin.backlund import kernels as _kernels
    from jetgaudin.flows import _heyoka_system

    B = jg.TwoPointBacklund(B_APPENDIX2, ETA_APPENDIX2)
    n = 1000
    orbit = B.iterate(X0_APPENDIX2, n, kernel="compiled")
    tm = timed(lambda: B.iterate(X0_APPENDIX2, n, kernel="compiled"), repeat)
    nu0 = _kernels.nu_default(X0_APPENDIX2[None], [B_APPENDIX2], [ETA_APPENDIX2])[0]
    tk = timed(lambda: _kernels.iterate_single(X0_APPENDIX2, B_APPENDIX2, ETA_APPENDIX2, nu0, False, n, 1,
                                               want_drift=False), repeat)
    tnu = timed(lambda: _kernels.nu_default(X0_APPENDIX2[None], [B_APPENDIX2], [ETA_APPENDIX2]), repeat)
    _kernels.closed_form_orbit(X0_APPENDIX2, B_APPENDIX2, ETA_APPENDIX2, nu0, 2)
    tcf = timed(lambda: _kernels.closed_form_orbit(X0_APPENDIX2, B_APPENDIX2, ETA_APPENDIX2, nu0, n), repeat)
    cf = _kernels.closed_form_orbit(X0_APPENDIX2, B_APPENDIX2, ETA_APPENDIX2, nu0, n)
    ref_np = B.iterate(X0_APPENDIX2, n, kernel="numpy")
    t0 = time.perf_counter()
    H = jg.interpolating_flow_hamiltonian(X0_APPENDIX2, B_APPENDIX2, ETA_APPENDIX2)
    t_weights = time.perf_counter() - t0
    grid = np.arange(n + 1, dtype=float)
    sys_ = _heyoka_system(H, 9)

    def hey(tol):
        t0 = time.perf_counter()
        kw = {} if tol is None else {"tol": tol}  # None: heyoka's default tolerance (machine epsilon)
        ta = hy.taylor_adaptive(sys_, X0_APPENDIX2.copy(), **kw)
        t_comp = time.perf_counter() - t0

        def run():
            ta.time = 0.0
            ta.state[:] = X0_APPENDIX2
            return ta.propagate_grid(grid)

        res = run()
        t = timed(run, repeat)
        return np.asarray(res[-1]), t, t_comp

    ref, _, _ = hey(1e-18)  # heyoka at its highest order: the reference of the flow of G_eta
    err_map = np.max(np.abs(orbit - ref))
    chosen = None
    for tol in (1e-9, 1e-10, 1e-11, 1e-12, 1e-13, 1e-14, 1e-15):
        X, t, tc = hey(tol)
        err = np.max(np.abs(X - ref))
        chosen = (tol, X, t, tc, err)
        if err <= 1e-12:
            break
    tol, X, th, tc, err_h = chosen
    rows.append(Row("b", "map, iterate(): 1000 steps incl. ν1 setup", np.median(tm) * 1e3, "ms",
                    f"best {tm.min() * 1e3:.3f} ms; max |map − heyoka(tol 1e-18)| = {err_map:.1e}; "
                    f"max |compiled − NumPy route| = {np.max(np.abs(orbit - ref_np)):.1e}"))
    rows.append(Row("b", "map kernel: 1000 steps given ν1", np.median(tk) * 1e3, "ms",
                    f"best {tk.min() * 1e3:.3f} ms; ν1 setup (branch rule, roots) {np.median(tnu) * 1e3:.3f} ms"))
    rows.append(Row("b", f"heyoka propagate_grid, tol={tol:g}", np.median(th) * 1e3, "ms",
                    f"best {th.min() * 1e3:.3f} ms; max |heyoka(tol) − heyoka(1e-18)| = {err_h:.1e}; "
                    f"taylor_adaptive compile {tc:.2f} s and G_eta weights {t_weights * 1e3:.1f} ms (apart)"))
    rows.append(Row("b", "ratio heyoka / map kernel", np.median(th) / np.median(tk), "x", "median vs median"))
    rows.append(Row("b", "ratio heyoka / map iterate()", np.median(th) / np.median(tm), "x", "median vs median"))
    Xd, td, _ = hey(None)
    rows.append(Row("b", "heyoka propagate_grid, default tol", np.median(td) * 1e3, "ms",
                    f"best {td.min() * 1e3:.3f} ms; max |heyoka(default) − heyoka(1e-18)| = "
                    f"{np.max(np.abs(Xd - ref)):.1e}"))
    rows.append(Row("b", "ratio heyoka(default tol) / map iterate()", np.median(td) / np.median(tm), "x",
                    "median vs median; target >= 3"))
    rows.append(Row("b", "Appendix 1 closed form (njit): 1000 steps", np.median(tcf) * 1e3, "ms",
                    f"best {tcf.min() * 1e3:.3f} ms; max |closed form − NumPy route| = "
                    f"{np.max(np.abs(cf - ref_np)):.1e} (parametrised by s: less accurate, infinite at k1 = 0)"))


def bench_fresh_process(rows):
    """The main job (1000 steps) timed in a fresh process: compiled (warm cache) vs NumPy."""
    code = (
        "import time, numpy as np, jetgaudin as jg\n"
        "X0 = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0])\n"
        "B = jg.TwoPointBacklund(1.0, 5 + 0.1j)\n"
        "t = time.perf_counter(); B.iterate(X0, 1000, kernel='{k}'); print(time.perf_counter() - t)\n"
    )
    out = {}
    for k in ("compiled", "numpy"):
        vals = []
        for _ in range(3):
            r = subprocess.run([sys.executable, "-c", code.format(k=k)], capture_output=True, text=True, timeout=300)
            vals.append(float(r.stdout.strip().splitlines()[-1]))
        out[k] = float(np.median(vals))
    rows.append(
        Row(
            "f",
            "main job, fresh process, compiled (warm cache)",
            out["compiled"] * 1e3,
            "ms",
            "includes importing numba and loading the cached kernels",
        )
    )
    rows.append(Row("f", "main job, fresh process, NumPy", out["numpy"] * 1e3, "ms", ""))


def bench_ensembles(rows, sizes=((10**3, 100), (10**5, 100), (10**5, 1000), (10**6, 100)), info=None,
                    processes_size=(10**5, 100)):
    """(c, d) ensembles of N = 3 orbits (B orbits × steps, for each pair of ``sizes``) on 1 and 2 threads; flop rate
    vs peak.  For the size ``processes_size`` also the machine's two-core ceiling without Numba's threads: the
    1-thread rate of the same work in one fresh process alone, then in each of 2 processes running it at the same
    time (``speed_parts.process_rates``: a barrier, only the overlapping calls count), and their sum."""
    import numba

    from jetgaudin import ensemble as ens
    from jetgaudin.backlund import kernels as _kernels
    from jetgaudin.backlund.kernels import flops_per_step

    flops = flops_per_step(3)["total"]
    nmax = numba.config.NUMBA_NUM_THREADS
    rng = np.random.default_rng(1)
    for B, steps in sizes:
        t0 = time.perf_counter()
        X0 = ens.sample_on_leaf(3, [0.5, 0.2, 1.0], B, seed=2)
        b = np.full(B, 1.0)
        eta = 5.0 + rng.uniform(-0.5, 0.5, B) + 0.1j
        nu0 = _kernels.nu_default(X0, b, eta, 1)
        t_setup = time.perf_counter() - t0
        rate = {}
        for threads in (1, 2):
            if threads > nmax:
                continue
            numba.set_num_threads(threads)
            _kernels.run_batch(X0[:4], b[:4], eta[:4], nu0[:4], False, 2, 1, True)
            rep = 3 if B <= 10**5 else 1
            t = timed(
                lambda X0=X0, b=b, eta=eta, nu0=nu0, steps=steps: _kernels.run_batch(X0, b, eta, nu0, False, steps,
                                                                                      steps),
                rep,
                clock=time.perf_counter,
            )
            rate[threads] = B * steps / np.median(t)
            rows.append(
                Row(
                    "c",
                    f"ensemble {B:.0e} × {steps}, {threads} thread(s)",
                    rate[threads],
                    "orbit-steps/s",
                    f"best {B * steps / t.min():.3g}; kernel only (set-up: sampling and ν1 {t_setup:.2f} s)",
                )
            )
        numba.set_num_threads(nmax)
        if 2 in rate:
            rows.append(Row("c", f"ensemble {B:.0e} × {steps}: 2 threads / 1 thread", rate[2] / rate[1], "x", ""))
        if (B, steps) == tuple(processes_size):
            _bench_two_processes(rows, X0, b, eta, nu0, steps, rate)
        if 2 in rate:
            peak = _peak_gflops(info or machine_info(), 2)
            rows.append(
                Row(
                    "d",
                    f"ensemble {B:.0e} × {steps}, 2 threads: flop rate",
                    rate[2] * flops / 1e9,
                    "GFLOP/s",
                    f"{flops} flops/step (flops_per_step); {100 * rate[2] * flops / 1e9 / peak:.2f} % of "
                    f"peak {peak:.0f} GFLOP/s",
                )
            )


def _bench_two_processes(rows, X0, b, eta, nu0, steps, rate, rounds=2):
    """(c) rows of the 1-thread rate in 1 process alone and in each of 2 processes at once (wall; CPU-time rates,
    hypervisor steal and the load in the notes), alternated ``rounds`` times (means over the rounds), next to the
    1- and 2-thread rows of ``rate``."""
    proc = _sibling("speed_parts").process_rates
    B = X0.shape[0]
    runs: dict[int, list[dict]] = {1: [], 2: []}
    for _ in range(rounds):
        for n in (1, 2):
            runs[n].append(proc(X0, b, eta, nu0, steps, n))

    def mean(n, key):  # per process, over the rounds
        return np.mean([r[key] for r in runs[n]], axis=0)

    alone, each, cpu1, cpu2 = mean(1, "wall")[0], mean(2, "wall"), mean(1, "cpu")[0], mean(2, "cpu")
    head = f"ensemble {B:.0e} × {steps}"
    kept = "+".join(str(k) for r in runs[2] for k in r["kept"])
    rows.append(Row("c", f"{head}, 1 process × 1 thread, alone", alone, "orbit-steps/s",
                    f"fresh process, NUMBA_NUM_THREADS=1, wall; CPU-time rate {cpu1:.3g}; mean of {rounds} rounds "
                    "alternated with the 2-process runs"))
    rows.append(Row("c", f"{head}, 2 processes × 1 thread, each", float(np.mean(each)), "orbit-steps/s",
                    "processes " + ", ".join(f"{w:.3g}" for w in each) + " (wall); CPU-time rates "
                    + ", ".join(f"{c:.3g}" for c in cpu2) + f"; calls inside the overlap {kept}; hypervisor steal "
                    f"{100 * max(r['steal'] for r in runs[2]):.1f} %; load {os.getloadavg()[0]:.2f}"))
    total = float(np.sum(each))
    vs = f"; the 2-thread row is {rate[2] / total:.2f} × this" if 2 in rate else ""
    rows.append(Row("c", f"{head}, 2 processes × 1 thread, sum", total, "orbit-steps/s",
                    f"{total / alone:.2f} × one process alone (2 = two independent cores){vs}.  The two-core "
                    "ceiling without Numba's threads: a CPU-time rate below the one alone = the cores slow each "
                    "other (shared cache, memory, hypervisor); a wall rate below the CPU-time rate = other jobs"))


def bench_generic(rows, steps=10**5, numpy_steps=300):
    """(e) N = 1..5 on the generic route (random states on a leaf, η = 5 + 0.1i)."""
    import jetgaudin as jg
    from jetgaudin import ensemble as ens
    from jetgaudin.backlund import kernels as _kernels

    for N in range(1, 6):
        c = np.zeros(N)
        c[-1] = 1.0
        X0 = ens.sample_on_leaf(N, c, 1, seed=N, scale=0.5)[0]
        B = jg.TwoPointBacklund(1.0, 5 + 0.1j)
        nu0 = B.nu1(X0)
        _kernels.iterate_single(X0, 1.0, B.eta, nu0, False, 2, 1, specialise=False)
        t = timed(
            lambda X0=X0, nu0=nu0: _kernels.iterate_single(
                X0, 1.0, 5 + 0.1j, nu0, False, steps, 1000, specialise=False
            ),
            3,
        )
        tn = timed(lambda X0=X0, B=B: B.iterate(X0, numpy_steps, kernel="numpy"), 1)
        rate = steps / np.median(t)
        rows.append(
            Row(
                "e",
                f"N={N} generic route",
                rate,
                "steps/s",
                f"NumPy route {numpy_steps / tn[0]:.3g} steps/s; ratio {rate * tn[0] / numpy_steps:.0f}x; "
                f"{_kernels.flops_per_step(N, 'generic')['total']} flops/step",
            )
        )


def bench_memory(rows, steps=10**8, every=1000):
    """Resident memory of a 10^8-step run saving every 1000th state (fresh process, peak RSS = VmHWM)."""
    code = (
        "import time, numpy as np, jetgaudin as jg\n"
        "X0 = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0])\n"
        "B = jg.TwoPointBacklund(1.0, 5 + 0.1j)\n"
        f"t = time.perf_counter(); o = B.iterate(X0, {steps}, save_every={every}, kernel='compiled')\n"
        "dt = time.perf_counter() - t\n"
        # VmHWM (peak RSS of this address space): ru_maxrss would include the parent's RSS at fork time
        "hwm = [ln for ln in open('/proc/self/status') if ln.startswith('VmHWM')][0].split()[1]\n"
        "print(o.shape[0], dt, int(hwm) / 1024)\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=3600)
    S, dt, mb = r.stdout.split()
    rows.append(
        Row(
            "g",
            f"{steps:.0e} steps, every {every}th saved: peak RSS",
            float(mb),
            "MB",
            f"{S} states; {float(dt):.1f} s ({steps / float(dt):.3g} steps/s wall)",
        )
    )


def _sibling(name: str):
    """A module of this directory, loaded by path (the harness is also loaded by path from ``jetgaudin bench``)."""
    import importlib.util
    from pathlib import Path

    # the siblings import ``timed`` from the harness under this name, whatever name its loader gave it
    sys.modules.setdefault("jetgaudin_benchmarks_harness", sys.modules[__name__])
    full = f"jetgaudin_benchmarks_{name}"
    if full in sys.modules:
        return sys.modules[full]
    spec = importlib.util.spec_from_file_location(full, Path(__file__).with_name(f"{name}.py"))
    mod = importlib.util.module_from_spec(spec)
    sys.modules[full] = mod
    spec.loader.exec_module(mod)
    return mod


def _heyoka_missing() -> str | None:
    try:
        import heyoka  # noqa: F401
    except ImportError:
        return "heyoka is not installed (pip install 'jetgaudin[heyoka]')"
    return None


def _dask_missing() -> str | None:
    try:
        import dask.distributed  # noqa: F401
    except ImportError:
        return "dask.distributed is not installed (pip install 'jetgaudin[distributed]')"
    return None


def run_benchmarks(parts=PARTS, quick=False, echo=print):
    """Run the selected parts; ``quick`` shrinks the sizes (for a smoke test).  Parts needing a missing optional
    package are skipped with a note (echoed).  Returns ``(rows, info)``."""
    extra = _sibling("speed_parts")
    bench_fixed_cost, bench_compile, bench_dask = extra.bench_fixed_cost, extra.bench_compile, extra.bench_dask
    setup = _sibling("setup_parts")
    info = machine_info()
    rows: list[Row] = []
    plan = [
        ("a", lambda: bench_single(rows, steps=10**5 if quick else 10**6, numpy_steps=200 if quick else 2000,
                                   repeat=3 if quick else 5), None),
        ("b", lambda: bench_appendix2(rows, repeat=5 if quick else 50), _heyoka_missing),
        ("cd", lambda: bench_ensembles(rows, sizes=((10**3, 100), (10**4, 100)) if quick else
                                       ((10**3, 100), (10**5, 100), (10**5, 1000), (10**6, 100)), info=info,
                                       processes_size=(10**4, 100) if quick else (10**5, 100)), None),
        ("e", lambda: bench_generic(rows, steps=10**4 if quick else 10**5, numpy_steps=50 if quick else 300), None),
        ("f", lambda: bench_fresh_process(rows), None),
        ("g", lambda: bench_memory(rows, steps=10**6 if quick else 10**8), None),
        ("h", lambda: bench_fixed_cost(rows, Row, orbits=10**4 if quick else 10**5), None),
        ("i", lambda: bench_compile(rows, Row), None),
        ("j", lambda: bench_dask(rows, Row, orbits=10**4 if quick else 10**5, steps=100 if quick else 1000),
         _dask_missing),
        ("k", lambda: setup.bench_setup(rows, Row, orbits=10**4 if quick else 10**5, repeat=3 if quick else 15), None),
        ("l", lambda: setup.bench_compile_parts(rows, Row), None),
        ("m", lambda: extra.bench_step_accuracy(rows, Row, steps=20 if quick else 200, states=1 if quick else 4),
         None),
    ]
    for letters, run, missing in plan:
        if not set(letters) & set(parts):
            continue
        why = missing() if missing else None
        if why:
            echo(f"({letters}) skipped: {why}")
            continue
        k = len(rows)
        run()
        echo(rows_to_text(rows[k:]))
    info["loadavg_end"] = os.getloadavg()
    return rows, info


def rows_to_text(rows) -> str:
    return "\n".join(f"({r.part}) {r.what:<52} {r.value:>12.4g} {r.unit:<14} {r.note}" for r in rows)


def rows_to_markdown(rows, info) -> str:
    lines = ["| part | measurement | value | unit | notes |", "|---|---|---:|---|---|"]
    for r in rows:
        lines.append(f"| {r.part} | {r.what} | {r.value:.4g} | {r.unit} | {r.note} |")
    lines.append("")
    lines.append("Machine: " + json.dumps(info, default=str))
    return "\n".join(lines)
