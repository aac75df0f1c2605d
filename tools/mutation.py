"""Mutation testing of the mathematical core with Cosmic Ray: a seeded, bounded sample of mutants per module.

Usage (needs ``pip install -e '.[mutation]'``; see docs/mutation.md)::

    python tools/mutation.py                      # the default sample (~150 mutants, hours on 2 cores)
    python tools/mutation.py --per-module 2 --only algebra.py --json out.json

For each module of :data:`GROUPS` the script copies ``src/`` and ``tests/`` into a temporary directory (Cosmic Ray
mutates files in place: the working tree is never touched), lets ``cosmic-ray init`` enumerate every mutant, keeps
those of :data:`OPERATORS` (the plausible slips: arithmetic, comparison, sign, constant, boolean; not the bitwise
operators, which fail on floats at once), draws ``--per-module`` of them with ``--seed``, marks the others skipped,
and runs ``cosmic-ray exec`` with the module's fast test selection (``pytest -x``: the first failing test kills),
after checking that the selection passes on the unmutated copy (a baseline).
It prints one line per module and writes a JSON report (counts and every survivor with its diff).
"""

from __future__ import annotations

import argparse
import json
import random
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: module (under src/jetgaudin) -> the tests that decide it (fast selections: each mutant runs them once)
GROUPS: dict[str, tuple[str, ...]] = {
    "algebra.py": ("tests/test_algebra.py",),
    "lax.py": ("tests/test_lax.py",),
    "spectral.py": ("tests/test_spectral.py", "tests/test_branch_rule.py"),
    "hamiltonians.py": ("tests/test_hamiltonians.py",),
    "backlund/_dressing.py": ("tests/test_backlund.py", "tests/test_routes.py"),
    "backlund/maps.py": ("tests/test_backlund.py", "tests/test_maps.py"),
    "backlund/closed_form.py": ("tests/test_closed_form.py",),
    "backlund/generating.py": ("tests/test_generating.py",),
    "backlund/kernels/_scalar.py": ("tests/test_routes.py", "tests/test_kernels.py"),
    "backlund/kernels/_n3.py": ("tests/test_routes.py", "tests/test_kernels.py"),
    "backlund/kernels/_generic.py": ("tests/test_routes.py", "tests/test_kernels.py"),
    "backlund/kernels/_branch.py": ("tests/test_branch_rule.py", "tests/test_kernels.py"),
    # added since the last sample (issue 33): families, gaudin, exact steps, events, solve, the run layer, disk
    "families/trigonometric.py": ("tests/test_bite_families.py", "tests/test_trigonometric.py",
                                  "tests/test_trig_one_point.py"),
    "families/elliptic.py": ("tests/test_elliptic.py",),
    "families/_jacobi.py": ("tests/test_jacobi.py",),
    "gaudin/model.py": ("tests/test_bite_gaudin.py", "tests/test_gaudin.py"),
    "gaudin/maps.py": ("tests/test_gaudin_maps.py", "tests/test_chain_drift.py", "tests/test_chain_refusals.py",
                       "tests/test_chain_compiled_start.py"),
    "gaudin/_backend.py": ("tests/test_bite_gaudin.py", "tests/test_auto_route.py"),
    "gaudin/_curve.py": ("tests/test_gaudin.py", "tests/test_branch_rule.py", "tests/test_bite_exact.py"),
    "exact.py": ("tests/test_bite_exact.py", "tests/test_exact.py", "tests/test_exact_first_class.py"),
    # test_exact_chain_compiled.py compares the NumPy route of the solve with the compiled one (seed 35: the NumPy
    # Newton method and its continuation of ν ran in no test of the selection before)
    "exact_chain.py": ("tests/test_bite_exact.py", "tests/test_exact_chain_compiled.py", "tests/test_exact_chain.py",
                       "tests/test_exact_first_class.py"),
    "events.py": ("tests/test_bite_events.py", "tests/test_solve.py"),
    "solve.py": ("tests/test_bite_solve.py", "tests/test_solve.py", "tests/test_exact_first_class.py"),
    "run/driver.py": ("tests/test_bite_run.py", "tests/test_run.py", "tests/test_run_compile.py",
                      "tests/test_reliability_runlayer.py"),
    "run/health.py": ("tests/test_bite_run.py", "tests/test_run.py", "tests/test_reliability_runlayer.py"),
    "run/store.py": ("tests/test_bite_run.py", "tests/test_run.py", "tests/test_data_safety_io.py",
                     "tests/test_reliability_runlayer.py"),
    # the test_bite_* files (issue 33) first in a selection: pytest -x stops at the first failure, and they are fast
    "_fs.py": ("tests/test_bite_disk.py", "tests/test_fs.py"),
    # the disk-space reservation before HDF5 writes (fallocate, RLIMIT_FSIZE, the reserve file)
    "_space.py": ("tests/test_bite_disk.py", "tests/test_bite_run.py", "tests/test_fs.py"),
    # the GPU drivers, tested on Numba's CUDA simulator (tests/test_gpu.py sets NUMBA_ENABLE_CUDASIM=1 before
    # numba.cuda is imported: the kernels run as Python, so a mutated kernel needs no compiler and no GPU)
    "gpu/_device.py": ("tests/test_bite_gpu.py", "tests/test_gpu.py"),
    "gpu/_drivers.py": ("tests/test_bite_gpu.py", "tests/test_gpu.py"),
    "gpu/_kernels.py": ("tests/test_bite_gpu.py", "tests/test_gpu.py", "tests/test_gpu_sun.py"),
    "gpu/_resident.py": ("tests/test_bite_gpu.py", "tests/test_gpu.py"),
    # added since the seed-33 sample (issue 33, item 5: the seed-35 round): one model (the route table of the maps,
    # the registry, jet constants as a site option), the dressing split from gaudin/maps.py, the chain Hamiltonian,
    # solve's route table and the exact chain's Python-side constants
    "_system_maps.py": ("tests/test_bite_gaudin.py", "tests/test_top_as_model.py", "tests/test_one_class.py"),
    "gaudin/_model_map.py": ("tests/test_top_as_model.py", "tests/test_one_class.py"),
    "gaudin/_site_constants.py": ("tests/test_bite_gaudin.py", "tests/test_site_constants.py",
                                  "tests/test_top_as_model.py"),
    "gaudin/_dressing.py": ("tests/test_gaudin_maps.py", "tests/test_trigonometric_maps.py",
                            "tests/test_chain_drift.py"),
    "gaudin/hamiltonian.py": ("tests/test_gaudin.py", "tests/test_solve_models.py"),
    "_exact_chain_prep.py": ("tests/test_bite_exact.py", "tests/test_exact_chain_compiled.py",
                             "tests/test_exact_chain.py"),
    "methods.py": ("tests/test_bite_solve.py", "tests/test_solve_models.py", "tests/test_top_as_model.py"),
    # modules older than the seed-33 sample that hold logic and were in no area: the families' contract and series,
    # the chain's one-point maps, integrals as forms and compensated arithmetic, the run's spec and replay
    "families/_base.py": ("tests/test_bite_families.py", "tests/test_trigonometric.py", "tests/test_elliptic.py"),
    "families/_series.py": ("tests/test_trigonometric_maps.py", "tests/test_elliptic.py"),
    "gaudin/_one_point.py": ("tests/test_trig_one_point.py", "tests/test_gaudin_maps.py"),
    # test_elliptic.py: the elliptic family at b = 0 has the constant c_0 of ν² as an integral (constant_form)
    "gaudin/_forms.py": ("tests/test_gaudin.py", "tests/test_elliptic.py", "tests/test_gaudin_maps.py",
                         "tests/test_trigonometric_maps.py"),
    "gaudin/_compensated.py": ("tests/test_chain_drift.py",),
    "run/spec.py": ("tests/test_bite_run.py", "tests/test_run.py"),
    "run/replay.py": ("tests/test_bite_run.py", "tests/test_data_safety.py", "tests/test_reliability_refusals.py"),
}

#: the default sample size per module (the kernels recompile for every mutant: fewer there)
PER_MODULE = {"backlund/kernels/_scalar.py": 5, "backlund/kernels/_n3.py": 5, "backlund/kernels/_generic.py": 4,
              "backlund/kernels/_branch.py": 3, "backlund/closed_form.py": 4, "backlund/generating.py": 4,
              # issue 33: at least 10 per area (AREAS), spread over the area's modules
              "families/trigonometric.py": 4, "families/elliptic.py": 4, "families/_jacobi.py": 4,
              "gaudin/model.py": 4, "gaudin/maps.py": 3, "gaudin/_backend.py": 4, "gaudin/_curve.py": 2,
              "exact.py": 6, "exact_chain.py": 6, "events.py": 12, "solve.py": 12,
              "run/driver.py": 5, "run/health.py": 3, "run/store.py": 5, "_fs.py": 12, "_space.py": 10,
              "gpu/_device.py": 2, "gpu/_drivers.py": 4, "gpu/_kernels.py": 4, "gpu/_resident.py": 4,
              # the seed-35 round's additions
              "_system_maps.py": 4, "gaudin/_model_map.py": 2, "gaudin/_site_constants.py": 4,
              "gaudin/_dressing.py": 4, "gaudin/hamiltonian.py": 3, "_exact_chain_prep.py": 4, "methods.py": 4,
              "families/_base.py": 3, "families/_series.py": 3, "gaudin/_one_point.py": 3, "gaudin/_forms.py": 3,
              "gaudin/_compensated.py": 3, "run/spec.py": 3, "run/replay.py": 3}
DEFAULT_PER_MODULE = 6

#: the areas whose kill rate docs/mutation.md reports (issue 33: at least 90 % each), and their modules
AREAS: dict[str, tuple[str, ...]] = {
    "core": ("algebra.py", "lax.py", "spectral.py", "hamiltonians.py", "backlund/_dressing.py", "backlund/maps.py",
             "backlund/closed_form.py", "backlund/generating.py", "backlund/kernels/_scalar.py",
             "backlund/kernels/_n3.py", "backlund/kernels/_generic.py", "backlund/kernels/_branch.py"),
    "families": ("families/trigonometric.py", "families/elliptic.py", "families/_jacobi.py", "families/_base.py",
                 "families/_series.py"),
    "gaudin": ("gaudin/model.py", "gaudin/maps.py", "gaudin/_backend.py", "gaudin/_curve.py", "_system_maps.py",
               "gaudin/_model_map.py", "gaudin/_site_constants.py", "gaudin/_dressing.py", "gaudin/hamiltonian.py",
               "gaudin/_one_point.py", "gaudin/_forms.py", "gaudin/_compensated.py"),
    "exact": ("exact.py", "exact_chain.py", "_exact_chain_prep.py"),
    "events": ("events.py",),
    "solve": ("solve.py", "methods.py"),
    "run": ("run/driver.py", "run/health.py", "run/store.py", "run/spec.py", "run/replay.py"),
    "disk": ("_fs.py", "_space.py"),
    "gpu": ("gpu/_device.py", "gpu/_drivers.py", "gpu/_kernels.py", "gpu/_resident.py"),
}

_ARITH = ("Add", "Sub", "Mul", "Div", "Pow")
_CMP = ("Lt", "LtE", "Gt", "GtE", "Eq", "NotEq")


def plausible(operator: str) -> bool:
    """The operators of the sample: slips a person could make in this code."""
    name = operator.split("/", 1)[-1]
    if name.startswith("ReplaceBinaryOperator_"):
        _, a, b = name.split("_")
        return a in _ARITH and b in _ARITH
    if name.startswith("ReplaceComparisonOperator_"):
        _, a, b = name.split("_")
        return a in _CMP and b in _CMP
    return name.startswith("ReplaceUnaryOperator_") or name in {
        "NumberReplacer", "ReplaceTrueWithFalse", "ReplaceFalseWithTrue", "ReplaceAndWithOr", "ReplaceOrWithAnd",
        "AddNot", "ZeroIterationForLoop"}


def _cosmic(*args: str, cwd: Path) -> None:
    subprocess.run([sys.executable, "-m", "cosmic_ray.cli", *args], cwd=cwd, check=True,
                   stdout=subprocess.DEVNULL)


def run_module(module: str, tests: tuple[str, ...], k: int, seed: int, timeout: float, work: Path) -> dict:
    """Sample ``k`` plausible mutants of ``module`` and run them; returns the counts and the survivors."""
    from cosmic_ray.work_db import WorkDB, use_db
    from cosmic_ray.work_item import TestOutcome, WorkerOutcome, WorkResult

    path = f"src/jetgaudin/{module}"
    cfg = work / f"{module.replace('/', '_')}.toml"
    session = work / f"{module.replace('/', '_')}.sqlite"
    command = f"{sys.executable} -m pytest -x -q -p no:cacheprovider -p no:randomly " + " ".join(tests)
    cfg.write_text(f'[cosmic-ray]\nmodule-path = "{path}"\ntimeout = {timeout}\nexcluded-modules = []\n'
                   f'test-command = "env PYTHONPATH=src {command}"\n\n[cosmic-ray.distributor]\nname = "local"\n')
    # baseline: the selection must pass on the unmutated copy, or every mutant would count as killed
    base = subprocess.run(["env", "PYTHONPATH=src", *command.split()], cwd=work, capture_output=True, text=True)
    if base.returncode != 0:
        raise SystemExit(f"{module}: the tests fail without a mutant (fix them first):\n{base.stdout[-2000:]}")
    _cosmic("init", str(cfg), str(session), cwd=work)
    with use_db(str(session), WorkDB.Mode.open) as db:
        items = list(db.work_items)
        pool = sorted((i for i in items if plausible(i.mutations[0].operator_name)),
                      key=lambda i: (i.mutations[0].operator_name, i.mutations[0].occurrence))  # job ids are random
        chosen = {i.job_id for i in random.Random(f"{seed}:{module}").sample(pool, min(k, len(pool)))}
        db.set_multiple_results([i.job_id for i in items if i.job_id not in chosen],
                                WorkResult(worker_outcome=WorkerOutcome.SKIPPED))
    _cosmic("exec", str(cfg), str(session), cwd=work)
    out = {"module": module, "tests": list(tests), "mutants": len(items), "plausible": len(pool),
           "sampled": len(chosen), "killed": 0, "survived": [], "incompetent": 0, "timeout": 0}
    with use_db(str(session), WorkDB.Mode.open) as db:
        for item, result in db.completed_work_items:
            if item.job_id not in chosen:
                continue
            m = item.mutations[0]
            if result.worker_outcome != WorkerOutcome.NORMAL or result.test_outcome == TestOutcome.INCOMPETENT:
                out["incompetent"] += 1
            elif result.test_outcome == TestOutcome.KILLED and result.output == "timeout":  # Cosmic Ray's timeout
                out["timeout"] += 1
            elif result.is_killed:
                out["killed"] += 1
            else:
                out["survived"].append({"operator": m.operator_name, "occurrence": m.occurrence,
                                        "line": m.start_pos[0], "definition": m.definition_name,
                                        "diff": result.diff})
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--per-module", type=int, default=None, help="mutants per module (default: PER_MODULE)")
    ap.add_argument("--seed", type=int, default=27)
    ap.add_argument("--timeout", type=float, default=300.0, help="seconds per mutant (compiles included)")
    ap.add_argument("--only", nargs="*", default=None, help="modules of GROUPS to run (default: all)")
    ap.add_argument("--area", nargs="*", default=None, help="areas of AREAS to run (their modules)")
    ap.add_argument("--json", type=Path, default=None, help="write the report here")
    args = ap.parse_args(argv)
    modules = list(GROUPS) if not args.only else args.only
    if args.area:
        unknown = [a for a in args.area if a not in AREAS]
        if unknown:
            ap.error(f"unknown areas {unknown}; known: {list(AREAS)}")
        modules = [m for a in args.area for m in AREAS[a] if args.only is None or m in args.only]
    unknown = [m for m in modules if m not in GROUPS]
    if unknown:
        ap.error(f"unknown modules {unknown}; known: {list(GROUPS)}")
    report = []
    with tempfile.TemporaryDirectory(prefix="jetgaudin-mutation-") as tmp:
        work = Path(tmp)
        ignore = shutil.ignore_patterns("__pycache__", ".hypothesis", "*.nbi", "*.nbc")
        shutil.copytree(ROOT / "src", work / "src", ignore=ignore)
        shutil.copytree(ROOT / "tests", work / "tests", ignore=ignore)
        # some tests read the documentation (docs/chains.md's examples run in tests/test_gaudin.py)
        shutil.copytree(ROOT / "docs", work / "docs",
                        ignore=shutil.ignore_patterns("_build", "*.png", "*.gif", "*.mp4"))
        # tests/test_chain_drift.py loads benchmarks/chain_drift.py (its persistence score)
        shutil.copytree(ROOT / "benchmarks", work / "benchmarks", ignore=ignore)
        shutil.copy(ROOT / "pyproject.toml", work / "pyproject.toml")
        for module in modules:
            k = args.per_module if args.per_module is not None else PER_MODULE.get(module, DEFAULT_PER_MODULE)
            r = run_module(module, GROUPS[module], k, args.seed, args.timeout, work)
            report.append(r)
            decided = r["killed"] + len(r["survived"])
            print(f"{module:32s} sampled {r['sampled']:3d} of {r['plausible']:4d} plausible ({r['mutants']} in all): "
                  f"killed {r['killed']}/{decided}, survived {len(r['survived'])}, timeout {r['timeout']}, "
                  f"incompetent {r['incompetent']}", flush=True)
            if args.json:  # after every module: a long job stopped part-way keeps what it decided
                args.json.write_text(json.dumps({"seed": args.seed, "modules": report}, indent=1))
    killed = sum(r["killed"] for r in report)
    decided = killed + sum(len(r["survived"]) for r in report)
    for area, members in AREAS.items():
        rs = [r for r in report if r["module"] in members]
        if rs:
            k = sum(r["killed"] for r in rs)
            d = k + sum(len(r["survived"]) for r in rs)
            print(f"area {area:10s} killed {k}/{d}" + (f" = {k / d:.1%}" if d else ""))
    print(f"kill rate {killed}/{decided}" + (f" = {killed / decided:.1%}" if decided else ""))
    if args.json:
        args.json.write_text(json.dumps({"seed": args.seed, "modules": report}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
