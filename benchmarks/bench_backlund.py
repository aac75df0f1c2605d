"""Benchmarks of the compiled Bäcklund kernels (issue 6): one orbit, the Appendix 2 work vs heyoka,
ensembles on 1 and 2 threads with the flop rate, N = 1..5, the main job in a fresh process, memory.

Run: ``python benchmarks/bench_backlund.py [--quick] [--parts abcdefg] [--markdown FILE]``
(the same code as ``jetgaudin bench``; the table of ``docs/performance.md`` is its Markdown output).
Timings are medians of repeated runs (best-of in the notes); single-thread timings use the thread's
CPU time, multi-thread timings wall time.
"""

import argparse
import json
from pathlib import Path

from jetgaudin.cli.bench import rows_to_markdown, run_benchmarks


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="small sizes (a smoke test)")
    p.add_argument("--parts", default="abcdefg", help="letters of 'abcdefg'")
    p.add_argument("--markdown", type=Path, help="write the table as Markdown")
    a = p.parse_args()
    rows, info = run_benchmarks(a.parts, quick=a.quick)
    print("machine:", json.dumps(info, default=str))
    if a.markdown:
        a.markdown.write_text(rows_to_markdown(rows, info) + "\n")


if __name__ == "__main__":
    main()
