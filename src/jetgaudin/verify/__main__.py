"""``python -m jetgaudin.verify [--errata PATH] [--full] [--only LABEL ...] [--json]``.

With ``--errata PATH`` the errata file is (re)generated from the registry and nothing is run.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from . import DEFAULT_SEED, errata_markdown, exit_code, run_checks


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m jetgaudin.verify", description=__doc__)
    ap.add_argument("--errata", type=Path, help="write the generated errata markdown to this path and exit")
    ap.add_argument("--only", action="append", help="run only this check label (repeatable)")
    ap.add_argument("--full", action="store_true", help="include the heavier checks")
    ap.add_argument("--seed", type=int, default=DEFAULT_SEED)
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--coverage", action="store_true", help="print the coverage map of the paper (JSON) and exit")
    a = ap.parse_args(argv)
    if a.coverage:
        from .coverage import coverage

        print(json.dumps(coverage(), indent=1))
        return 0
    if a.errata is not None:
        a.errata.parent.mkdir(parents=True, exist_ok=True)
        a.errata.write_text(errata_markdown(), encoding="utf-8")
        print(f"wrote {a.errata}")
        return 0
    res = run_checks(only=a.only, full=a.full, seed=a.seed)
    if a.json:
        print(json.dumps([r.to_dict() for r in res], indent=1))
    else:
        for r in res:
            print(f"{r.label:20s} {r.status:9s} printed={r.printed:9s} corrected={r.corrected!s:9s} {r.seconds:6.2f}s")
    return exit_code(res)


if __name__ == "__main__":
    sys.exit(main())
