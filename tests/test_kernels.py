"""Compiled (Numba) kernels of the real two-point map against the NumPy reference route."""

import os
import tempfile

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.backlund import _kernels
from jetgaudin.ensemble import sample_on_leaf

from conftest import APPENDIX2_B, APPENDIX2_ETA, APPENDIX2_X0

# Tolerance for "same orbit to round-off".  Both routes are backward stable per step (a few ulp of
# the state); on the invariant torus the error grows at most linearly with the number of steps
# (a phase error), so after n steps the two orbits differ by ~ n * (few ulp) * max|X|.  We allow
# 1e-14 per step relative to max|X| (~ 50 ulp per step), well below any genuine discrepancy
# (a wrong formula shows up at the 1e-3 level after one step).
PER_STEP_RTOL = 1e-14


def _scale(orbit):
    return np.max(np.abs(orbit))


def test_appendix2_1000_steps_compiled_matches_numpy():
    B = jg.TwoPointBacklund(APPENDIX2_B, APPENDIX2_ETA)
    ref = B.iterate(APPENDIX2_X0, 1000, kernel="numpy")
    for kern in ("compiled",):
        orb = B.iterate(APPENDIX2_X0, 1000, kernel=kern)
        assert orb.shape == ref.shape == (1001, 9)
        assert np.max(np.abs(orb - ref)) <= 1000 * PER_STEP_RTOL * _scale(ref)
    # the generic route on N = 3 as well
    out, _, _, _ = _kernels.iterate_single(APPENDIX2_X0, APPENDIX2_B, APPENDIX2_ETA, B.nu1(APPENDIX2_X0), False,
                                           1000, 1, specialise=False)
    assert np.max(np.abs(out - ref)) <= 1000 * PER_STEP_RTOL * _scale(ref)


@pytest.mark.parametrize("N", [1, 2, 3, 4, 5])
@pytest.mark.parametrize("eta", [5 + 0.1j, 0.6 - 0.2j])  # |eta| >= 1 (bottom-up division) and < 1 (top-down)
def test_random_states_compiled_matches_numpy(N, eta, rng):
    c = np.zeros(N)
    c[-1] = 1.0
    c[:-1] = rng.uniform(-0.5, 0.5, N - 1)
    X0 = sample_on_leaf(N, c, 3, seed=int(rng.integers(1 << 30)), scale=0.5)
    B = jg.TwoPointBacklund(1.3, eta)
    steps = 200
    # near the pole (|eta| < 1, top-down division) the map amplifies round-off more: the NumPy route
    # itself moves by ~1e-12 after 200 steps (N = 5) when X0 is perturbed by 1e-16 relative (measured),
    # so "round-off" is 1e-13 per step there
    rtol = PER_STEP_RTOL if abs(eta) >= 1 else 10 * PER_STEP_RTOL
    for x in X0:
        ref = B.iterate(x, steps, kernel="numpy")
        nu0 = B.nu1(x)
        gen, _, _, _ = _kernels.iterate_single(x, 1.3, eta, nu0, False, steps, 1, specialise=False)
        assert np.max(np.abs(gen - ref)) <= steps * rtol * _scale(ref)
        comp = B.iterate(x, steps, kernel="compiled")  # N = 3: the closed-form kernel
        assert np.max(np.abs(comp - ref)) <= steps * rtol * _scale(ref)


def test_one_step_matches_numpy_to_few_ulp(rng):
    # one step: no accumulation; the two routes differ by a few ulp of the state (tolerance 1e-14
    # relative, i.e. ~ 50 ulp, allows for the conditioning of the division by (l - eta)(l - conj eta))
    X = sample_on_leaf(3, [0.3, -0.2, 2.0], 20, seed=5)
    B = jg.TwoPointBacklund(0.7, 3 - 0.25j)
    ref = B(X)
    comp = B.iterate(X, 1, kernel="compiled")[1]
    assert np.max(np.abs(comp - ref)) <= 1e-14 * _scale(ref)


def test_compiled_preserves_integrals_and_inverse():
    # independent checks of the compiled route: the 2N integrals (Prop. 2) are preserved, and the
    # "opposite" branch undoes the map.  Tolerances: 1e-13 relative after 1000 steps (round-off
    # random walk of ~1e-16 per step, measured drift ~1e-13).
    B = jg.TwoPointBacklund(APPENDIX2_B, APPENDIX2_ETA)
    orb = B.iterate(APPENDIX2_X0, 1000, kernel="compiled")
    I0 = jg.integrals(APPENDIX2_X0, APPENDIX2_B)
    drift = np.max(np.abs(jg.integrals(orb, APPENDIX2_B) - I0) / np.maximum(1, np.abs(I0)))
    assert drift < 1e-12
    back = B.inverse().iterate(orb[-1], 1000, kernel="compiled")[-1]
    assert np.max(np.abs(back - APPENDIX2_X0)) < 1e-11


def test_chunked_runs_equal_unsplit_bit_for_bit():
    B = jg.TwoPointBacklund(APPENDIX2_B, APPENDIX2_ETA)
    for kern in ("compiled", "numpy"):
        full = B.iterate(APPENDIX2_X0, 60, kernel=kern)
        a, nu = B.iterate(APPENDIX2_X0, 25, kernel=kern, return_nu=True)
        b, nu2 = B.iterate(a[-1], 35, kernel=kern, nu1=nu, return_nu=True)
        assert np.array_equal(np.concatenate([a, b[1:]]), full)
        _, nu_full = B.iterate(APPENDIX2_X0, 60, kernel=kern, return_nu=True)
        assert nu2 == nu_full


def test_save_every_and_batches_bit_for_bit(rng):
    B = jg.TwoPointBacklund(APPENDIX2_B, APPENDIX2_ETA)
    for kern in ("compiled", "numpy"):
        full = B.iterate(APPENDIX2_X0, 100, kernel=kern)
        assert np.array_equal(B.iterate(APPENDIX2_X0, 100, save_every=7, kernel=kern), full[::7])
    X = sample_on_leaf(3, [0.5, 0.2, 1.0], 4, seed=3).reshape(2, 2, 9)
    batch = B.iterate(X, 50, kernel="compiled")
    assert batch.shape == (51, 2, 2, 9)
    for i in range(2):
        for j in range(2):
            assert np.array_equal(batch[:, i, j], B.iterate(X[i, j], 50, kernel="compiled"))


def test_auto_uses_compiled_once_loaded():
    B = jg.TwoPointBacklund(APPENDIX2_B, APPENDIX2_ETA)
    B.iterate(APPENDIX2_X0, 2, kernel="compiled")  # loads the N = 3 kernels in this process
    assert jg.backlund.auto_kernel(20, 9) == "compiled"
    assert np.array_equal(B.iterate(APPENDIX2_X0, 20), B.iterate(APPENDIX2_X0, 20, kernel="compiled"))


@pytest.mark.parametrize(("state", "work", "expected"), [
    ("cold", 1000, "numpy"), ("cold", 19_999, "numpy"), ("cold", 20_000, "compiled"),
    ("cached", 1999, "numpy"), ("cached", 2000, "compiled"), ("loaded", 1, "compiled"),
])
def test_auto_policy(monkeypatch, state, work, expected):
    # the thresholds of docs/performance.md (part f): loading cached kernels ~ 1000 NumPy steps, compiling ~ 6 s
    from jetgaudin.backlund.kernels import _select

    monkeypatch.setattr(_select, "kernels_state", lambda names: state)
    assert _select.auto_kernel(work, 9) == expected
    assert jg.backlund.auto_kernel is _select.auto_kernel  # maps re-exports the one implementation
    assert _select.auto_kernel(work // 4, 9, (4,)) == _select.auto_kernel(work // 4 * 4, 9)  # counts orbit-steps


def test_kernels_state_sees_the_cache():
    from jetgaudin.backlund import kernels

    jg.TwoPointBacklund(APPENDIX2_B, APPENDIX2_ETA).iterate(APPENDIX2_X0, 2, kernel="compiled")
    assert kernels.kernels_state(kernels.kernel_names(9, False)) == "loaded"
    assert kernels.kernels_state(("no_such_kernel",)) == "cold"


def test_cache_lookup_matches_numbas_file_names():
    # after warmup every kernel is loaded here and, in a fresh process (nothing loaded), found in Numba's cache:
    # the lookup's file names (<module>.<function>-*.nbi) are the ones Numba writes
    import subprocess
    import sys

    from jetgaudin.backlund import kernels

    report = kernels.warmup(notify=lambda msg: None)
    assert set(report.kernels) == set(kernels.KERNEL_MODULES)
    assert kernels.kernels_state(tuple(kernels.KERNEL_MODULES)) == "loaded"
    code = ("import sys; from jetgaudin.backlund import kernels as k; "
            "print([k.kernels_state((n,)) for n in k.KERNEL_MODULES]); "
            "print(k.configure.__module__ in sys.modules, any(m.endswith(('._n3', '._lanes')) for m in sys.modules), "
            "'numba' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split("\n")
    assert out[0] == str(["cached"] * len(kernels.KERNEL_MODULES))
    # importing the package imports no kernel module and not Numba (the target is configured at first use)
    assert out[1] == "True False False"


def test_prepare_says_what_it_compiles():
    from jetgaudin.backlund import kernels

    said = []
    kernels.warmup(notify=said.append)
    said.clear()
    report = kernels.prepare(9, None, notify=said.append)  # already loaded: nothing to say, no time
    assert report.state == "loaded" and report.seconds == 0.0 and said == []
    assert report.kernels == ("run_orbit3", "nu_default_kernel")
    assert kernels.kernel_names(9, True, 10_000) == ("run_lanes3", "nu_default_kernel")
    assert kernels.kernel_names(12, True, 10) == ("run_batch_generic", "nu_default_kernel")


@pytest.mark.parametrize(("steps", "save_every", "match"), [
    (2**63, 2**62, "steps"),  # beyond int64: was uninitialised memory (issue 11, item 8)
    (2**64, 1, "steps"),  # was a Numba TypingError
    (10, 2**63, "save_every"),
    (-1, 1, "steps"),
    (2**62, 1, "GiB"),  # 2^62 saved rows cannot be allocated: refused before allocating
])
def test_counts_are_validated_before_allocating(steps, save_every, match):
    B = jg.TwoPointBacklund(APPENDIX2_B, APPENDIX2_ETA)
    with pytest.raises(jg.InvalidParameterError, match=match):
        B.iterate(APPENDIX2_X0, steps, kernel="compiled", save_every=save_every)
    nu0 = B.nu1(APPENDIX2_X0)
    with pytest.raises(jg.InvalidParameterError, match=match):
        _kernels.iterate_single(APPENDIX2_X0, APPENDIX2_B, APPENDIX2_ETA, nu0, False, steps, save_every)
    with pytest.raises(jg.InvalidParameterError, match=match):
        _kernels.run_batch(APPENDIX2_X0[None], [APPENDIX2_B], [APPENDIX2_ETA], [nu0], False, steps, save_every)


def test_real_eta_is_refused():
    """Im eta = 0 (the identity map) is refused by the map itself, whatever the route (docs/architecture.md)."""
    with pytest.raises(jg.InvalidParameterError, match="Im eta = 0"):
        jg.TwoPointBacklund(1.0, 2.0, backend="compiled")


def test_state_along_the_field_is_a_fixed_point():
    # N = 1, y = (0, 0, 1): v = w = 0, s = 0 and M0 is diagonal, so the dressing is the identity.  The
    # projective eigenvector makes this regular (the ratio forms of s and kappa would divide by zero).
    B = jg.TwoPointBacklund(1.0, 2 + 0.5j)
    x = np.array([0.0, 0.0, 1.0])
    for kern in ("numpy", "compiled"):
        orb = B.iterate(x, 3, kernel=kern)
        assert np.allclose(orb, x, rtol=0, atol=1e-15)  # round-off of one division by |eta|^2


def test_status_codes_map_to_typed_errors():
    assert isinstance(_kernels.status_error(_kernels.STATUS_BRANCH, 3), jg.BranchPointError)
    for st in (_kernels.STATUS_RESIDUAL, _kernels.STATUS_NONFINITE):
        err = _kernels.status_error(st, 7, 2)
        assert isinstance(err, jg.SingularStepError) and "step 7 of orbit 2" in str(err)


def test_overflow_raises_singular_step():
    # entries ~1e200: u^2 overflows inside the step; the kernels report it instead of returning NaN
    B = jg.TwoPointBacklund(1.0, 5 + 0.1j)
    x = APPENDIX2_X0 * 1e200
    nu0 = 1.0 + 0j  # the branch rule itself would overflow; give a value to reach the kernel
    for spec in (True, False):
        with pytest.raises(jg.SingularStepError):
            _kernels.iterate_single(x, 1.0, B.eta, nu0, False, 2, 1, specialise=spec)


def test_wrong_nu_is_caught_by_the_residual():
    # a nu1 that is not an eigenvalue of l(eta) makes the division inexact: status RESIDUAL -> error
    for spec in (True, False):
        with pytest.raises(jg.SingularStepError, match="remainder"):
            _kernels.iterate_single(APPENDIX2_X0, APPENDIX2_B, APPENDIX2_ETA, 1.0 + 0j, False, 1, 1,
                                    specialise=spec)


def test_bad_arguments():
    B = jg.TwoPointBacklund(APPENDIX2_B, APPENDIX2_ETA)
    with pytest.raises(jg.InvalidParameterError, match="kernel"):
        B.iterate(APPENDIX2_X0, 3, kernel="fortran")
    with pytest.raises(jg.InvalidParameterError, match="save_every"):
        B.iterate(APPENDIX2_X0, 3, save_every=0)
    with pytest.raises(jg.InvalidStateError):
        B.iterate([np.nan] * 9, 3, kernel="compiled")


@pytest.mark.parametrize("N", [1, 2, 3, 5])
def test_compiled_branch_rule_matches_nu(N, rng):
    # the compiled default branch of nu(eta) vs jetgaudin.nu (NumPy): same root, equal to round-off.
    # 1e-13 relative: the two evaluate nu^2 by different sums (Horner vs powers) near the pole lambda = 0
    c = np.zeros(N)
    c[-1] = 1.0
    c[:-1] = rng.uniform(-0.5, 0.5, N - 1)
    X = sample_on_leaf(N, c, 50, seed=N)
    eta = rng.uniform(-5, 5, 50) + 1j * rng.uniform(-1, 1, 50)
    b = rng.uniform(0.5, 2, 50) * rng.choice([-1, 1], 50)
    for sheet in (1, -1):
        got = _kernels.nu_default(X, b, eta, sheet)
        ref = np.array([jg.nu(eta[i], X[i], b[i], sheet=sheet) for i in range(50)])
        assert np.all(np.abs(got - ref) <= 1e-13 * np.abs(ref))
    with pytest.raises(jg.BranchPointError):
        _kernels.nu_default(X[:1], b[:1], [0.5j])  # Re(eta) = 0: the rule is undefined


def test_compiled_branch_rule_refuses_a_branch_point_on_the_segment():
    # N = 1, y = (1, 0, -2), b = 1: nu^2 = (l^2 - 4 l + 5)/l^2 vanishes at 2 +- i, on the segment [2, 2 + 2i]
    x = np.array([[1.0, 0.0, -2.0]])
    with pytest.raises(jg.BranchPointError):
        jg.nu(2 + 2j, x[0], 1.0)
    with pytest.raises(jg.BranchPointError):
        _kernels.nu_default(x, [1.0], [2 + 2j])
    # just off the line the rule is defined, and the two routes take the same root (1e-13, as above)
    for eta in (2.001 + 2j, 1.999 + 2j):
        ref = jg.nu(eta, x[0], 1.0)
        assert abs(_kernels.nu_default(x, [1.0], [eta])[0] - ref) <= 1e-13 * abs(ref)


def test_flop_count_is_consistent():
    # the generic count grows linearly in N (Horner, products, division are O(N) per step)
    f = [_kernels.flops_per_step(N, "generic")["total"] for N in range(1, 6)]
    d = np.diff(f)
    assert np.all(d > 0) and np.all(d == d[0])


def test_warmup_command_says_how_long_it_took():
    from typer.testing import CliRunner

    from jetgaudin.cli import app

    r = CliRunner().invoke(app, ["warmup"])
    assert r.exit_code == 0 and "warmup: 5 kernels" in r.output and " s" in r.output


def test_a_changed_kernel_source_invalidates_every_cached_kernel(tmp_path):
    # Numba keys a cached kernel by the content of its own file only; the kernels inline blocks of _scalar.py, so a
    # cache directory whose stamp records other kernel sources loses the kernels' cache files (they are recompiled)
    from jetgaudin.backlund import kernels
    from jetgaudin.backlund.kernels import _target

    for name in ("_lanes.run_lanes3-227.py311.nbi", "_lanes.run_lanes3-227.py311.1.nbc", "_n3.run_orbit3-9.py311.nbi",
                 "other.f-1.py311.nbi"):
        (tmp_path / name).write_text("x")
    (tmp_path / _target.STAMP_NAME).write_text("an older digest\n")
    digest = _target.sources_digest()
    assert _target.clean_cache_dir(str(tmp_path), digest) == 3
    assert sorted(p.name for p in tmp_path.iterdir()) == [_target.STAMP_NAME, "other.f-1.py311.nbi"]
    (tmp_path / "_n3.run_orbit3-9.py311.nbi").write_text("x")  # compiled from the present sources
    assert _target.clean_cache_dir(str(tmp_path), digest) == 0  # the stamp matches: kept
    # the directories the kernels really use carry the stamp of the present sources
    kernels.warmup(notify=lambda msg: None)
    lanes = kernels.kernel_module("_lanes")
    stamp = os.path.join(lanes.run_lanes3._cache._cache_path, _target.STAMP_NAME)
    assert open(stamp).read().strip() == digest


# ---------------------------------------------------------------------------------------------
# the real form of the N = 3 step (kernels/_n3.py): its formulas against the complex products of the NumPy route
# ---------------------------------------------------------------------------------------------

_SIGMA = np.array([[[0, 1], [1, 0]], [[0, -1j], [1j, 0]], [[1, 0], [0, -1]]])


def _from_python(block):
    """A kernel block, compiled without Numba's CPython wrapper (callable from compiled code only: a call from Python
    would crash), wrapped in a compiled function for the tests."""
    import numba  # after the kernels' set-up (kernel_module), which configures Numba's target

    return numba.njit(lambda *args: block(*args))


def _sigma(y):
    """``y·σ`` for real or complex 3-vectors ``y`` (..., 3): the ``ℓ_m = [[u, v], [w, −u]]`` of lax.ell_coefficients."""
    return np.einsum("...a,aij->...ij", np.asarray(y, dtype=complex), _SIGMA)


def test_real_form_of_the_dressing_products(rng):
    # M0 = -Re(eta) I + i Im(eta) n.sigma with n real and |n| = 1, so T1 = M0 l + l adj M0 and T2 = M0 l adj M0 are
    # the real maps 2m y - 2c n x y and |eta|^2 y - 2mc n x y + 2c^2 n x (n x y) (m = -Re eta, c = Im eta).  Reference:
    # the NumPy route's M0 (_dressing.real_two_point_M0) and 2x2 complex products; the axis n from the kernel block.
    from jetgaudin.backlund import _dressing
    from jetgaudin.backlund.kernels._drivers import kernel_module

    axis = _from_python(kernel_module("_n3")._axis)
    for _ in range(200):
        eta = complex(rng.uniform(-4, 4), rng.uniform(-3, 3)) * rng.choice([0.2, 1.0])
        k1, k2 = rng.normal(size=2) + 1j * rng.normal(size=2)
        y = rng.normal(size=3)
        M0 = _dressing.real_two_point_M0(eta, k1, k2)
        ell = _sigma(y)
        T1 = _dressing.mm(M0, ell) + _dressing.mm(ell, _dressing.adj(M0))
        T2 = _dressing.mm(_dressing.mm(M0, ell), _dressing.adj(M0))
        *n, r = axis(k1, k2, abs(k1) ** 2 + abs(k2) ** 2, 1.0)  # unnormalised axis n' and r = 1/|k|^2
        n = np.array(n) * r
        assert abs(n @ n - 1) <= 1e-15  # a few ulp
        m, c = -eta.real, eta.imag
        ny = np.cross(n, y)
        # 1e-13 relative to the largest term (|eta|^2 |y|): ~500 ulp; a wrong sign or factor is an O(1) error
        tol = 1e-13 * (1 + abs(eta)) ** 2 * np.linalg.norm(y)
        assert np.max(np.abs(_sigma(2 * m * y - 2 * c * ny) - T1)) <= tol
        assert np.max(np.abs(_sigma(abs(eta) ** 2 * y - 2 * m * c * ny + 2 * c * c * np.cross(n, ny)) - T2)) <= tol


@pytest.mark.parametrize("eta", [5 + 0.1j, 2 - 1j, 0.6 - 0.2j, 0.3 + 0.5j])  # both division directions
def test_real_form_step_equals_the_complex_division(eta, rng):
    # one dressing by the kernel block _dress3 (real form, one recurrence for both directions) against the NumPy
    # route's complex R(lambda) and Laurent division (_dressing.dress_two_point); and its residual test: exact for
    # the eigenvector of l(eta), refused (flag false) for a perturbed one, where the complex division leaves a
    # remainder.  Tolerance 1e-14 of the state (~50 ulp, as test_one_step_matches_numpy_to_few_ulp).
    import numba

    from jetgaudin import lax
    from jetgaudin.backlund import _dressing
    from jetgaudin.backlund.kernels._drivers import kernel_module

    n3 = kernel_module("_n3")
    axis, scale3 = _from_python(n3._axis), _from_python(n3._scale3)
    d3 = n3._dress3  # inlined by Numba at its call sites, which takes no *args
    dress3 = numba.njit(lambda x0, x1, x2, x3, x4, x5, x6, x7, x8, b, n1, n2, n3, r, cst:
                        d3(x0, x1, x2, x3, x4, x5, x6, x7, x8, b, n1, n2, n3, r, cst))
    cst = _from_python(n3._constants3)(eta)
    b = 1.3
    for x in sample_on_leaf(3, [0.3, -0.2, 1.0], 10, seed=int(rng.integers(1 << 30)), scale=0.5):
        ell = lax.ell_coefficients(x, b)
        le = _dressing.horner(ell, eta)
        u, v, w = le[0, 0], le[0, 1], le[1, 0]
        k1, k2 = (complex(k) for k in _dressing.eigenvector(u, v, w, jg.nu(eta, x, b)))
        for scale, exact in ((1.0, True), (1.0 + 1e-3, False)):
            M0 = _dressing.real_two_point_M0(eta, k1 * scale, k2)
            new, res = _dressing.dress_two_point(ell, eta, np.conj(eta), M0)
            ref = lax.state_from_ell(new).real
            n = axis(k1 * scale, k2, abs(k1 * scale) ** 2 + abs(k2) ** 2, 1.0)  # (n', r)
            ok, *got = dress3(*x, b, *n, cst)
            # the power-of-two scale of the axis (_scale3) changes no bit: 2^-40 and the state's own scale
            for q in (2.0**-40, scale3(*x, b)):
                nq = axis(k1 * scale, k2, abs(k1 * scale) ** 2 + abs(k2) ** 2, q)
                assert dress3(*x, b, *nq, cst) == (ok, *got)
            assert bool(ok) is exact and bool(res <= 1e-8 * (1 + np.max(np.abs(ell)))) is exact
            if exact:
                assert np.max(np.abs(np.array(got) - ref)) <= 1e-14 * np.max(np.abs(ref))


@pytest.mark.parametrize("rel", [1e-3, 1e-10, 1e-15])
def test_lanes_redo_path_equals_the_single_orbit(rel):
    # every third orbit gets nu1 off by `rel` (cont=True), so nu^2 changes by ~2 rel at the first step: 1e-3, the
    # Newton update is refused and the lane is redone by the second pass with the closest root; 1e-10 (above the
    # carry's 1e-13, below 1e-8), the lane is redone with nu1 set to its Newton update first; 1e-15, nu1 is used as
    # it is and its update carried.  Each is bit for bit the single-orbit route's case (a redone lane that kept its
    # old nu1, or took the update when it should carry it, differs in the first step's bits)
    X = sample_on_leaf(3, [0.5, 0.2, 1.0], 70, seed=4)
    b = np.full(70, 1.0)
    eta = np.full(70, 5 + 0.1j)
    nu = _kernels.nu_default(X, b, eta) * np.where(np.arange(70) % 3 == 0, 1 + rel, 1.0)
    out, _, _, nu_last, status, _ = _kernels.run_batch(X, b, eta, nu, True, 30, 1)
    assert np.all(status == 0)
    for i in (0, 1, 3, 66, 69):
        single, _, _, nu_i = _kernels.iterate_single(X[i], 1.0, 5 + 0.1j, nu[i], True, 30, 1)
        assert np.array_equal(out[i], single) and nu_i == nu_last[i]


def test_lanes_with_failed_members_equal_their_single_orbits():
    # a block of lanes with a failed member (the lanes' selects keep a failed or dead lane's state, ν1 and status in
    # place): every member, failed or not, equals its single-orbit run bit for bit, and a
    # failed member keeps its last good state.  40 orbits: a block of 32 lanes with failures and redone lanes, and
    # a block of 8 without
    from jetgaudin.backlund.kernels import _drivers

    X = sample_on_leaf(3, [0.5, 0.2, 1.0], 40, seed=4)
    b = np.full(40, 1.0)
    eta = np.full(40, 5 + 0.1j)
    nu = _kernels.nu_default(X, b, eta)
    nu[[3, 17]] *= 1 + 1e-3  # not the eigenvalue: used as given (cont=False) it fails; continued, it is redone
    nu[5] *= -1  # the other sheet: a valid eigenvalue, stepped as given
    X[20] *= 1e155  # overflows in the first step
    nu[20] = 1.0
    single = _drivers.single_kernel(9, True)
    for cont, failing in ((False, {3, 17, 20}), (True, {20})):
        out, final, _, nu_last, status, fail = _kernels.run_batch(X, b, eta, nu, cont, 30, 1)
        assert set(np.flatnonzero(status)) == failing
        for i in range(40):
            ref = np.empty((31, 9))
            ref_final = np.empty(9)
            st, n, nu_i = single(X[i], 1.0, 5 + 0.1j, nu[i], cont, 30, 1, ref, ref_final, np.empty(6), False)
            assert status[i] == st and fail[i] == n
            assert np.array_equal(out[i, : n + 1], ref[: n + 1]) and np.array_equal(final[i], ref_final)
            if st:
                assert np.array_equal(out[i, n:], np.broadcast_to(ref_final, (31 - n, 9)))  # frozen
            else:
                assert nu_last[i] == nu_i


_FMA_SCRIPT = """
import numba
from jetgaudin.backlund.kernels import _target
_target.configure()
from jetgaudin.backlund.kernels import _scalar
f = numba.njit(lambda a, b, c: _scalar._fma(a, b, c))
print(repr(f(0.1, 10.0, -1.0)), repr(f(1.0 + 2.0**-30, 1.0 - 2.0**-30, -1.0)))
"""


@pytest.mark.parametrize("cpu", ["host", "generic"])
def test_fused_multiply_add_is_rounded_once_on_every_target(cpu):
    # the N = 3 blocks' explicit a*b + c (llvm.fma): one rounding, so the exact values below (from fractions, not
    # from the code); 0.1*10 - 1 and (1 + e)(1 - e) - 1 rounded twice give 0.0.  "generic" is a target without FMA
    # instructions (Numba's NUMBA_CPU_NAME): LLVM then calls the C library's fma, which must give the same bits
    import subprocess
    import sys
    from fractions import Fraction

    src = os.path.dirname(os.path.dirname(jg.__file__))
    env = dict(os.environ, NUMBA_CACHE_DIR=tempfile.mkdtemp(), PYTHONPATH=src)
    if cpu == "generic":
        env["NUMBA_CPU_NAME"] = "generic"
    out = subprocess.run([sys.executable, "-c", _FMA_SCRIPT], capture_output=True, text=True, env=env, check=True,
                         timeout=300).stdout.split()
    exact = [float(Fraction(0.1) * 10 - 1), float(Fraction(1 + 2.0**-30) * Fraction(1 - 2.0**-30) - 1)]
    assert [float(v) for v in out] == exact
    assert exact[0] != 0.1 * 10.0 - 1.0 and exact[1] == -(2.0**-60)


@pytest.mark.parametrize("size", [1e-100, 1e60, 1e120, 1e145])
def test_n3_route_covers_huge_and_tiny_states(size):
    # the unnormalised axis n' = q |k|^2 n-hat grows like |y|^2; the power of two q of _scale3 keeps the cross
    # products n' x y of the size of y, so the compiled N = 3 route steps states up to ~1e150 like the NumPy route
    # (without q it failed from ~1e102 on).  Appendix 2's state times `size`; 1e-13 of the state over 5 steps (the
    # routes' 1e-14 per step, as tests/test_routes.py)
    X = np.array(APPENDIX2_X0) * size
    m = jg.TwoPointBacklund(APPENDIX2_B, APPENDIX2_ETA)
    ref = m.iterate(X, 5, kernel="numpy")
    got = m.iterate(X, 5, kernel="compiled")
    assert np.max(np.abs(got - ref)) <= 1e-13 * np.max(np.abs(ref))


def test_scale_power_of_two_from_the_bits_equals_frexp_ldexp():
    # _n3._scale3 builds q = 2^(-2E) (E: frexp's exponent of the state's size) from the bits of the size; the
    # reference is the C library's frexp/ldexp, over the whole range: normal q, subnormal q (sizes > 2^511), zero
    # (sizes > 2^537), and no scaling (1.0) for sizes >= 1e300, inf or NaN; at powers of two and just below them
    import math

    from jetgaudin.backlund.kernels import _drivers

    n3 = _drivers.kernel_module("_n3")
    size3, scale3 = _from_python(n3._size3), _from_python(n3._scale3)
    rng = np.random.default_rng(11)
    sizes = ([2.0**k for k in range(-1000, 997)] + [np.nextafter(2.0**k, 0) for k in range(1, 997)]
             + list(rng.uniform(0, 1, 2000) * 10.0 ** rng.integers(-300, 300, 2000)) + [0.0, 9.9e299, 1e300, np.inf,
                                                                                       np.nan])
    for v in sizes:
        sc = size3(v, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        ref = math.ldexp(1.0, -2 * math.frexp(sc)[1]) if sc < 1e300 else 1.0
        got = scale3(v, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        assert got == ref and math.copysign(1.0, got) == 1.0, v


@pytest.mark.parametrize("rel", [0.0, 1e-15, 1e-11, 1e-9, 1e-6])
def test_a_continued_nu1_off_by_rel_gives_the_accurate_orbit(rel):
    # the N = 3 route uses the carried nu1 as it is when nu^2 changed by less than 1e-13 relative (its Newton
    # update carried to the next step, off the dependency chain), applies the update first up to 1e-8, and takes the
    # closest root above: for each case the orbit continued from a nu1 off by `rel` equals the NumPy route's to the
    # round-off tolerance of this file (an update skipped wrongly would leave an error ~ rel in the first step)
    B = jg.TwoPointBacklund(APPENDIX2_B, APPENDIX2_ETA)
    ref = B.iterate(APPENDIX2_X0, 20, kernel="numpy")
    nu = B.nu1(APPENDIX2_X0) * (1 + rel)
    for spec in (True, False):
        out, _, _, _ = _kernels.iterate_single(APPENDIX2_X0, APPENDIX2_B, APPENDIX2_ETA, nu, True, 20, 1,
                                               specialise=spec)
        assert np.max(np.abs(out - ref)) <= 20 * PER_STEP_RTOL * _scale(ref)


@pytest.mark.parametrize("N, specialise", [(1, False), (2, False), (3, False), (3, True), (4, False)])
def test_drift_monitor_integrals_are_jg_integrals(N, specialise):
    # the kernels' drift pass (_scalar._integrals, _drift_pass) against jetgaudin.integrals of the same rows, the
    # definition drift_k = max_n |I_k(x_n) - I_k(x_0)| / max(1, |I_k(x_0)|), computed here from the saved rows.
    # The two sums add the same terms in another order: a few ulp of the largest term (|I| <= ~50 here), so 1e-13
    # absolute; a wrong integral formula is not preserved by the map and drifts at the 1e-2..1e-1 level (b y^3
    # for 2b y^3 in H_1: planted, this test fails).
    X = sample_on_leaf(N, np.linspace(0.5, 2.0, N), 1, seed=7 + N, scale=1.5)[0]
    b, eta = 1.3, 2 - 1j
    B = jg.TwoPointBacklund(b, eta)
    out, final, drift, _ = _kernels.iterate_single(X, b, eta, B.nu1(X), False, 50, 5, specialise=specialise)
    rows = np.concatenate([out, final[None]])
    I = jg.integrals(rows, b)
    want = np.max(np.abs(I - I[0]) / np.maximum(1.0, np.abs(I[0])), axis=0)
    assert drift.shape == (2 * N,)
    assert np.max(np.abs(drift - want)) <= 1e-13
    # the batch kernels' drift pass (the lanes for N = 3, the prange loop otherwise), orbit by orbit
    Xb = np.stack([X, 1.1 * X, X[::-1].copy()])
    outb, finalb, driftb, _ = _kernels.iterate_batch(Xb, np.full(3, b), np.full(3, eta),
                                                     np.array([B.nu1(x) for x in Xb]), False, 50, 5,
                                                     specialise=specialise)
    for i in range(3):
        Ib = jg.integrals(np.concatenate([outb[i], finalb[i][None]]), b)
        wantb = np.max(np.abs(Ib - Ib[0]) / np.maximum(1.0, np.abs(Ib[0])), axis=0)
        assert np.max(np.abs(driftb[i] - wantb)) <= 1e-13
