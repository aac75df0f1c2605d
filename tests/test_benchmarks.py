"""The benchmark harness (benchmarks/) and ``jetgaudin bench``: structure only, no timings (speed is measured in
benchmarks/, never in tests)."""

from __future__ import annotations

import importlib.util
import math
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


@pytest.mark.parametrize("script", ["bench_backlund", "memory_long_run", "before_after", "integrators", "auto_route",
                                    "chain_drift"])
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
    assert set(h.PARTS) == set("abcdefghijklm")
    assert bench._PARTS == h.PARTS  # the command's own list of letters (for its --help) is the harness's


def test_bench_parts_m_quick_prints_the_accuracy_rows():
    # part (m): per-step error of the compiled routes against the NumPy route, one row per route and case group and
    # one summary row per route (|eta| >= 1, |eta| < 1, Appendix 2); values are errors, so finite and >= 0, and the
    # worst over 7 cases of 20 steps is not exactly 0 (the routes evaluate in different orders).  No numbers
    # asserted: accuracy is measured in benchmarks/, the routes' bounds are tested in tests/test_routes.py.
    from typer.testing import CliRunner

    from jetgaudin.cli import app

    r = CliRunner().invoke(app, ["bench", "--parts", "m", "--quick"])
    assert r.exit_code == 0, r.output
    rows = [ln for ln in r.output.splitlines() if ln.startswith("(m) ")]
    for route in ("N = 3", "generic"):
        for case in ("Appendix 2", "η = (5+0.1j)", "η = (0.3+0.5j)"):
            assert any(ln.startswith(f"(m) {route} {case}: per-step error vs NumPy") for ln in rows), (route, case)
        summary = [ln for ln in rows if ln.startswith(f"(m) {route} route: worst per-step error vs NumPy")]
        assert len(summary) == 1
        assert all(g in summary[0] for g in ("|η| ≥ 1 ", "|η| < 1 ", "Appendix 2 ", "after one step"))
        assert float(summary[0].split("NumPy")[1].split()[0]) > 0
    values = [float(ln.split("NumPy")[1].split()[0]) for ln in rows]
    assert values and all(math.isfinite(v) and v >= 0 for v in values)
    assert "machine:" in r.output and "Traceback" not in r.output


def test_bench_parts_m_runs_from_the_script_and_the_harness():
    # the same letter through bench_backlund.py's parser and the harness (quick sizes), with the summary's extra
    mod = _load("bench_backlund")
    assert mod.parser().parse_args(["--parts", "m", "--quick"]).parts == "m"
    assert "(m) per-step accuracy" in " ".join(mod.parser().format_help().split())  # whatever the wrapping
    from jetgaudin.cli import bench

    rows, _ = bench.harness().run_benchmarks("m", quick=True, echo=lambda s: None)
    summary = [r for r in rows if r.what.endswith("route: worst per-step error vs NumPy")]
    assert [r.what.split()[0] for r in summary] == ["N", "generic"]
    for r in summary:
        assert set(r.extra) == {"|η| ≥ 1", "|η| < 1", "Appendix 2"}
        assert r.value == max(r.extra.values())


@pytest.mark.parametrize("parts", ["z", "mz", ""])
def test_bench_unknown_parts_exit_2_with_one_line(parts):
    from typer.testing import CliRunner

    from jetgaudin.cli import app

    r = CliRunner().invoke(app, ["bench", "--parts", parts, "--quick"])
    assert r.exit_code == 2
    assert len(r.output.strip().splitlines()) == 1 and "abcdefghijklm" in r.output and "Traceback" not in r.output


def test_process_rates_times_each_process_inside_the_overlap():
    # part (c)'s "2 processes × 1 thread" rows: each fresh process reports a finite positive rate (wall and CPU
    # time) and no more calls inside the common window than it made; tiny work, structure only (no speed asserted)
    import numpy as np

    from jetgaudin.backlund import kernels
    from jetgaudin.cli import bench
    from jetgaudin.ensemble import sample_on_leaf

    sp = bench.harness()._sibling("speed_parts")
    X = sample_on_leaf(3, [0.5, 0.2, 1.0], 64, seed=2)
    b, eta = np.full(64, 1.0), np.full(64, 5 + 0.1j)
    nu = kernels.nu_default(X, b, eta)
    r = sp.process_rates(X, b, eta, nu, 10, 2, reps=3)
    assert len(r["wall"]) == len(r["cpu"]) == len(r["kept"]) == 2
    assert all(math.isfinite(v) and v > 0 for v in [*r["wall"], *r["cpu"]])
    assert all(0 <= k <= 3 for k in r["kept"]) and 0 <= r["steal"] <= 1
