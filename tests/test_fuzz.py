"""Fuzzing (Hypothesis): random and hostile input to the command line and to the public API must give a
clear error or a correct result -- never a traceback, a silent NaN, or a hang.

Bounded time: every CLI example runs at most a handful of steps (`--steps` <= 4, `--no-plots`), and the
number of examples comes from the Hypothesis profile in conftest (30 per test).
"""

import contextlib
import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

import jetgaudin as jg
from jetgaudin import recording as rec
from jetgaudin.cli import main

from conftest import APPENDIX2_X0

HOSTILE_FLOATS = st.sampled_from(
    [0.0, -0.0, 1e308, -1e308, 5e-324, -5e-324, 2.2250738585072014e-308, 1e-300, 1e300, 1e154, math.nan,
     math.inf, -math.inf, 1.0, -2.4, 0.5]
)
NUMBERS = st.one_of(HOSTILE_FLOATS, st.floats(allow_nan=True, allow_infinity=True, width=64),
                    st.floats(-10, 10, allow_nan=False))
NUMBER_TEXT = st.one_of(NUMBERS.map(repr), NUMBERS.map(str), st.text(max_size=8),
                        st.sampled_from(["", " ", "1e", "--1", "0x10", "1_0", "١", "nan", "-inf", "1e999", "j"]))
INIT_TEXT = st.one_of(
    st.integers(1, 200).map(lambda N: ",".join(["0.1"] * (3 * N))),  # up to N = 200: large N and "huge" input
    st.lists(NUMBER_TEXT, min_size=0, max_size=13).map(",".join),
    st.lists(NUMBERS, min_size=3, max_size=12).map(lambda v: ",".join(repr(x) for x in v[: len(v) // 3 * 3])),
    st.text(max_size=40),
)
ETA_TEXT = st.one_of(
    st.text(max_size=12),
    st.tuples(NUMBERS, NUMBERS).map(lambda t: f"{t[0]!r}{'+' if not str(t[1]).startswith('-') else ''}{t[1]!r}i"),
    st.sampled_from([f"{z.real!r}{z.imag:+}i" for z in jg.branch_points(APPENDIX2_X0, 1.0)]),  # eta at a branch point
    st.sampled_from(["5+0.1i", "5+0.1j", "5", "0+0.1i", "5+0i", "i", "-i", "1e308+1e308i", "5e-324+5e-324i",
                     "nan+1i", "5+infj", "5++0.1i", "5+0.1ii", "(5+0.1j)"]),
)


def run_cli(args):
    """Run `jetgaudin ARGS` in-process, capturing stdout/stderr via file descriptors 1/2."""
    import contextlib
    import io

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            main([str(a) for a in args])
            code = 0
        except SystemExit as exc:
            code = 0 if exc.code is None else exc.code
    return code, out.getvalue(), err.getvalue()


def check_outcome(code, err, out_dir: Path):
    """A clear error (one line, exit 1 or 2) or a correct, completed run."""
    assert "Traceback" not in err, err
    assert code in (0, 1, 2), (code, err)
    if code != 0:
        lines = [ln for ln in err.splitlines() if ln.strip()]
        assert len(lines) >= 1 and lines[-1].startswith("jetgaudin"), err
        if code == 2:
            assert len(lines) == 1, err
        return
    run = rec.read_run(out_dir)
    assert run["status"] == "completed"
    n, X = rec.load_orbit(out_dir)
    assert np.all(np.isfinite(X))
    I = jg.integrals(X, run["inputs"]["b"])
    rel = np.max(np.abs(I - I[0]), axis=0) / np.maximum(1.0, np.abs(I[0]))
    assert np.all(rel <= run["inputs"]["max_drift"])  # the health check's guarantee holds for the data


@given(b=NUMBER_TEXT, eta=ETA_TEXT, init=INIT_TEXT, steps=st.integers(-3, 4))
def test_fuzz_orbit_cli(b, eta, init, steps):
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "o"
        code, _, err = run_cli(["orbit", f"--b={b}", f"--eta={eta}", f"--init={init}", f"--steps={steps}",
                                "--no-plots", "--out", out])
        check_outcome(code, err, out)


@given(init=st.lists(NUMBERS, min_size=3, max_size=12).map(lambda v: v[: len(v) // 3 * 3]),
       b=NUMBERS, re=NUMBERS, im=NUMBERS)
def test_fuzz_orbit_cli_numbers(init, b, re, im):
    """Well-formed but extreme numbers (NaN, inf, 1e308, subnormals, -0.0)."""
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "o"
        code, _, err = run_cli(["orbit", f"--b={b!r}", f"--eta={re!r}{im:+}j" if math.isfinite(im) else
                                f"--eta={re!r}+{im!r}j", "--init=" + ",".join(repr(x) for x in init),
                                "--steps=3", "--no-plots", "--out", out])
        check_outcome(code, err, out)


@given(eta=ETA_TEXT, init=INIT_TEXT, b=NUMBER_TEXT)
def test_fuzz_info_cli(eta, init, b):
    code, out, err = run_cli(["info", "--json", f"--b={b}", f"--eta={eta}", f"--init={init}"])
    assert "Traceback" not in err and code in (0, 2), (code, err)
    if code == 0:
        d = json.loads(out)  # valid JSON (NaN would be refused by the parser below)
        assert all(math.isfinite(v) for v in d["integrals"].values())
    else:
        assert len([ln for ln in err.splitlines() if ln.strip()]) == 1


@given(init=st.lists(st.floats(-5, 5), min_size=9, max_size=9), re=st.floats(-8, 8), im=st.floats(-3, 3))
def test_fuzz_public_map(init, re, im):
    """The map: a JetGaudinError, or a finite real state with the integrals preserved."""
    assume(im != 0)
    try:
        B = jg.TwoPointBacklund(1.0, complex(re, im))
        X = B(np.array(init))
    except jg.JetGaudinError:
        return
    assert np.all(np.isfinite(X))
    I0, I1 = jg.integrals(np.array(init), 1.0), jg.integrals(X, 1.0)
    # round-off: a few ulps of the largest term (|y|^2 <= 75 here) times the conditioning of the step;
    # steps that lose more than 1e-6 must have raised SingularStepError instead
    assert np.max(np.abs(I1 - I0)) <= 1e-6 * (1 + np.max(np.abs(I0)))


MODERATE_HOSTILE = st.sampled_from([0.0, -0.0, 5e-324, -5e-324, 2.2250738585072014e-308, 1e-300, 1e50, -1e50,
                                     1.0, -3.0, 0.5, math.nan, math.inf])


@given(X=st.lists(MODERATE_HOSTILE, min_size=0, max_size=12), b=MODERATE_HOSTILE)
def test_fuzz_public_map_hostile_states(X, b):
    """Hostile states and fields (NaN, inf, subnormals, -0.0, 1e50, wrong lengths): the map raises a
    JetGaudinError or returns a finite state.  (Magnitudes whose squares overflow:
    test_overflowing_input_raises_jetgaudin_error.)"""
    try:
        with np.errstate(all="ignore"):
            r = jg.TwoPointBacklund(b, 5 + 0.1j)(X)
    except jg.JetGaudinError:
        return
    assert np.all(np.isfinite(r)), (X, b, r)


@pytest.mark.parametrize("case", ["integrals", "casimirs", "map_big_state", "map_big_field"])
def test_overflowing_input_raises_jetgaudin_error(case):
    f = {"integrals": lambda: jg.integrals([0.0, 0.0, 1e308], 1.0),
         "casimirs": lambda: jg.casimirs([0.0, 0.0, 1e308]),
         "map_big_state": lambda: jg.TwoPointBacklund(1.0, 5 + 0.1j)([0.0, 1e308, 0.0]),
         "map_big_field": lambda: jg.TwoPointBacklund(1e308, 5 + 0.1j)([0.0, 0.0, 1.0])}[case]
    with np.errstate(all="ignore"), pytest.raises(jg.JetGaudinError):
        f()


@pytest.fixture(scope="module")
def interrupted_run(tmp_path_factory):
    """An interrupted run (SIGINT after 40 of 200 steps) to damage and resume."""
    import signal

    d = tmp_path_factory.mktemp("run")

    class Interrupting:
        def __init__(self):
            self.B, self.k = jg.TwoPointBacklund(1.0, 5 + 0.1j), 0

        def step(self, X, nu1):
            self.k += 1
            if self.k == 40:
                os.kill(os.getpid(), signal.SIGINT)
            return self.B.step(X, nu1)

    with pytest.raises(rec.RunInterrupted):
        rec.run_orbit(rec.OrbitSpec(1.0, 5 + 0.1j, 200, tuple(APPENDIX2_X0)), d, backlund=Interrupting(),
                      options=rec.RecordOptions(checkpoint_seconds=0.0))
    return d, jg.TwoPointBacklund(1.0, 5 + 0.1j).iterate(APPENDIX2_X0, 200, kernel="numpy")


@given(which=st.sampled_from(["run.json", "orbit.h5", "orbit.csv"]), mode=st.sampled_from(["truncate", "flip"]),
       frac=st.floats(0, 1), bit=st.integers(0, 7))
def test_fuzz_resume_of_damaged_files(interrupted_run, which, mode, frac, bit):
    """A truncated or bit-flipped file passed to --resume: a clear error, or exactly the true orbit."""
    src, ref = interrupted_run
    with resume_damaged_copy(src, which, mode, frac, bit, ["orbit", "--no-plots"]) as d:
        if d is not None:  # the damage hit bytes that carry no data (free space, the 'updated' time, ...)
            n, X = rec.load_orbit(d)
            assert np.array_equal(X, ref)


@contextlib.contextmanager
def resume_damaged_copy(src, which, mode, frac, bit, command):
    """Copy the run ``src``, truncate ``which`` at ``frac`` or flip one bit there, and resume it with ``command``:
    a one-line error (exit 2; yields None) or a completed resume (exit 0; yields the directory)."""
    import shutil

    with tempfile.TemporaryDirectory() as d:
        d = Path(d) / "r"
        shutil.copytree(src, d)
        path = d / which
        data = bytearray(path.read_bytes())
        at = min(len(data) - 1, int(frac * len(data)))
        if mode == "truncate":
            data = data[:at]
        else:
            data[at] ^= 1 << bit
        path.write_bytes(bytes(data))
        code, _, err = run_cli([command[0], "--resume", d, *command[1:]])
        assert "Traceback" not in err
        assert code in (0, 2), (code, err)
        if code == 2:
            assert len([ln for ln in err.splitlines() if ln.strip()]) == 1
        yield d if code == 0 else None


# ---------------------------------------------------------------------------------------------- ensembles
def check_ensemble_outcome(code, err, out_dir: Path):
    """A clear error (one line, exit 1 or 2) or a completed run whose rows are finite and healthy."""
    from jetgaudin.ensemble_recording import load_ensemble

    assert "Traceback" not in err, err
    assert code in (0, 1, 2), (code, err)
    if code != 0:
        lines = [ln for ln in err.splitlines() if ln.strip()]
        assert len(lines) >= 1 and lines[-1].startswith("jetgaudin"), err
        if code == 2:
            assert len(lines) == 1, err
        return
    run = rec.read_run(out_dir)
    assert run["status"] == "completed"
    assert np.all(np.isfinite(load_ensemble(out_dir).states))


@given(b=NUMBER_TEXT, eta=ETA_TEXT, casimirs=INIT_TEXT, steps=st.integers(-3, 4), orbits=st.integers(-1, 3),
       n=st.integers(-1, 4), every=st.integers(-1, 3))
def test_fuzz_ensemble_cli(b, eta, casimirs, steps, orbits, n, every):
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "e"
        code, _, err = run_cli(["ensemble", "--sample", "leaf", f"--casimirs={casimirs}", f"--n={n}",
                                f"--orbits={orbits}", f"--b={b}", f"--eta={eta}", f"--steps={steps}",
                                f"--save-every={every}", "--no-progress", "--out", out])
        check_ensemble_outcome(code, err, out)


@given(content=st.one_of(st.text(max_size=60).map(str.encode), st.binary(max_size=60),
                         st.lists(st.lists(NUMBERS, min_size=1, max_size=7), min_size=1, max_size=3).map(
                             lambda rows: "\n".join(",".join(repr(v) for v in r) for r in rows).encode())))
def test_fuzz_ensemble_input_file(content):
    """Garbage CSV input (text, binary, ragged or hostile numbers): a clear error or a correct run."""
    with tempfile.TemporaryDirectory() as d:
        f = Path(d) / "x.csv"
        f.write_bytes(content)
        code, _, err = run_cli(["ensemble", "--input", f, "--steps=2", "--no-progress", "--out", Path(d) / "e"])
        check_ensemble_outcome(code, err, Path(d) / "e")


@pytest.fixture(scope="module")
def interrupted_ensemble(tmp_path_factory):
    """An ensemble interrupted (SIGINT) after about 20 of 60 steps, to damage and resume."""
    import signal

    from jetgaudin import ensemble_recording as er
    from jetgaudin.ensemble import iterate_ensemble, sample_on_leaf

    d = tmp_path_factory.mktemp("ens")
    spec = er.EnsembleSpec(sample_on_leaf(3, [0.4, -0.3, 1.5], 4, seed=2), 1.0, 5 + 0.1j, 60, 3)

    def progress(n, steps):
        if n >= 20:
            os.kill(os.getpid(), signal.SIGINT)

    with pytest.raises(rec.RunInterrupted):
        er.run_ensemble(spec, d, max_chunk_steps=4, checkpoint_seconds=0.0, progress=progress)
    return d, iterate_ensemble(spec.X0, 1.0, 5 + 0.1j, 60, save_every=3).states


@given(which=st.sampled_from(["run.json", "ensemble.h5", "checkpoint-0.npz", "checkpoint-1.npz"]),
       mode=st.sampled_from(["truncate", "flip"]), frac=st.floats(0, 1), bit=st.integers(0, 7))
def test_fuzz_ensemble_resume_of_damaged_files(interrupted_ensemble, which, mode, frac, bit):
    """A truncated or bit-flipped file passed to `ensemble --resume`: a clear error, or exactly the true rows."""
    from jetgaudin.ensemble_recording import load_ensemble

    src, ref = interrupted_ensemble
    with resume_damaged_copy(src, which, mode, frac, bit, ["ensemble", "--no-progress"]) as d:
        if d is not None:  # the damage hit bytes that carry no data (the unused checkpoint slot, free space, ...)
            assert np.array_equal(load_ensemble(d).states, ref)
