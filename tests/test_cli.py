"""The `jetgaudin` command line, through its real entry point `jetgaudin.cli.main` (in-process, fast) and a
few subprocess runs of `python -m jetgaudin` and of the installed `jetgaudin` script.

Reference values never come from the CLI itself: orbits are recomputed with the public
`TwoPointBacklund.iterate` (a different driver loop), integrals with `jg.integrals`, and a few values by hand.
"""

import json
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.cli import main
from jetgaudin.recording import load_orbit, read_csv

from conftest import APPENDIX2_B, APPENDIX2_ETA, APPENDIX2_X0

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def run_cli(capsys, *args):
    """Run `jetgaudin ARGS` in-process; return (exit code, stdout, stderr)."""
    with pytest.raises(SystemExit) as exc:
        main([str(a) for a in args])
    out = capsys.readouterr()
    code = exc.value.code
    return (0 if code is None else code), out.out, out.err


def assert_one_line_error(code, err, expected=2):
    assert code == expected, err
    assert "Traceback" not in err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    assert lines[0].startswith("jetgaudin"), err


# ---------------------------------------------------------------------------------------------- orbit
@pytest.fixture(scope="module")
def appendix2_dir(tmp_path_factory):
    """`jetgaudin orbit` with no options, run once in an empty working directory."""
    cwd = tmp_path_factory.mktemp("cwd")
    old = os.getcwd()
    os.chdir(cwd)
    try:
        with pytest.raises(SystemExit) as exc:
            main(["orbit"])
    finally:
        os.chdir(old)
    assert exc.value.code in (0, None)
    return cwd / "jetgaudin-orbit"


def test_orbit_defaults_write_every_file(appendix2_dir):
    for name in ("orbit.csv", "orbit.h5", "run.json", "figure1.png", "figure2.png", "integrals.png"):
        assert (appendix2_dir / name).is_file(), name
    for name in ("figure1.png", "figure2.png", "integrals.png"):
        data = (appendix2_dir / name).read_bytes()
        assert data[:8] == PNG_MAGIC and len(data) > 20_000  # a real picture, not an empty canvas


def test_orbit_defaults_are_appendix2(appendix2_dir):
    run = json.loads((appendix2_dir / "run.json").read_text())
    inp = run["inputs"]
    assert inp["b"] == APPENDIX2_B and complex(*inp["eta"]) == APPENDIX2_ETA and inp["steps"] == 1000
    assert inp["init"] == APPENDIX2_X0.tolist() and inp["branch"] == "default" and inp["N"] == 3
    assert run["version"] == jg.__version__
    assert run["status"] == "completed" and run["last_safe_step"] == 1000
    # integrals at n = 0 by hand: H_1 = 2 b y^3 = -2.4, C_3 = |z|^2 = 1 (Prop. 2)
    assert run["integrals0"][0] == -2.4 and run["integrals0"][5] == 1.0
    np.testing.assert_array_equal(run["integrals0"], jg.integrals(APPENDIX2_X0, APPENDIX2_B))
    assert len(run["max_drift_abs"]) == 6 and len(run["max_drift_rel"]) == 6


def test_orbit_csv_round_trips_and_equals_the_map(appendix2_dir):
    text = (appendix2_dir / "orbit.csv").read_text()
    header, *rows = text.splitlines()
    assert header == "n,y0^1,y0^2,y0^3,y1^1,y1^2,y1^3,y2^1,y2^2,y2^3"
    assert len(rows) == 1001 and rows[0].startswith("0,") and rows[-1].startswith("1000,")
    n, X = read_csv(appendix2_dir / "orbit.csv")
    np.testing.assert_array_equal(n, np.arange(1001))
    # exact: 17 significant digits round-trip every double; the orbit is recomputed by another loop
    kernel = json.loads((appendix2_dir / "run.json").read_text())["inputs"]["kernel"]
    ref = jg.TwoPointBacklund(APPENDIX2_B, APPENDIX2_ETA).iterate(APPENDIX2_X0, 1000, kernel=kernel)
    assert np.array_equal(X, ref)
    n_h5, X_h5 = load_orbit(appendix2_dir)
    assert np.array_equal(X_h5, ref) and np.array_equal(n_h5, np.arange(1001))


def test_orbit_acceptance_numbers(appendix2_dir):
    """Issue 4 acceptance: |z| stays 1 and each integral drifts by <= 1e-11 (relative) over 1000 steps."""
    _, X = read_csv(appendix2_dir / "orbit.csv")
    I = jg.integrals(X, APPENDIX2_B)
    rel = np.max(np.abs(I - I[0]), axis=0) / np.abs(I[0])
    assert np.all(rel <= 1e-11), rel  # the bound; observed ~2e-13 (round-off accumulation)
    sphere = np.max(np.abs(np.linalg.norm(X[:, 6:9], axis=1) - 1.0))
    assert sphere <= 1e-12, sphere  # C_3 = |z|^2 is a Casimir; observed ~9e-14
    run = json.loads((appendix2_dir / "run.json").read_text())
    # run.json reports the same drifts (computed from the same saved rows)
    np.testing.assert_allclose(run["max_drift_rel"], rel, rtol=1e-12, atol=0)
    assert abs(run["sphere"]["max_deviation"] - sphere) <= 1e-15


def _recorded_kernel(out):
    """The kernel a run used ('auto' resolves by run length and Numba's cache; the two agree to round-off only)."""
    kernel = json.loads((out / "run.json").read_text())["inputs"]["kernel"]
    assert kernel in ("compiled", "numpy")
    return kernel


def test_orbit_summary_printed(tmp_path, capsys):
    code, out, err = run_cli(capsys, "orbit", "--steps", 5, "--no-plots", "--out", tmp_path / "o")
    assert code == 0, err
    for word in ("H_1", "C_3", "|z|", "orbit.csv", "orbit.h5", "run.json", "completed"):
        assert word in out, word


@pytest.mark.parametrize("eta", ["5+0.1j", "5+0.1i", "5 + 0.1 i", "5.0+1e-1J"])
def test_eta_spellings_give_the_same_orbit(tmp_path, capsys, eta):
    code, _, err = run_cli(capsys, "orbit", "--steps", 20, "--no-plots", "--eta", eta, "--out", tmp_path)
    assert code == 0, err
    _, X = read_csv(tmp_path / "orbit.csv")
    kernel = _recorded_kernel(tmp_path)
    assert np.array_equal(X, jg.TwoPointBacklund(1.0, 5 + 0.1j).iterate(APPENDIX2_X0, 20, kernel=kernel))


def test_all_orbit_options(tmp_path, capsys):
    init = "0.3,-0.1,0.7,0.2,0.5,-0.4,0.6,0.0,0.8"
    code, _, err = run_cli(capsys, "orbit", "--b", -1.5, "--eta", "3-0.2i", "--steps", 50, "--init", init,
                           "--branch", "opposite", "--save-every", 7, "--no-csv", "--no-plots",
                           "--max-drift", 1e-6, "--max-imag", 1e-6, "--kernel", "numpy", "--out", tmp_path / "x")
    assert code == 0, err
    d = tmp_path / "x"
    assert not (d / "orbit.csv").exists() and not (d / "figure1.png").exists()
    n, X = load_orbit(d)
    np.testing.assert_array_equal(n, list(range(0, 50, 7)) + [50])  # every 7th step and the last
    X0 = [float(v) for v in init.split(",")]
    ref = jg.TwoPointBacklund(-1.5, 3 - 0.2j, "opposite").iterate(X0, 50, kernel="numpy")
    assert np.array_equal(X, ref[n])
    run = json.loads((d / "run.json").read_text())
    assert run["inputs"]["branch"] == "opposite" and run["inputs"]["save_every"] == 7
    assert run["inputs"]["max_drift"] == 1e-6 and run["inputs"]["csv"] is False and run["inputs"]["kernel"] == "numpy"


def test_opposite_branch_is_the_inverse(tmp_path, capsys):
    code, _, err = run_cli(capsys, "orbit", "--steps", 1, "--branch", "opposite", "--no-plots", "--out", tmp_path)
    assert code == 0, err
    _, X = read_csv(tmp_path / "orbit.csv")
    back = jg.TwoPointBacklund(1.0, 5 + 0.1j)(X[1])
    # one forward step undoes one opposite step up to round-off (|X| ~ 3, a few ulps per step)
    np.testing.assert_allclose(back, APPENDIX2_X0, rtol=0, atol=1e-13)


@pytest.mark.parametrize("init", ["-2.4,-0.6,-1.2,1,0,0", "0.5,-0.2,0.3,0.1,0.4,-0.2,0.3,0.3,0.1,0.6,0.0,0.8"])
def test_orbit_N2_and_N4(tmp_path, capsys, init):
    X0 = np.array([float(v) for v in init.split(",")])
    code, _, err = run_cli(capsys, "orbit", "--steps", 30, "--init", init, "--out", tmp_path)
    assert code == 0, err
    _, X = read_csv(tmp_path / "orbit.csv")
    assert X.shape == (31, len(X0))
    kernel = _recorded_kernel(tmp_path)
    assert np.array_equal(X, jg.TwoPointBacklund(1.0, 5 + 0.1j).iterate(X0, 30, kernel=kernel))
    I = jg.integrals(X, 1.0)
    # preserved integrals: round-off level after 30 steps (|I| ~ 1)
    assert np.max(np.abs(I - I[0])) <= 1e-12
    for name in ("figure1.png", "figure2.png", "integrals.png"):
        assert (tmp_path / name).read_bytes()[:8] == PNG_MAGIC
    assert json.loads((tmp_path / "run.json").read_text())["inputs"]["N"] == len(X0) // 3


def test_steps_zero_writes_the_initial_state(tmp_path, capsys):
    code, _, err = run_cli(capsys, "orbit", "--steps", 0, "--no-plots", "--out", tmp_path)
    assert code == 0, err
    n, X = read_csv(tmp_path / "orbit.csv")
    assert n.tolist() == [0] and np.array_equal(X[0], APPENDIX2_X0)


def test_rerun_refuses_any_run_without_overwrite(tmp_path, capsys):
    """A new run never writes into a directory holding a run (completed or not) unless --overwrite (issue 11, 6)."""
    assert run_cli(capsys, "orbit", "--steps", 3, "--no-plots", "--out", tmp_path)[0] == 0
    before = (tmp_path / "orbit.csv").read_bytes()
    code, _, err = run_cli(capsys, "orbit", "--steps", 4, "--no-plots", "--out", tmp_path)
    assert_one_line_error(code, err)
    assert "holds a run (status completed)" in err and "--overwrite" in err
    assert (tmp_path / "orbit.csv").read_bytes() == before  # nothing touched
    run = json.loads((tmp_path / "run.json").read_text())
    run["status"] = "interrupted"
    (tmp_path / "run.json").write_text(json.dumps(run))
    code, _, err = run_cli(capsys, "orbit", "--steps", 4, "--no-plots", "--out", tmp_path)
    assert_one_line_error(code, err)
    assert "--resume" in err
    assert run_cli(capsys, "orbit", "--steps", 4, "--no-plots", "--overwrite", "--out", tmp_path)[0] == 0
    assert json.loads((tmp_path / "run.json").read_text())["inputs"]["steps"] == 4


# ---------------------------------------------------------------------------------------------- bad input
BAD_ORBIT = [
    (["--eta", "five"], "--eta"),
    (["--eta", "5+0.1k"], "--eta"),
    (["--eta", "nan+1i"], "--eta"),
    (["--eta", "5"], "--eta: eta must have a nonzero imaginary part (Im eta = 0"),  # the identity: refused
    (["--eta", "5+0i"], "Im eta = 0"),
    (["--init", "1,2"], "multiple of 3"),
    (["--init", "1,2,3,4"], "multiple of 3"),
    (["--init", ""], "--init"),
    (["--init", "1,2,x"], "not a number"),
    (["--init", "1,2,inf"], "not finite"),
    (["--init", ",".join(["0.1"] * 387)], "N <= 128"),
    (["--init", "0,0,1e200"], "too large"),
    (["--b", "0"], "nonzero"),
    (["--b", "-0.0"], "nonzero"),
    (["--b", "nan"], "finite"),
    (["--b", "abc"], "--b"),
    (["--b", "1e308"], "--b"),  # the message names the option at fault, not --init
    (["--b", "1e154"], "--b"),
    (["--eta", "0+0.1i"], "--eta: Re(eta) = 0"),
    (["--eta", "1e308+0.1i"], "--eta"),
    (["--steps", "-1"], ">= 0"),
    (["--steps", "1.5"], "--steps"),
    (["--save-every", "0"], "--save-every"),
    (["--max-drift", "-1"], "--max-drift"),
    (["--branch", "left"], "--branch"),
    (["--kernel", "fast"], "--kernel"),
    (["--bogus"], "--bogus"),
]


@pytest.mark.parametrize(("args", "word"), BAD_ORBIT, ids=[" ".join(a) for a, _ in BAD_ORBIT])
def test_orbit_bad_input_one_line_exit_2(tmp_path, capsys, args, word):
    code, out, err = run_cli(capsys, "orbit", "--no-plots", "--out", tmp_path / "o", *args)
    assert_one_line_error(code, err)
    assert word in err
    assert not (tmp_path / "o" / "orbit.csv").exists()


def test_unwritable_out(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    code, _, err = run_cli(capsys, "orbit", "--steps", 2, "--out", blocker / "sub")
    assert_one_line_error(code, err)
    assert "--out" in err
    if os.geteuid() != 0:  # root ignores permission bits
        ro = tmp_path / "ro"
        ro.mkdir()
        ro.chmod(0o500)
        code, _, err = run_cli(capsys, "orbit", "--steps", 2, "--out", ro)
        assert_one_line_error(code, err)


@pytest.mark.parametrize("out", ["", "/dev/null", "/proc/jetgaudin-x", "/sys/jetgaudin-x"])
def test_hostile_out_paths(tmp_path, capsys, out, monkeypatch):
    """An empty --out (it would mean the current directory), a device, and paths under /proc and /sys."""
    monkeypatch.chdir(tmp_path)
    for cmd in (["orbit", "--steps", 2, "--no-plots"], ["flow", "--steps", 2, "--no-plots"],
                ["ensemble", "--sample", "leaf", "--casimirs", "0,0,1", "--orbits", 2, "--steps", 2]):
        code, _, err = run_cli(capsys, *cmd, "--out", out)
        assert_one_line_error(code, err)
        assert "--out" in err
    assert list(tmp_path.iterdir()) == []  # nothing written into the current directory


def test_the_entry_point_flushes_everything_and_keeps_the_exit_code(tmp_path):
    """`python -m jetgaudin` ends by os._exit after main() (no interpreter teardown, ~0.5 s with the kernels
    loaded): the output written to a pipe must still be complete (a JSON document of tens of kB parses), and the
    exit codes stay those of main() (0, 2)."""
    import json
    import subprocess
    import sys

    p = subprocess.run([sys.executable, "-m", "jetgaudin", "verify", "--coverage", "--json"], capture_output=True,
                       text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    assert len(p.stdout) > 10_000 and len(json.loads(p.stdout)) > 100
    p = subprocess.run([sys.executable, "-m", "jetgaudin", "orbit", "--steps", "-1", "--out", str(tmp_path / "r")],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and "--steps" in p.stderr, p.stderr


def test_broken_pipe_is_not_a_failure(tmp_path):
    """`jetgaudin info | head -1`: the reader leaves early; exit 0 (exit 1 is reserved for failed runs)."""
    import subprocess
    import sys

    for cmd in (["info"], ["verify", "--only", "Hh"]):
        p = subprocess.Popen([sys.executable, "-m", "jetgaudin", *cmd], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        p.stdout.close()
        assert p.wait(timeout=120) == 0
        assert b"Traceback" not in p.stderr.read()
        p.stderr.close()


@pytest.mark.parametrize(
    "args",
    [["info", "--tol", "nan"], ["info", "--tol", "-1"], ["orbit", "--resume", ""],
     ["flow", "--eta", "x"], ["flow", "--b", "0"], ["flow", "--init", "1,2"], ["flow", "--steps", "-2"],
     ["flow", "--eta", "5"], ["flow", "--dt", "0"], ["flow", "--compare", "--hamiltonian", "physical"],
     ["flow", "--compare", "--dt", "0.5"], ["info", "--init", "1,2,3,4"], ["info", "--b", "0"],
     ["info", "--eta", "1+2k"], ["orbit", "--resume", "/nonexistent/dir"]],
)
def test_flow_info_resume_bad_input(tmp_path, capsys, args):
    code, _, err = run_cli(capsys, *args, "--out", tmp_path) if args[0] == "flow" else run_cli(capsys, *args)
    assert_one_line_error(code, err)


# ---------------------------------------------------------------------------------------------- flow
def test_flow_compare_map_is_time_one_flow(tmp_path, capsys):
    code, out, err = run_cli(capsys, "flow", "--compare", "--steps", 40, "--out", tmp_path)
    assert code == 0, err
    for name in ("flow.csv", "flow.h5", "orbit.csv", "orbit.h5", "compare.csv", "figure1.png", "figure2.png",
                 "integrals.png", "run.json"):
        assert (tmp_path / name).is_file(), name
    t, Xf = read_csv(tmp_path / "flow.csv")
    np.testing.assert_array_equal(t, np.arange(41.0))
    _, Xo = read_csv(tmp_path / "orbit.csv")
    # the same orbit as the map's own iterate, up to round-off (flow --compare uses the default kernel)
    np.testing.assert_allclose(Xo, jg.TwoPointBacklund(1.0, 5 + 0.1j).iterate(APPENDIX2_X0, 40), rtol=0, atol=1e-13)
    dist = np.loadtxt(tmp_path / "compare.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(dist[:, 1], np.linalg.norm(Xo - Xf, axis=1), rtol=1e-15, atol=0)
    # the map is exactly the time-1 flow of G_eta; DOP853 at rtol = atol = 1e-12 over t = 40 leaves ~1e-12
    assert dist[:, 1].max() <= 1e-9
    assert "distance map - flow" in out
    run = json.loads((tmp_path / "run.json").read_text())
    assert run["compare"]["max_distance"] == dist[:, 1].max()


def test_flow_physical_is_eq_em(tmp_path, capsys):
    from jetgaudin.systems import twisted_top_rhs

    code, _, err = run_cli(capsys, "flow", "--hamiltonian", "physical", "--dt", 1e-4, "--steps", 2, "--no-plots",
                           "--out", tmp_path)
    assert code == 0, err
    t, X = read_csv(tmp_path / "flow.csv")
    # central difference at t = dt against the equations of motion (em) written out: truncation
    # dt^2 |X'''| / 6 ~ 2e-7 (|X'''| ~ 1e2 here) plus integrator error ~ rtol |X| / dt ~ 3e-8
    deriv = (X[2] - X[0]) / (t[2] - t[0])
    np.testing.assert_allclose(deriv, twisted_top_rhs(X[1], 1.0), rtol=0, atol=1e-6)
    assert not (tmp_path / "figure1.png").exists()


def test_flow_heyoka_method(tmp_path, capsys):
    pytest.importorskip("heyoka")
    code, _, err = run_cli(capsys, "flow", "--method", "heyoka", "--steps", 5, "--no-plots", "--out", tmp_path)
    assert code == 0, err
    _, X = read_csv(tmp_path / "flow.csv")
    ref = jg.TwoPointBacklund(1.0, 5 + 0.1j).iterate(APPENDIX2_X0, 5)
    np.testing.assert_allclose(X, ref, rtol=0, atol=1e-10)  # Taylor method at tol 1e-12 vs the exact map


# ---------------------------------------------------------------------------------------------- info
def test_info_json_appendix2(capsys):
    code, out, err = run_cli(capsys, "info", "--json")
    assert code == 0, err
    d = json.loads(out)
    assert d["N"] == 3
    assert d["integrals"]["H_1"] == -2.4 and d["integrals"]["C_3"] == 1.0  # by hand (Prop. 2)
    np.testing.assert_array_equal(d["casimirs"], jg.casimirs(APPENDIX2_X0))
    nu = complex(*d["nu_default"])
    # nu(eta)^2 = u^2 + v w at eta (round-off of a few ulps of |nu^2| ~ 1)
    assert abs(nu**2 - jg.nu_squared(5 + 0.1j, APPENDIX2_X0, 1.0)) <= 1e-14
    assert complex(*d["nu_opposite"]) == -nu and nu.real > 0
    assert np.isfinite(d["G_eta"])
    assert d["on_canonical_leaf"] is False  # <x, z> = -2.19 != 0 (Appendix 2 is not on the leaf (fo))
    assert len(d["branch_points"]) == 6


def test_info_on_canonical_leaf(capsys):
    # z = e3, x = e1, y = (0.3, 0.2, -0.5): <x, z> = 0, |z| = 1, <y, z> + |x|^2/2 = 0 -> on the leaf
    code, out, _ = run_cli(capsys, "info", "--json", "--init", "0.3,0.2,-0.5,1,0,0,0,0,1")
    assert code == 0
    assert json.loads(out)["on_canonical_leaf"] in (True, None)  # None only if jetgaudin.canonical is absent


def test_info_table(capsys):
    code, out, _ = run_cli(capsys, "info", "--eta", "5+0.1j")
    assert code == 0
    for word in ("H_2", "Casimir C_1", "default root", "opposite root", "G_η", "canonical leaf", "branch points"):
        assert word in out, word


def test_version_and_help(capsys):
    code, out, _ = run_cli(capsys, "--version")
    assert code == 0 and out.strip() == jg.__version__
    code, out, _ = run_cli(capsys)
    assert code == 0 and "orbit" in out and "flow" in out and "info" in out
    for cmd in ("orbit", "flow", "info"):
        code, out, _ = run_cli(capsys, cmd, "--help")
        assert code == 0 and "--b" in out


def test_lazy_progress_draws_after_delay(capsys):
    from jetgaudin.cli._common import LazyProgress

    p = LazyProgress("orbit", delay=0.0, force=True)
    p(5, 10)
    p(10, 10)
    p.close()
    assert "10/10" in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------- subprocesses
def _env():
    env = dict(os.environ)
    env.pop("DISPLAY", None)  # plots must work without a display (Agg)
    env["MPLBACKEND"] = ""
    return env


def test_python_m_jetgaudin_subprocess(tmp_path):
    r = subprocess.run([sys.executable, "-m", "jetgaudin", "orbit", "--steps", "10", "--out", str(tmp_path)],
                       capture_output=True, text=True, timeout=120, env=_env())
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "figure1.png").read_bytes()[:8] == PNG_MAGIC
    r = subprocess.run([sys.executable, "-m", "jetgaudin", "orbit", "--init", "1,2", "--out", str(tmp_path)],
                       capture_output=True, text=True, timeout=120)
    assert_one_line_error(r.returncode, r.stderr)


@pytest.mark.skipif(shutil.which("jetgaudin") is None, reason="console script not installed (pip install -e .)")
def test_installed_script_subprocess(tmp_path):
    r = subprocess.run(["jetgaudin", "orbit", "--steps", "3", "--no-plots", "--out", str(tmp_path)],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    r = subprocess.run(["jetgaudin", "orbit", "--b", "0", "--out", str(tmp_path)], capture_output=True, text=True,
                       timeout=120)
    assert_one_line_error(r.returncode, r.stderr)


@pytest.mark.parametrize("init", ["-2.4,-0.6,-1.2,1,0,0", "0.5,-0.2,0.3,0.1,0.4,-0.2,0.3,0.3,0.1,0.6,0.0,0.8"])
def test_flow_compare_and_info_N2_N4(tmp_path, capsys, init):
    X0 = np.array([float(v) for v in init.split(",")])
    code, _, err = run_cli(capsys, "flow", "--compare", "--steps", 10, "--init", init, "--out", tmp_path)
    assert code == 0, err
    dist = np.loadtxt(tmp_path / "compare.csv", delimiter=",", skiprows=1)[:, 1]
    assert dist.max() <= 1e-9  # map = time-1 flow of G_eta for any N (DOP853 at rtol 1e-12 over t = 10)
    assert (tmp_path / "figure1.png").read_bytes()[:8] == PNG_MAGIC
    code, out, err = run_cli(capsys, "info", "--json", "--init", init)
    assert code == 0, err
    d = json.loads(out)
    assert d["N"] == len(X0) // 3 and len(d["integrals"]) == len(X0) // 3 * 2
    np.testing.assert_array_equal(list(d["integrals"].values()), jg.integrals(X0, 1.0))
    assert d["on_canonical_leaf"] in (False, None)  # the canonical realisation is for N = 3 only


def test_resume_through_the_cli(tmp_path, capsys):
    assert run_cli(capsys, "orbit", "--steps", 5, "--no-plots", "--out", tmp_path)[0] == 0
    code, _, err = run_cli(capsys, "orbit", "--resume", tmp_path)
    assert_one_line_error(code, err)
    assert "already completed" in err
    run = json.loads((tmp_path / "run.json").read_text())
    run["status"] = "interrupted"  # an edited run.json no longer matches its digest: refused
    (tmp_path / "run.json").write_text(json.dumps(run))
    code, _, err = run_cli(capsys, "orbit", "--resume", tmp_path)
    assert_one_line_error(code, err)
    assert "digest" in err
    code, _, err = run_cli(capsys, "orbit", "--resume", tmp_path, "--out", tmp_path / "elsewhere")
    assert_one_line_error(code, err)


def test_resume_with_different_inputs_is_refused(tmp_path, capsys):
    import signal

    from jetgaudin import recording as rec

    class Interrupting:  # the real map, interrupted by SIGINT at step 20
        def __init__(self):
            self.B, self.k = jg.TwoPointBacklund(1.0, 5 + 0.1j), 0

        def step(self, X, nu1):
            self.k += 1
            if self.k == 20:
                os.kill(os.getpid(), signal.SIGINT)
            return self.B.step(X, nu1)

    with pytest.raises(rec.RunInterrupted):
        rec.run_orbit(rec.OrbitSpec(1.0, 5 + 0.1j, 100, tuple(APPENDIX2_X0)), tmp_path, backlund=Interrupting())
    for args in (["--steps", 99], ["--eta", "5+0.2i"], ["--b", 2], ["--save-every", 3], ["--no-csv"]):
        code, _, err = run_cli(capsys, "orbit", "--resume", tmp_path, *args)
        assert_one_line_error(code, err)
        assert "different inputs" in err
    code, out, err = run_cli(capsys, "orbit", "--resume", tmp_path, "--steps", 100, "--eta", "5+0.1j")
    assert code == 0, err  # the same inputs, spelled out: accepted
    _, X = read_csv(tmp_path / "orbit.csv")
    assert np.array_equal(X, jg.TwoPointBacklund(1.0, 5 + 0.1j).iterate(APPENDIX2_X0, 100, kernel="numpy"))


@pytest.mark.parametrize(("args", "word"), [(["--max-drift", "1e-16"], "integral drift"),
                                            (["--max-imag", "1e-30"], "imaginary residue")])
def test_health_failure_exit_1(tmp_path, capsys, args, word):
    # thresholds below round-off (drift ~1e-15 per few steps, residue ~1e-18) must stop the run as failed
    code, out, err = run_cli(capsys, "orbit", "--steps", 200, "--no-plots", "--out", tmp_path, *args)
    assert_one_line_error(code, err, expected=1)
    assert word in err and "kept in" in err
    run = json.loads((tmp_path / "run.json").read_text())
    assert run["status"].startswith("failed: ") and word in run["status"]
