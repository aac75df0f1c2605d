"""``jetgaudin bench``: runs the benchmark harness of the source tree (``benchmarks/harness.py``); the harness,
not this command, holds the measurements.  Parts needing heyoka or Dask are skipped with a note when missing."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path
from types import ModuleType
from typing import Annotated, Any

import typer

from ._app import app

__all__ = ["harness", "bench_command"]

_PARTS = "abcdefghijklm"


def harness() -> ModuleType:
    """The module ``benchmarks/harness.py`` of the source checkout this package runs from.

    Raises :class:`FileNotFoundError` when the package is installed without its source tree."""
    name = "jetgaudin_benchmarks_harness"
    if name in sys.modules:
        return sys.modules[name]
    path = Path(__file__).resolve().parents[3] / "benchmarks" / "harness.py"
    if not path.is_file():
        raise FileNotFoundError(f"the benchmark harness ships with the source tree ({path} not found); "
                                "run `jetgaudin bench` from a checkout of jetgaudin")
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    return mod


def __getattr__(name: str) -> Any:  # Row, rows_to_markdown, run_benchmarks, ... from the harness
    if name in ("Row", "rows_to_markdown", "rows_to_text", "run_benchmarks", "machine_info"):
        return getattr(harness(), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


@app.command("bench")
def bench_command(
    parts: Annotated[str, typer.Option("--parts", help=f"which parts to run: letters of '{_PARTS}'")] = "abcdefhi",
    quick: Annotated[bool, typer.Option("--quick", help="small sizes (a smoke test, a few minutes)")] = False,
    markdown: Annotated[Path | None, typer.Option("--markdown", help="also write the table as Markdown")] = None,
) -> None:
    """Benchmarks: (a) one orbit, compiled vs NumPy; (b) Appendix 2 work vs heyoka; (c, d) ensembles on 1 and 2
    threads (and 2 processes × 1 thread at once) and the flop rate; (e) N = 1..5; (f) the main job in a fresh
    process; (g) memory of a 10^8-step run; (h) fixed cost of short calls; (i) first-use compile time; (j) Dask
    LocalCluster vs threads; (k) the per-orbit set-up of a call; (l) cold compile kernel by kernel; (m) per-step
    accuracy of the compiled N = 3 and generic routes against the NumPy route (summary row per route: |eta| >= 1,
    |eta| < 1, Appendix 2)."""
    from ._common import fail

    bad = set(parts) - set(_PARTS)
    if bad or not parts:
        fail(f"--parts: unknown part(s) {''.join(sorted(bad)) or '(none given)'}; use letters of '{_PARTS}'")
    try:
        h = harness()
    except FileNotFoundError as e:
        fail(str(e))
    rows, info = h.run_benchmarks(parts, quick=quick, echo=typer.echo)
    typer.echo("machine: " + json.dumps(info, default=str))
    if markdown is not None:
        markdown.write_text(h.rows_to_markdown(rows, info) + "\n")
