"""Bad input raises a specific jetgaudin exception whose message names the problem (never a silent NaN)."""

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin import _errors
from jetgaudin.lax import ell_coefficients, jet_coefficients, jet_function
from jetgaudin.spectral import curve_coefficients, spectral_determinant
from jetgaudin.systems import material_point_rhs, twisted_top_rhs

X9 = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1.0, 0.0, 0.0])


def test_hierarchy():
    for name in _errors.__all__:
        cls = getattr(_errors, name)
        assert issubclass(cls, jg.JetGaudinError) and issubclass(cls, ValueError)
        assert getattr(jg, name) is cls


# every function that takes a state X (shape (..., 3N))
STATE_FUNCS = [
    ("poisson_tensor", lambda X: jg.poisson_tensor(X)),
    ("casimirs", lambda X: jg.casimirs(X)),
    ("integrals", lambda X: jg.integrals(X, 1.0)),
    ("integral_gradients", lambda X: jg.integral_gradients(X, 1.0)),
    ("curve_coefficients", lambda X: curve_coefficients(X, 1.0)),
    ("ell_coefficients", lambda X: ell_coefficients(X, 1.0)),
    ("lax_matrix", lambda X: jg.lax_matrix(1.0 + 0.5j, X, 1.0)),
    ("uvw", lambda X: jg.uvw(1.0 + 0.5j, X, 1.0)),
    ("nu", lambda X: jg.nu(1.0 + 0.5j, X, 1.0)),
    ("nu_squared", lambda X: jg.nu_squared(1.0 + 0.5j, X, 1.0)),
    ("branch_points", lambda X: jg.branch_points(X, 1.0)),
    ("bracket", lambda X: jg.bracket(np.ones(9), np.ones(9), X)),
    ("interpolating_hamiltonian", lambda X: jg.interpolating_hamiltonian(X, 1.0, 5 + 0.1j)),
    ("integrate", lambda X: jg.integrate(jg.physical_hamiltonian(3, 1.0), X, 1.0)),
    ("twisted_top_rhs", lambda X: twisted_top_rhs(X, 1.0)),
    ("material_point", lambda X: jg.material_point(X)),
    ("material_point_rhs", lambda X: material_point_rhs(X, 1.0)),
]


@pytest.mark.parametrize(("name", "f"), STATE_FUNCS, ids=[s[0] for s in STATE_FUNCS])
@pytest.mark.parametrize(
    ("X", "match"),
    [
        (np.ones(8), "not a positive multiple of 3"),
        (np.ones(0), "not a positive multiple of 3"),
        (1.0, "scalar"),
        (np.r_[X9[:8], np.nan], "non-finite"),
        (np.r_[X9[:8], np.inf], "non-finite"),
        (np.r_[X9[:8], -np.inf], "non-finite"),
        (np.array(["a"] * 9), "numeric"),
    ],
    ids=["len8", "empty", "scalar", "nan", "inf", "-inf", "strings"],
)
def test_bad_states(name, f, X, match):
    with pytest.raises(jg.InvalidStateError, match=match):
        f(X)


# complex states are allowed in the algebra / Lax / spectral kernels (the complex one-point maps use them);
# the real flows and the N = 3 system functions reject them
REAL_ONLY = {"interpolating_hamiltonian", "integrate", "twisted_top_rhs", "material_point", "material_point_rhs"}


@pytest.mark.parametrize(("name", "f"), [s for s in STATE_FUNCS if s[0] in REAL_ONLY],
                         ids=[s[0] for s in STATE_FUNCS if s[0] in REAL_ONLY])
def test_complex_state_rejected_where_real_needed(name, f):
    with pytest.raises(jg.InvalidStateError, match="must be real"):
        f(X9 + 1e-3j)


@pytest.mark.parametrize("N", [0, -1, 1.5, "3", None, True])
def test_bad_N(N):
    with pytest.raises(jg.InvalidParameterError, match="jet order N"):
        jg.structure_constants(N)
    with pytest.raises(jg.InvalidParameterError, match="jet order N"):
        jet_coefficients(N)
    with pytest.raises(jg.InvalidParameterError, match="jet order N"):
        jg.physical_hamiltonian(N, 1.0)
    with pytest.raises(jg.InvalidParameterError, match="jet order N"):
        jg.GaudinTop(N, 1.0)


def test_b_zero_where_a_formula_divides_by_b():
    """b = 0: the branch rule of nu (normalised by nu -> |b|) and everything built on it; the tops."""
    with pytest.raises(jg.InvalidParameterError, match="field b must be nonzero"):
        jg.nu(1 + 1j, X9, 0.0)
    with pytest.raises(jg.InvalidParameterError, match="field b must be nonzero"):
        jg.branch_points(X9, 0.0)
    with pytest.raises(jg.InvalidParameterError, match="field b must be nonzero"):
        jg.interpolating_hamiltonian(X9, 0.0, 5 + 0.1j)
    with pytest.raises(jg.InvalidParameterError, match="field b must be nonzero"):
        jg.interpolating_weights(X9, [0.0, 0.0, 0.0], 5 + 0.1j)
    for top in (jg.lagrange_top, jg.generalized_lagrange_top):
        with pytest.raises(jg.InvalidParameterError, match="field strength b must be nonzero"):
            top(0.0)
    # formulas that do not divide by b accept b = 0 (N = 1..: integrals, Lax matrix)
    assert np.all(np.isfinite(jg.integrals(X9, 0.0)))


@pytest.mark.parametrize("b", [np.nan, np.inf, "x", [1.0, 2.0], 1j, [[1.0, 2.0, 3.0]]])
def test_bad_field(b):
    with pytest.raises(jg.InvalidParameterError, match="field b"):
        jg.integrals(X9, b)
    with pytest.raises(jg.InvalidParameterError, match="field b"):
        twisted_top_rhs(X9, b)


@pytest.mark.parametrize("b", [np.nan, "x", 0.0])
def test_bad_field_strength_of_tops(b):
    with pytest.raises(jg.InvalidParameterError, match="field strength b"):
        jg.GaudinTop(3, b)


@pytest.mark.parametrize("lam", [0.0, np.nan, complex(1, np.inf), "a"])
def test_bad_spectral_parameter(lam):
    for f in (lambda: jg.lax_matrix(lam, X9, 1.0), lambda: jg.uvw(lam, X9, 1.0),
              lambda: jg.nu_squared(lam, X9, 1.0), lambda: jg.r_matrix(lam),
              lambda: jet_function(1, lam, N=3)):
        with pytest.raises(jg.InvalidParameterError, match="lambda"):
            f()
    with pytest.raises(jg.JetGaudinError, match="lambda|Re"):
        jg.nu(lam, X9, 1.0)


def test_bad_mu_eta_sheet_constants():
    with pytest.raises(jg.InvalidParameterError, match="mu must be finite"):
        spectral_determinant(1.0, np.nan, X9, 1.0)
    with pytest.raises(jg.InvalidParameterError, match="eta must be finite"):
        jg.interpolating_hamiltonian(X9, 1.0, complex(np.inf, 0))
    with pytest.raises(jg.InvalidParameterError, match="eta must be a complex number"):
        jg.interpolating_hamiltonian(X9, 1.0, "eta")
    with pytest.raises(jg.InvalidParameterError, match="sheet"):
        jg.nu(1 + 1j, X9, 1.0, sheet=0)
    with pytest.raises(jg.InvalidParameterError, match="c_1..c_\\(N-1\\)"):
        jg.integrals(X9, 1.0, c=[1.0])
    with pytest.raises(jg.InvalidParameterError, match="c_k must be finite"):
        jg.integrals(X9, 1.0, c=[1.0, np.nan])


def test_gradient_shape_mismatch():
    with pytest.raises(jg.InvalidStateError, match="grad_f"):
        jg.bracket(np.ones(6), np.ones(9), X9)
    with pytest.raises(jg.InvalidStateError, match="grad_H"):
        jg.hamiltonian_vector_field(np.ones(6), X9)
    with pytest.raises(jg.InvalidStateError, match="weights"):
        jg.IntegralHamiltonian(1.0, np.ones(4)).gradient(X9)


def test_unknown_method_and_bad_times():
    H = jg.physical_hamiltonian(3, 1.0)
    with pytest.raises(jg.InvalidParameterError, match="method must be 'DOP853' or 'heyoka'"):
        jg.integrate(H, X9, 1.0, method="euler")
    with pytest.raises(jg.InvalidParameterError, match="t_eval"):
        jg.integrate(H, X9, 1.0, t_eval=[0.0, 3.0])
    with pytest.raises(jg.InvalidParameterError, match="t_eval"):
        jg.integrate(H, X9, 1.0, t_eval=[1.0, 0.0])
