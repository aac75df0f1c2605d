"""Benchmarks of the compiled Bäcklund kernels: one orbit, the Appendix 2 work vs heyoka, ensembles on 1 and 2
threads with the flop rate, N = 1..5, the main job in a fresh process, memory, the fixed cost of short calls,
first-use compile time, Dask LocalCluster vs threads, the per-orbit set-up of a call, cold compile kernel by
kernel, and the per-step accuracy of the compiled routes against the NumPy route (the harness:
``benchmarks/harness.py``, whose docstring lists the parts a..m).

Examples (every value shown is accepted):

    python benchmarks/bench_backlund.py --quick                  # a smoke test, a few minutes
    python benchmarks/bench_backlund.py --parts abcdefhij --markdown table.md
    python benchmarks/bench_backlund.py --parts m --quick          # accuracy of the compiled routes, seconds

The table of ``docs/performance.md`` is its Markdown output.  Timings are medians of repeated runs (best-of in
the notes); single-thread timings use the thread's CPU time, multi-thread timings wall time.  Parts needing
heyoka (b) or Dask (j) are skipped with a note when those are not installed.
"""

import argparse
import importlib.util
import json
import sys
from pathlib import Path


def _harness():
    path = Path(__file__).with_name("harness.py")
    spec = importlib.util.spec_from_file_location("jetgaudin_benchmarks_harness", path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


def _parts(text: str) -> str:
    letters = _harness().PARTS
    if not text or set(text) - set(letters):
        raise argparse.ArgumentTypeError(f"use letters of '{letters}', got {text!r}")
    return text


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true", help="small sizes (a smoke test)")
    letters = _harness().PARTS
    p.add_argument("--parts", type=_parts, default=letters,
                   help=f"letters of '{letters}' (default: all): (a) one orbit, (b) Appendix 2 vs heyoka, (c, d) "
                   "ensembles and flop rate, (e) N = 1..5, (f) fresh process, (g) memory, (h) short calls, "
                   "(i) compile, (j) Dask, (k) set-up of a call, (l) compile by kernel, (m) per-step accuracy")
    p.add_argument("--markdown", type=Path, help="write the table as Markdown to this file")
    return p


def main(argv=None):
    a = parser().parse_args(argv)
    h = _harness()
    rows, info = h.run_benchmarks(a.parts, quick=a.quick)
    print("machine:", json.dumps(info, default=str))
    if a.markdown:
        a.markdown.write_text(h.rows_to_markdown(rows, info) + "\n")


if __name__ == "__main__":
    main()
