"""Ensembles of Bäcklund orbits (jetgaudin.ensemble) and the `jetgaudin ensemble` command."""

import numpy as np
import pytest
from typer.testing import CliRunner

import jetgaudin as jg
from jetgaudin.ensemble import iterate_ensemble, sample_on_energy_shell, sample_on_leaf

from conftest import APPENDIX2_B, APPENDIX2_ETA, APPENDIX2_X0


@pytest.fixture
def batch(rng):
    B = 24
    X0 = sample_on_leaf(3, [0.4, -0.3, 1.5], B, seed=int(rng.integers(1 << 30)))
    b = rng.uniform(0.5, 2.0, B) * rng.choice([-1, 1], B)
    eta = rng.uniform(-6, 6, B) + 1j * rng.uniform(0.05, 0.4, B) * rng.choice([-1, 1], B)
    eta.real[np.abs(eta.real) < 0.5] += 1.0  # keep Re(eta) away from the pole at 0 (branch rule)
    return X0, b, eta


def test_member_equals_single_compiled_run_bit_for_bit(batch):
    X0, b, eta = batch
    res = iterate_ensemble(X0, b, eta, 120, save_every=7)
    assert res.states.shape == (120 // 7 + 1, len(b), 9)
    for i in range(len(b)):
        single, nu = jg.TwoPointBacklund(b[i], eta[i]).iterate(X0[i], 120, save_every=7, kernel="compiled",
                                                               return_nu=True)
        assert np.array_equal(res.states[:, i], single)
        assert res.nu[i] == nu
    # the generic route gives the same bits in an ensemble as in a single run as well
    gen = iterate_ensemble(X0[:3], b[:3], eta[:3], 30, specialise=False)
    from jetgaudin.backlund import _kernels

    for i in range(3):
        nu0 = _kernels.nu_default(X0[i : i + 1], b[i : i + 1], eta[i : i + 1])[0]
        single = _kernels.iterate_single(X0[i], b[i], eta[i], nu0, False, 30, 1, specialise=False)[0]
        assert np.array_equal(gen.states[:, i], single)


def test_member_matches_numpy_route(batch):
    # round-off agreement: 1e-14 per step relative to max|X| (see tests/test_kernels.py for the argument)
    X0, b, eta = batch
    steps = 60
    res = iterate_ensemble(X0[:6], b[:6], eta[:6], steps)
    for i in range(6):
        ref = jg.TwoPointBacklund(b[i], eta[i]).iterate(X0[i], steps, kernel="numpy")
        rtol = 1e-14 if abs(eta[i]) >= 1 else 1e-13
        assert np.max(np.abs(res.states[:, i] - ref)) <= steps * rtol * np.max(np.abs(ref))


def test_drift_equals_independent_computation(batch):
    # the kernel's drift vs jg.integrals on the returned states: the same sums in another order, so
    # they agree to a few ulp of the integrals (1e-14 absolute for integrals of size ~10)
    X0, b, eta = batch
    res = iterate_ensemble(X0, b, eta, 50, save_every=5)
    for i in range(len(b)):
        I = jg.integrals(res.states[:, i], b[i])
        I0 = I[0]
        drift = np.max(np.abs(I - I0) / np.maximum(1, np.abs(I0)), axis=0)
        assert np.allclose(res.drift[i], drift, rtol=0, atol=1e-14)
    assert res.max_drift.shape == (len(b),)
    assert np.all(res.max_drift < 1e-12)  # the map preserves the 2N integrals (Prop. 2)
    # the two reductions of the (B, 2N) table, by name: over the integrals (per orbit), over the orbits (per integral)
    assert np.array_equal(res.max_drift_per_orbit, res.drift.max(axis=1))
    assert np.array_equal(res.max_drift, res.max_drift_per_orbit)
    assert res.max_drift_per_integral.shape == (X0.shape[1] // 3 * 2,)
    assert np.array_equal(res.max_drift_per_integral, res.drift.max(axis=0))


def test_continuation_with_nu_equals_unsplit_run(batch):
    X0, b, eta = batch
    full = iterate_ensemble(X0, b, eta, 40)
    a = iterate_ensemble(X0, b, eta, 15)
    c = iterate_ensemble(a.final, b, eta, 25, nu1=a.nu)
    assert np.array_equal(np.concatenate([a.states, c.states[1:]]), full.states)


def test_root_fallback_bit_for_bit(batch):
    # nu1 off by 1e-6: the Newton continuation of nu1 is refused at the first step and the closest-root
    # rule is used (in the lock-stepped ensemble kernel, by re-running that lane with the scalar kernel)
    X0, b, eta = batch
    nu0 = iterate_ensemble(X0, b, eta, 0).nu * (1 + 1e-6)
    res = iterate_ensemble(X0, b, eta, 20, nu1=nu0)
    for i in range(len(b)):
        single, nu = jg.TwoPointBacklund(b[i], eta[i]).iterate(X0[i], 20, kernel="compiled", nu1=nu0[i],
                                                               return_nu=True)
        assert np.array_equal(res.states[:, i], single) and res.nu[i] == nu
    # and the continued root is the right one: the orbit matches the unperturbed run to round-off
    ref = iterate_ensemble(X0, b, eta, 20)
    assert np.max(np.abs(res.states - ref.states)) < 1e-11


def test_samplers(rng):
    c = np.array([0.4, -0.3, 1.5])
    X = sample_on_leaf(3, c, 50, seed=7)
    assert np.allclose(jg.casimirs(X), c, rtol=0, atol=1e-13)  # exact construction, round-off only
    assert np.array_equal(X, sample_on_leaf(3, c, 50, seed=7))  # seeded
    for N in (1, 2, 4):
        cN = rng.uniform(-1, 1, N)
        cN[-1] = 2.0
        assert np.allclose(jg.casimirs(sample_on_leaf(N, cN, 5, seed=1)), cN, rtol=0, atol=1e-13)
    E = sample_on_energy_shell(3, 1.5, 2.0, 40, seed=3)
    assert np.allclose(jg.physical_hamiltonian(3, 1.5)(E), 2.0, rtol=1e-14, atol=0)
    with pytest.raises(jg.InvalidParameterError):
        sample_on_leaf(3, [1, 2, -1], 5)
    with pytest.raises(jg.InvalidParameterError):
        sample_on_energy_shell(1, 1.0, 1.0, 5)


def test_bad_input():
    X = sample_on_leaf(3, [0.1, 0.1, 1.0], 4, seed=1)
    with pytest.raises(jg.InvalidStateError):
        iterate_ensemble(X[0], 1.0, 5 + 0.1j, 3)
    with pytest.raises(jg.InvalidParameterError, match="shape"):
        iterate_ensemble(X, [1.0, 2.0], 5 + 0.1j, 3)
    with pytest.raises(jg.InvalidParameterError, match="nonzero"):
        iterate_ensemble(X, [1.0, 0.0, 1.0, 1.0], 5 + 0.1j, 3)
    with pytest.raises(jg.InvalidParameterError, match="imaginary"):
        iterate_ensemble(X, 1.0, 5.0, 3)
    with pytest.raises(jg.InvalidParameterError, match="save_every"):
        iterate_ensemble(X, 1.0, 5 + 0.1j, 3, save_every=0)


def test_failing_orbit_is_named():
    X = np.stack([APPENDIX2_X0, APPENDIX2_X0 * 1e200])
    with pytest.raises(jg.SingularStepError, match="orbit 1"):
        iterate_ensemble(X, APPENDIX2_B, APPENDIX2_ETA, 3, nu1=[1.0 + 0j, 1.0 + 0j])


# ---------------------------------------------------------------------------------------------
# the command line
# ---------------------------------------------------------------------------------------------


@pytest.fixture
def cli():
    from jetgaudin.cli import app

    return CliRunner(), app


def test_cli_csv_and_npz_input(cli, tmp_path):
    from jetgaudin.ensemble_recording import load_ensemble

    runner, app = cli
    X0 = sample_on_leaf(3, [0.4, -0.3, 1.5], 3, seed=4)
    csv = tmp_path / "x.csv"
    np.savetxt(csv, X0, delimiter=",", header="y1,y2,y3,x1,x2,x3,z1,z2,z3")
    out = tmp_path / "a"
    r = runner.invoke(app, ["ensemble", "--input", str(csv), "--steps", "10", "--out", str(out), "--eta",
                            "4+0.2i", "--b", "2"])
    assert r.exit_code == 0, r.output
    ref = iterate_ensemble(X0, 2.0, 4 + 0.2j, 10)
    assert np.array_equal(load_ensemble(out).states, ref.states)
    npz = tmp_path / "x.npz"
    np.savez(npz, X=X0, b=np.array([1.0, 2.0, 3.0]), eta=np.array([4 + 0.2j, 5 + 0.1j, 3 - 0.3j]))
    r = runner.invoke(app, ["ensemble", "--input", str(npz), "--steps", "10", "--out", str(out), "--overwrite"])
    assert r.exit_code == 0, r.output
    ref = iterate_ensemble(X0, [1.0, 2.0, 3.0], [4 + 0.2j, 5 + 0.1j, 3 - 0.3j], 10)
    assert np.array_equal(load_ensemble(out).states, ref.states)


@pytest.mark.parametrize(
    "args",
    [
        ["--input", "x.csv", "--sample", "leaf"],  # two sources of initial states
        ["--sample", "leaf", "--casimirs", "0,0,1", "--seed", "-1"],  # issue 11, 9: a negative seed is input
        ["--sample", "leaf", "--casimirs", "0,0,1", "--orbits", "1e23"],  # far beyond memory: refused, exit 2
        ["--b", "1+1i", "--orbits", "3"],  # b must be real (issue 11, 10)
        ["--sample", "leaf", "--casimirs", "1,2", "--orbits", "3"],  # wrong number of Casimirs
        ["--sample", "energy", "--orbits", "3"],  # no --energy
        ["--sample", "leaf", "--casimirs", "0,0,1", "--orbits", "3", "--eta", "5"],  # real eta
        ["--input", "/nonexistent/x.csv"],
        ["--sample", "leaf", "--casimirs", "0,0,1", "--orbits", "0"],
    ],
)
def test_cli_bad_input_one_line_exit_2(cli, args, tmp_path):
    runner, app = cli
    r = runner.invoke(app, ["ensemble", *args, "--out", str(tmp_path)])
    assert r.exit_code == 2, r.output
    lines = [ln for ln in r.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and "error" in lines[0]
    assert "Traceback" not in r.output


def test_cli_default_sampling(cli, tmp_path):
    """Neither --input nor --sample: the documented default leaf (docs/cli.md), seeded (issue 11, item 10)."""
    from jetgaudin.ensemble import DEFAULT_CASIMIRS
    from jetgaudin.ensemble_recording import load_ensemble

    runner, app = cli
    r = runner.invoke(app, ["ensemble", "--orbits", "4", "--steps", "3", "--out", str(tmp_path / "d")])
    assert r.exit_code == 0, r.output
    X0 = sample_on_leaf(3, DEFAULT_CASIMIRS, 4, seed=0)
    assert np.array_equal(load_ensemble(tmp_path / "d").X0, X0)


def test_cli_bad_csv(cli, tmp_path):
    runner, app = cli
    bad = tmp_path / "bad.csv"
    bad.write_text("1,2,3,4\n5,6,7,8\n")
    r = runner.invoke(app, ["ensemble", "--input", str(bad)])
    assert r.exit_code == 2
    assert "3N" in r.output


def test_cli_bench_rejects_unknown_parts(cli):
    runner, app = cli
    r = runner.invoke(app, ["bench", "--parts", "az"])
    assert r.exit_code == 2 and "unknown part" in r.output


def test_bench_markdown_table():
    from jetgaudin.cli.bench import Row, rows_to_markdown

    md = rows_to_markdown([Row("a", "one orbit", 1.0e7, "steps/s", "note")], {"CPU(s)": "2"})
    assert "| a | one orbit | 1e+07 | steps/s | note |" in md and '"CPU(s)": "2"' in md
