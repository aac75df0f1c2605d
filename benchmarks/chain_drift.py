"""Growth of the integral drift of the chain maps (every family) and the top's map with the number of steps: the
exponent p of ``max drift ~ n^p`` on an ensemble of orbits (issue 33: round-off gives p ≈ 1/2, a bias p ≈ 1).

    python benchmarks/chain_drift.py                           # 64 orbits, compiled to 10^6, NumPy to 10^5
    python benchmarks/chain_drift.py --orbits 64 --compiled-max 100000 --numpy-max 1000
    python benchmarks/chain_drift.py --compiled-max 0 --only rational   # the NumPy route only
    python benchmarks/chain_drift.py --compiled-max 0 --numpy-max 1000000 --only elliptic --jsonl /tmp/ell.jsonl
    python benchmarks/chain_drift.py --persistence 1000000 --only rational      # a bias per orbit (compiled)

``--persistence N``: a bias whose sign depends on the orbit leaves the ensemble's mean (``z``) at zero but makes
each orbit drift linearly.  The compiled route's ``N`` steps are cut into four quarters; for each integral the
correlation over the orbits of the changes in two quarters, averaged over the six pairs, is printed (a random walk's
quarters are independent: ~0 ± 0.13 with 64 orbits; an orbit-wise linear drift: up to 1).

``--jsonl PATH`` appends one JSON line per point ``n`` as it is reached (map, route, orbits, n, drift, the fit so far,
``z``, machine) and keeps the ensemble's state after every ``--chunk`` steps in ``PATH.<map>.<route>.npz``: a run
killed and started again with the same arguments resumes from that state (a split run equals the unsplit one bit
for bit, both routes), so that a long NumPy run (~1–3 ms per step of 64 orbits) loses nothing.  Every drift run
also stops at the quarters of its last ``n`` and prints (and writes to ``PATH``) their persistence score, on its own
route: the NumPy routes' bias per orbit without a second run.

For each map and route, the ensemble of ``--orbits`` orbits (states drawn with a fixed seed, scale 0.5) is advanced
to ``n = 10^3, 10^3.5, ...`` steps; at each ``n`` the largest relative drift ``max_k |I_k(X_n) − I_k(X_0)| /
max(1, |I_k(X_0)|)`` over the integrals (the map's ``integrals``) and the orbits is printed, with the exponent of
the least-squares fit of ``log drift`` on ``log n``, and the bias test ``z``: the largest over the integrals of the mean
signed relative change at the last ``n`` over the orbits in units of its standard error (sd / √orbits): a random walk
gives ``|z| ~ 1``, an error of one sign at every step ``|z| ~ √n``.  Accuracy, not speed: no timings.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time

import numpy as np

import jetgaudin as jg
from jetgaudin.gaudin import GaudinModel

SITES = [(-0.5, 1), (0.4, 2)]
ETA = 1.5 + 0.2j


def maps() -> dict:
    return {
        "rational chain": GaudinModel(1.0, SITES).two_point_backlund(ETA),
        "trigonometric chain": GaudinModel(1.0, SITES, family="trigonometric", gamma=1.0).two_point_backlund(ETA),
        "elliptic chain": GaudinModel(0.0, SITES, family="elliptic", modulus=0.6).two_point_backlund(ETA),
        "top (N = 3)": jg.TwoPointBacklund(1.0, 5 + 0.1j),
    }


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--orbits", type=int, default=64, help="orbits of the ensemble (>= 64 for the issue's fit)")
    ap.add_argument("--compiled-max", type=int, default=10**6, help="longest compiled run (from 10^3)")
    ap.add_argument("--numpy-max", type=int, default=10**5, help="longest NumPy run (from 10^3)")
    ap.add_argument("--only", default="", help="run the maps whose name contains this text")
    ap.add_argument("--persistence", type=int, default=0, help="steps of the per-orbit bias test (compiled)")
    ap.add_argument("--jsonl", default="", help="append one JSON line per point n; resume from its checkpoints")
    ap.add_argument("--chunk", type=int, default=10000, help="steps between checkpoints (with --jsonl)")
    return ap


def grid(n_max: int) -> list[int]:
    """``10^3, 10^3.5, ...`` up to ``n_max`` (rounded to integers)."""
    out = []
    e = 3.0
    while round(10**e) <= n_max:
        out.append(int(round(10**e)))
        e += 0.5
    return out


def states(m, orbits: int) -> np.ndarray:
    rng = np.random.default_rng(2026)
    return 0.5 * rng.normal(size=(orbits, m.n_state or 9))


def drift_curve(m, X0: np.ndarray, ns: list[int], record=None, chunk: int = 0,
                checkpoint: str = "") -> tuple[list[float], float, np.ndarray | None]:
    """The largest relative drift over the orbits and integrals at each ``n`` in ``ns``, the bias score ``z`` at the
    last ``n``, and the persistence score (:func:`persistence`) of the quarters of the last ``n`` (module docstring;
    the same run stops at the quarters and keeps each orbit's changes there).  ``record(n, drift_so_far, z)`` is
    called at each ``n``; with ``checkpoint`` the state is saved there every ``chunk`` steps and a run resumes from it
    (same orbits bit for bit)."""
    I0 = m.integrals(X0)
    scale = np.maximum(1.0, np.abs(I0))
    marks = [ns[-1] * q // 4 for q in range(1, 5)]  # the quarters of the last n
    X, carry, done, out, worst, cum = X0, None, 0, [], 0.0, {}
    if checkpoint and os.path.exists(checkpoint):
        with np.load(checkpoint) as c:
            X, carry, done = c["X"], c["carry"], int(c["done"])
            out, worst = [float(v) for v in c["out"]], float(c["worst"])
            if "marks" in c:
                cum = {int(q): v for q, v in zip(c["marks"], c["cum"], strict=True)}
    for n in ns[len(out):]:
        while done < n:
            k = n - done if not chunk else min(chunk, n - done)
            k = min([k] + [q - done for q in marks if q > done])
            adv = m.advance(X, carry, k, k)
            X, carry, done = adv.X, adv.carry, done + k
            if done in marks:
                cum[done] = (m.integrals(X) - I0) / scale
            if checkpoint and done < n:
                _save(checkpoint, X, carry, done, out, worst, cum)
        change = (m.integrals(X) - I0) / scale
        worst = max(worst, float(np.max(np.abs(change))))  # the running largest drift
        out.append(worst)
        sd = change.std(axis=0) / np.sqrt(len(X0))
        z = float(np.max(np.abs(change.mean(axis=0)) / np.where(sd > 0, sd, np.inf)))
        if checkpoint:
            _save(checkpoint, X, carry, done, out, worst, cum)
        if record is not None:
            record(n, out, z)
    change = (m.integrals(X) - I0) / scale  # at the last n (resumed or not)
    sd = change.std(axis=0) / np.sqrt(len(X0))
    z = np.abs(change.mean(axis=0)) / np.where(sd > 0, sd, np.inf)
    pers = None
    if all(q in cum for q in marks) and marks[0] > 0:
        c = np.stack([np.zeros_like(cum[marks[0]])] + [cum[q] for q in marks])
        pers = persistence(np.diff(c, axis=0))
    return out, float(np.max(z)), pers


def _save(path: str, X, carry, done: int, out: list[float], worst: float, cum: dict | None = None) -> None:
    tmp = path + ".tmp.npz"
    marks = sorted(cum or {})
    np.savez(tmp, X=X, carry=np.asarray(carry), done=done, out=np.asarray(out), worst=worst,
             marks=np.asarray(marks, dtype=np.int64), cum=np.asarray([cum[q] for q in marks]) if marks else
             np.zeros((0,) + np.shape(X)[:-1] + (0,)))
    os.replace(tmp, path)


def persistence(changes: np.ndarray) -> np.ndarray:
    """The mean over the pairs of quarters of the correlation over the orbits of each integral's changes in them:
    ``changes`` ``(4, orbits, k)`` (the change in each quarter) -> ``(k,)`` (module docstring)."""
    c = [[np.corrcoef(changes[i, :, k], changes[j, :, k])[0, 1] for i in range(4) for j in range(i + 1, 4)]
         for k in range(changes.shape[2])]
    return np.mean(c, axis=1)


def quarter_changes(m, X0: np.ndarray, n: int) -> np.ndarray:
    """The relative change of every integral of every orbit in each quarter of ``n`` steps, ``(4, orbits, k)``."""
    I0 = m.integrals(X0)
    rows = m.advance(X0, None, n - n % 4, n // 4).rows
    I = (m.integrals(rows) - I0) / np.maximum(1.0, np.abs(I0))
    return np.diff(np.concatenate([np.zeros((1,) + I.shape[1:]), I]), axis=0)


def exponent(ns: list[int], d: list[float]) -> float:
    return float(np.polyfit(np.log(ns), np.log(d), 1)[0]) if len(ns) > 1 else float("nan")


def main(argv=None) -> None:
    args = parser().parse_args(argv)
    print(f"machine: {platform.processor() or platform.machine()}; {args.orbits} orbits; largest relative drift")
    for name, m in maps().items():
        if args.only not in name:
            continue
        X0 = states(m, args.orbits)
        if args.persistence:
            p = persistence(quarter_changes(m.with_backend("compiled"), X0, args.persistence))
            names = m.integral_names() if hasattr(m, "integral_names") else [f"I{k}" for k in range(len(p))]
            cells = "  ".join(f"{k}: {v:+.2f}" for k, v in zip(names, p, strict=True))
            print(f"{name:20s} compiled  persistence over {args.persistence} steps   {cells}", flush=True)
            continue
        for route, n_max in (("compiled", args.compiled_max), ("numpy", args.numpy_max)):
            ns = grid(n_max)
            if not ns:
                continue
            record, checkpoint = None, ""
            if args.jsonl:
                machine = _machine()
                checkpoint = f"{args.jsonl}.{name.split()[0]}.{route}.npz"

                def record(n, d, z, name=name, route=route, ns=ns, machine=machine):
                    line = {"map": name, "route": route, "orbits": args.orbits, "n": n, "drift": d[-1],
                            "exponent_so_far": exponent(ns[:len(d)], d), "range": [ns[0], n], "z": z,
                            "machine": machine, "utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}
                    with open(args.jsonl, "a") as fh:
                        fh.write(json.dumps(line) + "\n")
            mr = m.with_backend(route)
            d, z, pers = drift_curve(mr, X0, ns, record, args.chunk if args.jsonl else 0, checkpoint)
            cells = "  ".join(f"{n:.0e}: {v:.2e}" for n, v in zip(ns, d, strict=True))
            print(f"{name:20s} {route:9s} exponent {exponent(ns, d):5.2f}  bias |z| {z:5.1f}   {cells}", flush=True)
            if pers is not None:
                names = mr.integral_names() if hasattr(mr, "integral_names") else [f"I{k}" for k in range(len(pers))]
                pcells = "  ".join(f"{k}: {v:+.2f}" for k, v in zip(names, pers, strict=True))
                print(f"{name:20s} {route:9s} persistence over {ns[-1]} steps   {pcells}", flush=True)
                if args.jsonl:
                    with open(args.jsonl, "a") as fh:
                        fh.write(json.dumps({"map": name, "route": route, "orbits": args.orbits, "n": ns[-1],
                                             "persistence": dict(zip(names, map(float, pers), strict=True)),
                                             "machine": _machine()}) + "\n")


def _machine() -> str:
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()

if __name__ == "__main__":
    main()
