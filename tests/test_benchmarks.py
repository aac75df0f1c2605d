"""The benchmark harness (benchmarks/) and ``jetgaudin bench``: structure only, no timings (speed is measured in
benchmarks/, never in tests)."""

from __future__ import annotations

import importlib.util
import re
import shlex
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


def _load(name: str):
    spec = importlib.util.spec_from_file_location(f"_test_bench_{name}", BENCH / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize("script", ["bench_backlund", "memory_long_run", "before_after"])
def test_every_example_in_the_help_is_accepted(script):
    # issue 11, item 10: the --help text suggested --steps 1e8, which was refused
    mod = _load(script)
    examples = [ln.strip() for ln in mod.__doc__.splitlines() if ln.strip().startswith(f"python benchmarks/{script}")]
    assert examples
    for ex in examples:
        argv = shlex.split(ex.split("#")[0])[2:]
        mod.parser().parse_args(argv)  # SystemExit(2) on a refused value
    # and every integer the docstrings suggest for the CLI is written as an integer
    assert not re.search(r"--steps \d+(\.\d*)?e\d", mod.__doc__)


def test_bench_without_heyoka_skips_its_part_with_a_note(monkeypatch):
    # issue 11, item 10: `jetgaudin bench --quick` died with a traceback without heyoka
    monkeypatch.setitem(sys.modules, "heyoka", None)  # `import heyoka` raises ImportError
    from typer.testing import CliRunner

    from jetgaudin.cli import app

    notes: list[str] = []
    from jetgaudin.cli import bench

    rows, _ = bench.harness().run_benchmarks("b", quick=True, echo=notes.append)
    assert rows == [] and any("(b) skipped: heyoka is not installed" in n for n in notes)
    r = CliRunner().invoke(app, ["bench", "--parts", "b", "--quick"])
    assert r.exit_code == 0 and "skipped: heyoka is not installed" in r.output and "Traceback" not in r.output


def test_bench_markdown_rows():
    from jetgaudin.cli import bench

    h = bench.harness()
    md = h.rows_to_markdown([h.Row("i", "compile", 9.5, "s", "note")], {"Model name": "AMD EPYC"})
    assert "| i | compile | 9.5 | s | note |" in md and "AMD EPYC" in md
    assert set(h.PARTS) == set("abcdefghijkl")
