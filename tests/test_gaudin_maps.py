"""Property suite for the chain Bäcklund maps (issue 12): every declared MapProperties claim is asserted
generically on seeded random chains of 2-4 sites with orders 1-3 and b of random sign; plus the one-site-at-0
equality with today's maps, translation, pole coalescence, the dressing relation, b = 0 and bad input."""

from __future__ import annotations

import dataclasses
import zlib

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.backlund import MapProperties
from jetgaudin.gaudin import GaudinModel
from test_backlund import jacobian_fd
from test_gaudin import random_chain


@pytest.fixture
def rng(request):
    """Seeded per test and per parameter set (CRC-32 of the test id)."""
    return np.random.default_rng([20261123, zlib.crc32(request.node.nodeid.encode())])


def random_eta(rng, m):
    """Re eta in [-2.5, 2.5] at least 0.15 from every site, |Im eta| in [0.2, 0.8] of random sign."""
    while True:
        a = float(rng.uniform(-2.5, 2.5))
        if np.min(np.abs(m.positions - a)) > 0.15:
            return complex(a, rng.choice([-1, 1]) * rng.uniform(0.2, 0.8))


def integral_scale(m, X):
    """Natural size of each h_(i,m): sum of |q||y_c||y_d| + 2|b||l||y_c| over its terms (its rounding error is eps
    times this), shape (..., 2M)."""
    q, lin = m._forms
    n = np.linalg.norm(np.abs(X).reshape(X.shape[:-1] + (m.M, 3)), axis=-1)
    return (np.einsum("Icd,...c,...d->...I", np.abs(q), n, n) + 2 * abs(m.b) * np.einsum("Ic,...c->...I", lin, n)
            + 1e-300)


FACTORIES = {
    "two-point": lambda m, eta: m.two_point_backlund(eta),
    "two-point opposite": lambda m, eta: m.two_point_backlund(eta, "opposite"),
    "one-point": lambda m, eta: m.one_point_backlund(eta),
    "one-point opposite": lambda m, eta: m.one_point_backlund(eta, "opposite"),
    "one-point inverse": lambda m, eta: m.one_point_backlund(eta, inverse_map=True),
}


def _tol_scale(*Xs):
    return 1 + max(np.abs(X).max() for X in Xs)


def check_preserves_integrals(B, X, rng, declared):
    if declared:  # <= 1e-12 relative to each integral's natural scale (one step of round-off)
        Y = B(X)
        rel = np.abs(B.integrals(Y) - B.integrals(X)) / np.maximum(integral_scale(B.model, X),
                                                                    integral_scale(B.model, Y))
        assert rel.max() <= 1e-12, rel.max()


def check_poisson(B, X, rng, declared):
    if declared:  # J Pi(X) J^T = Pi(B(X)); J by 6th-order differences (h = 1e-3, accurate to ~1e-12 relative,
        # test_backlund.jacobian_fd); 1e-10 relative to |J|^2 |Pi| leaves a factor ~30 over the measured 3e-12
        m = B.model
        J = jacobian_fd(B, X)
        d = J @ m.poisson_tensor(X) @ J.T - m.poisson_tensor(B(X))
        assert np.abs(d).max() <= 1e-10 * np.abs(J).max() ** 2 * max(1.0, np.abs(m.poisson_tensor(X)).max())


def check_real(B, X, rng, declared):
    Y = B(X)
    if declared:  # real output; the dropped imaginary part is round-off
        assert np.isrealobj(Y) and B.step(X)[2].max() <= 1e-13
    else:
        assert np.abs(np.imag(Y)).max() > 1e-6


def check_symmetric(B, X, rng, declared):
    if declared:  # inverse() undoes the map (two steps of round-off times the conditioning: 1e-9 relative)
        Y = B(X)
        assert np.abs(B.inverse()(Y) - X).max() <= 1e-9 * _tol_scale(X, Y)
        if B.properties.real:  # and the conjugate parameter is the inverse too
            back = type(B)(B.model, np.conj(B.eta), B.branch)(Y)
            assert np.abs(back - X).max() <= 1e-9 * _tol_scale(X, Y)


def nu_hamiltonian(m, X, a):
    """nu(a) as a Hamiltonian: sum_(i,m) (a - lam_i)^-m / (2 nu(a)) h_(i,m) (the weights are constant on its flow)."""
    nu_a = float(m.nu(X, a).real)
    w = np.array([(a - p) ** (-k) for p, N in m.sites for k in range(1, 2 * N + 1)]) / (2 * nu_a)
    return m.hamiltonian(w)


def measured_orders(m, X, sheet):
    """log2 of the error ratios of the map, Im eta = h -> 0, against the flow of nu(a) for time -2h per step (+2h on
    the opposite branch), over t = 0.4, h = 0.02, 0.01, 0.005; a at least 0.25 from the branch points and sites."""
    r = m.branch_points(X)
    cands = [a for a in np.linspace(-2.9, 2.9, 59) if np.min(np.abs(m.positions - a)) > 0.25]
    a = max(cands, key=lambda a: np.min(np.abs(r - a)))
    assert np.min(np.abs(r - a)) > 0.2
    H = nu_hamiltonian(m, X, a)
    errs = []
    for h in [0.02, 0.01, 0.005]:
        n = int(round(0.4 / (2 * h)))
        B = m.two_point_backlund(a + 1j * h, "default" if sheet == 1 else "opposite")
        exact = jg.integrate(H, X, -2 * sheet * h * n, rtol=1e-13, atol=1e-14).X[-1]
        errs.append(np.abs(B.iterate(X, n)[-1] - exact).max())
    return np.log2(np.array(errs[:-1]) / np.array(errs[1:]))


def check_order(B, X, rng, declared):
    if declared is not None:  # measured global order matches within 0.15
        assert np.all(np.abs(measured_orders(B.model, X * 0.7, B.sheet) - declared) < 0.15)


def check_interpolates_flow(B, X, rng, declared):
    if declared:  # the time +-1 flow of G_eta: DOP853 at 1e-13 over t = 1 (~1e-12), quadrature of omega (~1e-13)
        H = B.model.interpolating_flow_hamiltonian(X, B.eta)
        flow = jg.integrate(H, X, float(B.sheet), rtol=1e-13, atol=1e-13).X[-1]
        assert np.abs(B(X) - flow).max() <= 1e-10 * _tol_scale(X)


CHECKS = {
    "preserves_integrals": check_preserves_integrals,
    "poisson": check_poisson,
    "real": check_real,
    "symmetric": check_symmetric,
    "order": check_order,
    "interpolates_flow": check_interpolates_flow,
}


def test_every_property_has_a_check():
    assert set(CHECKS) == {f.name for f in dataclasses.fields(MapProperties)}


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("kind", list(FACTORIES))
@pytest.mark.parametrize("prop", list(CHECKS))
def test_declared_properties_hold(rng, seed, kind, prop):
    m = random_chain(rng)
    B = FACTORIES[kind](m, random_eta(rng, m))
    X = rng.normal(size=m.n_state)
    CHECKS[prop](B, X, rng, getattr(B.properties, prop))


# ---- independent route: the dressing relation ----------------------------------------------------


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("kind", list(FACTORIES))
def test_dressing_relation(rng, seed, kind):
    """K(lam) L(X) = L(X') K(lam) at random complex lam, with K the dressing matrix at X (eq. (mm), (ansatz), and for
    the inverse one-point map adj M, since L(X') = M^-1 L(X) M) and X' the image.  This checks the site-wise
    principal-part construction against the defining relation.  Tolerance 1e-10 relative to |K| |L|: round-off of a
    few products of O(1-10) numbers."""
    m = random_chain(rng)
    B = FACTORIES[kind](m, random_eta(rng, m))
    X = rng.normal(size=(2, m.n_state))
    Y = B(X)
    for lam in rng.normal(size=3) + 1j * rng.normal(size=3):
        K = B.dressing_matrix(X, lam)
        L, Lt = m.lax_matrix(X, lam), m.lax_matrix(Y, lam)
        scale = np.abs(K).max() * max(np.abs(L).max(), np.abs(Lt).max())
        assert np.abs(K @ L - Lt @ K).max() <= 1e-10 * scale


# ---- the one-site model at 0 is today's model ----------------------------------------------------


@pytest.mark.parametrize("N", [1, 2, 3, 4])
def test_one_site_at_zero_equals_todays_maps(rng, N):
    """Same orbits (200 steps, batch of 3) as jg.TwoPointBacklund (NumPy route) and its inverse, the same one-point
    maps and the same G_eta weights.  The two routes round differently (principal parts vs Laurent division):
    1e-11 relative over 200 steps (measured <= 7e-13 after 50)."""
    b = float(rng.choice([-1.0, 0.6]))
    eta = complex(rng.uniform(0.4, 2.5) * rng.choice([-1, 1]), rng.uniform(0.1, 0.6))
    m = GaudinModel(b, [(0.0, N)])
    X = rng.normal(size=(3, 3 * N))
    for branch in ("default", "opposite"):
        a = m.two_point_backlund(eta, branch).iterate(X, 200)
        o = jg.TwoPointBacklund(b, eta, branch).iterate(X, 200, kernel="numpy")
        assert np.abs(a - o).max() <= 1e-11 * (1 + np.abs(o).max())
    for branch in ("default", "opposite"):
        for inv in (False, True):
            Y1 = m.one_point_backlund(eta, branch, inv)(X)
            Y0 = jg.OnePointBacklund(b, eta, branch, inv)(X)
            assert np.abs(Y1 - Y0).max() <= 1e-11 * (1 + np.abs(Y0).max())
    w1 = m.interpolating_weights(X[0], eta)
    w0 = jg.interpolating_weights(X[0], b, eta)
    assert np.abs(w1 - w0).max() <= 1e-12 * (1 + np.abs(w0).max())  # same quadrature of the same integrand


def test_batch_member_equals_single_run_bit_for_bit(rng):
    m = random_chain(rng)
    B = m.two_point_backlund(random_eta(rng, m))
    X = rng.normal(size=(4, m.n_state))
    batch = B.iterate(X, 30)
    for k in range(4):
        assert np.array_equal(batch[:, k], B.iterate(X[k], 30))
    # a run split in two, the second half continuing the carry, equals the unsplit run bit for bit
    first, carry = B.iterate(X, 12, return_carry=True)
    second = B.iterate(first[-1], 18, carry=carry)
    assert np.array_equal(np.concatenate([first, second[1:]]), batch)
    assert B.iterate(X, 30, save_every=7).shape == (5, 4, m.n_state)
    assert np.array_equal(B.iterate(X, 30, save_every=7)[-1], batch[28])


# ---- translation and pole coalescence --------------------------------------------------------------


@pytest.mark.parametrize("N", [1, 2, 3])
def test_translation(rng, N):
    """One site at lam = c with parameter eta + c equals the site at 0 with eta (and a whole chain translated with
    its eta): the same map, to round-off (1e-11 relative over 20 steps)."""
    b = float(rng.choice([-1.0, 0.6]))
    c = float(rng.uniform(-3, 3))
    eta = complex(rng.uniform(0.4, 2), rng.uniform(0.1, 0.6))
    X = rng.normal(size=(2, 3 * N))
    ref = jg.TwoPointBacklund(b, eta).iterate(X, 20, kernel="numpy")
    got = GaudinModel(b, [(c, N)]).two_point_backlund(eta + c).iterate(X, 20)
    assert np.abs(got - ref).max() <= 1e-11 * (1 + np.abs(ref).max())
    m = random_chain(rng)
    e = random_eta(rng, m)
    Y = rng.normal(size=m.n_state)
    shifted = GaudinModel(m.b, [(p + c, k) for p, k in m.sites])
    d = shifted.two_point_backlund(e + c).iterate(Y, 20) - m.two_point_backlund(e).iterate(Y, 20)
    assert np.abs(d).max() <= 1e-11 * (1 + np.abs(Y).max())
    assert np.allclose(shifted.integrals(Y)[shifted.casimir_mask()], m.integrals(Y)[m.casimir_mask()], rtol=1e-14)


@pytest.mark.parametrize("N", [2, 3])
def test_pole_coalescence(rng, N):
    """The order-N jet at 0 is the limit of N order-1 sites at lam_i = eps t_i with spins S_i solving
    sum_i lam_i^k S_i = y_k (k < N): the moment map y_k = sum_i lam_i^k S_i is Poisson up to the brackets
    {y_k, y_l} = y_(k+l), k + l >= N, which are O(eps^(k+l-N+1)) instead of 0, and L_chain - L_jet =
    sum_i S_i lam_i^N / lam^(N+1) + ... = O(eps) (S_i ~ eps^-(N-1)).  So moments of the chain map's image converge to
    the jet map's image at rate eps: measured error ratios per halving of eps in [1.9, 2.1] (1.97-1.997 here), and the
    error at eps = 0.005 below 0.01 |y|."""
    b, eta = 0.9, 0.7 + 0.4j
    y = rng.normal(size=(N, 3))
    ref = jg.TwoPointBacklund(b, eta)(y.reshape(-1)).reshape(N, 3)
    t = np.array([-1.0, 0.35, 1.2])[:N]
    errs = []
    for eps in [0.02, 0.01, 0.005]:
        lam = eps * t
        V = lam[None, :] ** np.arange(N)[:, None]  # V[k, i] = lam_i^k
        S = np.linalg.solve(V, y)
        Sn = jg.gaudin_magnet(b, lam).two_point_backlund(eta)(S.reshape(-1)).reshape(N, 3)
        errs.append(np.abs(V @ Sn - ref).max())
    ratios = np.array(errs[:-1]) / np.array(errs[1:])
    assert np.all((ratios > 1.9) & (ratios < 2.1)), ratios
    assert errs[-1] < 0.01 * np.abs(y).max()


# ---- b = 0 and bad input -------------------------------------------------------------------------


def test_zero_field(rng):
    """b = 0 (the magnet without field): the real two-point map works (integrals kept, inverse, the time-1 flow of
    G_eta; nu ~ |S|/lam with S the total spin); the one-point map and total spin S = 0 are refused."""
    m = GaudinModel(0.0, [(-1.0, 1), (0.3, 2), (1.4, 1)])
    X = rng.normal(size=m.n_state)
    eta = 0.8 + 0.35j
    B = m.two_point_backlund(eta)
    Y = B(X)
    assert (np.abs(m.integrals(Y) - m.integrals(X)) / integral_scale(m, X)).max() <= 1e-12
    assert np.abs(B.inverse()(Y) - X).max() <= 1e-11 * _tol_scale(X)
    check_interpolates_flow(B, X, rng, True)
    S = X.reshape(-1, 3)[list(m.offsets)].sum(axis=0)
    big = 1e4 + 1j
    assert abs(m.nu(X, big) * big - np.linalg.norm(S)) <= 1e-3 * np.linalg.norm(S)  # O(1/lam) correction
    with pytest.raises(jg.InvalidParameterError, match="nonzero field b"):
        m.one_point_backlund(eta)
    Z = X.copy().reshape(-1, 3)
    Z[m.offsets[0]] -= S  # total spin zero
    with pytest.raises(jg.BranchPointError, match="total spin"):
        B(Z.reshape(-1))


def test_bad_input(rng):
    m = GaudinModel(1.0, [(-1.0, 2), (0.5, 1)])
    with pytest.raises(jg.InvalidParameterError, match="Re\\(eta\\) = 0.5 is a site"):
        m.two_point_backlund(0.5 + 0.2j)
    with pytest.raises(jg.InvalidParameterError, match="Re\\(eta\\) = -1.0 is a site"):
        m.one_point_backlund(-1.0 + 0.2j)
    with pytest.raises(jg.InvalidParameterError, match="Im\\(eta\\) = 0"):
        m.two_point_backlund(0.2)
    with pytest.raises(jg.InvalidParameterError, match="branch"):
        m.two_point_backlund(0.2 + 1j, "other")
    with pytest.raises(jg.InvalidParameterError, match="eta must be finite"):
        m.two_point_backlund(complex(np.nan, 1))
    B = m.two_point_backlund(0.2 + 0.4j)
    with pytest.raises(jg.InvalidStateError, match="3M = 9"):
        B(np.ones(6))
    with pytest.raises(jg.InvalidStateError, match="real"):
        B(np.ones(9) * 1j)
    with pytest.raises(jg.InvalidStateError, match="non-finite"):
        B(np.full(9, np.nan))
    with pytest.raises(jg.InvalidParameterError, match="steps"):
        B.iterate(np.ones(9), -1)
    with pytest.raises(jg.InvalidParameterError, match="GaudinModel"):
        jg.ChainTwoPointBacklund("model", 0.2 + 0.4j)
    # a branch point exactly at eta
    X = rng.normal(size=9)
    r = m.branch_points(X)
    r = r[np.argmax(np.abs(r.imag))]
    with pytest.raises(jg.BranchPointError, match="branch point"):
        m.two_point_backlund(r)(X)


def test_describe_and_surface(rng):
    m = GaudinModel(0.8, [(-1.0, 2), (0.5, 3), (2.0, 1)])
    B = m.two_point_backlund(5 + 0.1j)
    # issue 23: one default backend rule for every map ("auto")
    assert B.describe() == {"kind": "chain_two_point", "b": 0.8, "eta": [5.0, 0.1], "branch": "default",
                            "sites": [[-1.0, 2], [0.5, 3], [2.0, 1]], "backend": "auto"}
    assert B.n_state == 18 and B.inverse().branch == "opposite" and B.inverse().inverse() == B
    X = rng.normal(size=(2, 18))
    nu1 = B.start(X)
    assert nu1.shape == (2,) and np.allclose(nu1, m.nu(X, 5 + 0.1j))
    Y, carry, imag = B.step(X, nu1)
    assert np.array_equal(Y, B(X)) and np.array_equal(carry, nu1) and imag.shape == (2,)
    assert B.integrals(X).shape == (2, 12)
    P = m.one_point_backlund(5 + 0.1j, inverse_map=True)
    assert P.describe()["kind"] == "chain_one_point" and P.describe()["inverse_map"] is True


def test_chain_maps_are_maps_and_rebuild_from_their_description(rng):
    """Map contract (docs/architecture.md): both chain maps subclass jetgaudin.maps.Map, their description is JSON and
    map_from_description rebuilds an equal map (same backend) that gives the same bits."""
    import json

    from jetgaudin.maps import Map, map_from_description

    m = GaudinModel(0.8, [(-1.0, 2), (0.5, 3), (2.0, 1)])
    X = rng.normal(size=18)
    maps = [m.two_point_backlund(5 + 0.1j), m.two_point_backlund(5 + 0.1j, "opposite", "compiled"),
            m.one_point_backlund(0.3 + 0.7j), m.one_point_backlund(0.3 + 0.7j, "opposite", inverse_map=True)]
    for B in maps:
        assert isinstance(B, Map)
        d = json.loads(json.dumps(B.describe()))
        R = map_from_description(d)
        assert type(R) is type(B) and R == B and R.describe() == B.describe() and R.backend is B.backend
        assert np.array_equal(R.iterate(X, 3), B.iterate(X, 3))
    assert maps[1].branch is jg.Branch.OPPOSITE and maps[1].inverse().branch is jg.Branch.DEFAULT


def test_advance_continues_bit_for_bit_and_checks_counts(rng):
    """advance(X, carry, k) pieces chained by their carry equal one call (NumPy route); counts use the run layer's
    rule (check_count)."""
    m = GaudinModel(-0.7, [(-1.0, 2), (0.5, 1)])
    B = m.two_point_backlund(0.2 + 0.3j, kernel="numpy")  # pinned: AUTO may take another route for each piece's size
    X = rng.normal(size=(2, 9))
    full = B.advance(X, None, 7, 2)
    a = B.advance(X, None, 4, 2)
    b = B.advance(a.X, a.carry, 3, 1)
    assert np.array_equal(np.concatenate([a.rows, b.rows[1:2]]), full.rows)
    assert np.array_equal(b.X, full.X) and np.array_equal(b.carry, full.carry)
    with pytest.raises(jg.InvalidParameterError, match="save_every must be an integer >= 1"):
        B.advance(X, None, 3, 0)
    with pytest.raises(jg.InvalidParameterError, match="does not fit in 64 bits"):
        B.advance(X, None, 2**64, 1)
