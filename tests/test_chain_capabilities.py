"""The capabilities of docs/families.md §7 for chains of every family (issue 23): the leaf sampler, the physical
Hamiltonian, Dask, plot and animate.  References: the chain's own integrals for the sampler's leaf (a quadratic form
independent of the sampler), ν² evaluated directly from the Lax vector for the physical Hamiltonian (independent
of its weights), closed forms derived by hand from u, v, w (docstring of jetgaudin.gaudin.physical), the one-body
API for one rational site at 0."""

from __future__ import annotations

import json

import h5py
import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.ensemble import DEFAULT_CASIMIRS, default_chain_casimirs, sample_chain_on_leaf, sample_on_leaf
from jetgaudin.gaudin import GaudinModel
from test_cli_chains import main_quiet, one_line_error

FAMILIES = [("rational", {}), ("trigonometric", {"gamma": 0.7}), ("elliptic", {"modulus": 0.6})]
#: the families with a physical Hamiltonian (a point at infinity; jetgaudin.gaudin.physical)
WITH_INFINITY = FAMILIES[:2]


def _b(fam):
    return 0.0 if fam == "elliptic" else 0.8  # the elliptic family has no field


def _model(fam, kw, b=None, sites=((-1.0, 1), (0.3, 3), (1.2, 2))):
    return GaudinModel(_b(fam) if b is None else b, sites, family=fam, **kw)


def _cli_family(fam, kw):
    """``--family F [--gamma g | --modulus k] --b b`` of the command line."""
    return ["--family", fam] + [a for k, v in kw.items() for a in (f"--{k}", str(v))] + ["--b", str(_b(fam))]


# ------------------------------------------------------------------------------------------------ the sampler
@pytest.mark.parametrize(("fam", "kw"), FAMILIES)
def test_chain_sampler_lands_on_the_requested_leaf(fam, kw, rng):
    m = _model(fam, kw)
    c = rng.uniform(-1, 1, m.M)
    c[np.cumsum(m.orders) - 1] = rng.uniform(0.5, 2, len(m.sites))  # each site's C_N > 0
    X = sample_chain_on_leaf(m, c, 50, seed=4, scale=1.3)
    assert X.shape == (50, m.n_state)
    # the model's Casimirs h_(i,m>N_i) (its quadratic forms, not the sampler's formula), site by site C_1..C_N;
    # 1e-12: round-off of the forms on components of size ~ a few
    h = m.integrals(X)[:, m.casimir_mask()]
    assert np.allclose(h, c, rtol=0, atol=1e-12)
    assert np.std(X, axis=0).min() > 0.1  # states spread, not one point
    assert np.array_equal(X, sample_chain_on_leaf(m, c, 50, seed=4, scale=1.3))  # seeded


def test_chain_sampler_default_leaf_and_one_site_is_the_top_sampler():
    assert default_chain_casimirs((1, 2, 3, 4)) == [1.5, -0.3, 1.5, 0.4, -0.3, 1.5, 0.0, 0.4, -0.3, 1.5]
    m = GaudinModel(1.0, [(0.0, 3)])
    assert np.array_equal(sample_chain_on_leaf(m, None, 7, seed=2), sample_on_leaf(3, DEFAULT_CASIMIRS, 7, seed=2))


def test_chain_sampler_bad_input():
    m = _model("rational", {})
    with pytest.raises(jg.InvalidParameterError, match="M = 6"):
        sample_chain_on_leaf(m, [1.0, 2.0], 3)
    with pytest.raises(jg.InvalidParameterError, match="site 2"):
        sample_chain_on_leaf(m, [1, 0, 0, 0, 1, 1], 3)  # site 2's C_3 = 0
    with pytest.raises(jg.InvalidParameterError, match="size"):
        sample_chain_on_leaf(m, None, 0)


@pytest.mark.parametrize(("fam", "kw"), FAMILIES)
def test_cli_ensemble_sites_samples_the_default_leaf(fam, kw, tmp_path):
    extra = _cli_family(fam, kw)
    code = main_quiet("ensemble", "--sites", "-1:1,0.3:3,1.2:2", "--eta", "0.5+0.05i", "--orbits", "6",
                      "--seed", "5", "--steps", "12", "--out", tmp_path / "e", *extra)
    assert code == 0
    m = _model(fam, kw)
    with h5py.File(tmp_path / "e" / "ensemble.h5") as f:
        X0, states = np.array(f["X0"]), np.array(f["states"])
    assert np.array_equal(X0, sample_chain_on_leaf(m, None, 6, seed=5))
    # every member is its single orbit (the chain map, bit for bit)
    ref = m.two_point_backlund(0.5 + 0.05j).iterate(X0, 12)
    assert np.array_equal(states, ref)


def test_cli_ensemble_sites_casimirs_and_bad_input(tmp_path, capsys):
    code = main_quiet("ensemble", "--sites", "0:1,1:1", "--casimirs", "0.5,2", "--orbits", "3", "--steps", "2",
                      "--out", tmp_path / "e")
    assert code == 0
    with h5py.File(tmp_path / "e" / "ensemble.h5") as f:
        X0 = np.array(f["X0"])
    assert np.allclose(np.sum(X0.reshape(3, 2, 3) ** 2, axis=-1), [0.5, 2.0], atol=1e-13)  # |s_i|^2
    capsys.readouterr()
    for args, words in ((["--casimirs", "1"], ["--casimirs", "M = 2"]), (["--casimirs", "1,-1"], ["--casimirs",
                        "site 2"]), (["--sample", "energy", "--energy", "1"], ["--sites", "leaf"]),
                        (["--sample", "leaf", "--input", "x.csv"], ["at most one"])):
        code = main_quiet("ensemble", "--sites", "0:1,1:1", "--out", tmp_path / "bad", *args)
        assert one_line_error(code, capsys.readouterr().err, *words), args


# ------------------------------------------------------------------------------------ the physical Hamiltonian
def _nu2_coefficient(m, X):
    """The coefficient of ν²/2 the physical H is defined by, from ν² evaluated directly (model.nu_squared: the Lax
    vector, not the h's), by one Richardson extrapolation: rational [λ^-2] at λ = ∞ along the imaginary axis;
    trigonometric −Re[z^1]/(4γ²) at z = e^{2iγλ} → 0."""
    b = m.b
    J = sum(X[3 * o + 2] for o in m.offsets)
    if m.family.name == "rational":
        def f(t):
            return (m.nu_squared(X, 1 / t) - b * b - 2 * b * J * t) / t ** 2
        t = 1e-4j
        return (2 * f(t / 2) - f(t)).real / 2
    g = m.gamma

    def f(T):
        return (m.nu_squared(X, 1j * T) - (b - 1j * g * J) ** 2) / np.exp(-2 * g * T)
    T = 9.0
    return -(2 * f(T + np.log(2) / (2 * g)) - f(T)).real / (8 * g * g)


@pytest.mark.parametrize(("fam", "kw"), WITH_INFINITY)
def test_physical_hamiltonian_is_the_coefficient_at_infinity(fam, kw, rng):
    for sites in (((-1.0, 1), (0.3, 3), (1.2, 2)), ((0.4, 2),), ((-0.5, 1), (0.2, 1), (0.9, 1))):
        m = _model(fam, kw, sites=sites)
        X = rng.normal(size=m.n_state)
        # 1e-7 relative: the extrapolation's truncation (t² ~ 1e-8; z² ~ 1e-11) and round-off (eps/t² ~ 1e-8)
        assert m.physical_hamiltonian()(X) == pytest.approx(_nu2_coefficient(m, X), rel=1e-7, abs=1e-7)


def test_physical_hamiltonian_one_site_at_zero_is_the_tops(rng):
    for N in (2, 3, 4):
        X = rng.normal(size=3 * N)
        H_chain = GaudinModel(1.3, [(0.0, N)]).physical_hamiltonian()(X)
        # the one-body route (hamiltonians.py, eq. (H)); 1e-13: round-off of two quadratic forms
        assert H_chain == pytest.approx(float(jg.physical_hamiltonian(N, 1.3)(X)), rel=1e-13)


def test_physical_hamiltonian_of_magnets_closed_forms(rng):
    lam = np.array([-0.7, 0.2, 1.1])
    s = rng.normal(size=(3, 3))
    b, g = 0.6, 0.8
    S = s.sum(axis=0)
    # rational: ½|S|² + b Σ λ_i s_i^3 (the reduced-BCS form; docstring of jetgaudin.gaudin.physical)
    H = GaudinModel(b, [(p, 1) for p in lam]).physical_hamiltonian()(s.ravel())
    assert H == pytest.approx(0.5 * S @ S + b * lam @ s[:, 2], rel=1e-13)
    # trigonometric, from u, v, w at z -> 0 by hand
    c, sn = np.cos(g * lam), np.sin(g * lam)
    ref = sum(0.5 * ((c @ s[:, a]) ** 2 - (sn @ s[:, a]) ** 2) for a in (0, 1)) + \
        np.sum((b * np.sin(2 * g * lam) / (2 * g) + S[2] / 2 * np.cos(2 * g * lam)) * s[:, 2])
    Ht = GaudinModel(b, [(p, 1) for p in lam], family="trigonometric", gamma=g).physical_hamiltonian()(s.ravel())
    assert Ht == pytest.approx(ref, rel=1e-13)


def test_physical_hamiltonian_rational_limit_and_period(rng):
    sites = ((-1.0, 1), (0.3, 3))
    X = rng.normal(size=12)
    H0 = GaudinModel(0.8, sites).physical_hamiltonian()(X)
    errs = [abs(GaudinModel(0.8, sites, family="trigonometric", gamma=g).physical_hamiltonian()(X) - H0)
            for g in (0.02, 0.01)]
    assert 3.5 < errs[0] / errs[1] < 4.5  # O(γ²), as the model itself (docs/families.md §2)
    w = jg.GaudinModel(0.8, sites, family="trigonometric", gamma=0.7).physical_hamiltonian().weights
    shifted = ((-1.0 + np.pi / 0.7, 1), (0.3, 3))  # a site moved by the period: the same weights
    assert np.allclose(GaudinModel(0.8, shifted, family="trigonometric", gamma=0.7).physical_hamiltonian().weights,
                       w, rtol=0, atol=1e-14)


def test_physical_hamiltonian_refused_without_a_point_at_infinity(tmp_path, capsys):
    m = _model("elliptic", {"modulus": 0.6})
    with pytest.raises(jg.InvalidParameterError, match="elliptic family has no physical Hamiltonian"):
        m.physical_hamiltonian()
    init = ",".join(["0.1"] * m.n_state)
    code = main_quiet("flow", "--sites", "-1:1,0.3:3,1.2:2", "--init", init, "--hamiltonian", "physical",
                      "--out", tmp_path / "f", *_cli_family("elliptic", {"modulus": 0.6}))
    assert one_line_error(code, capsys.readouterr().err, "--hamiltonian", "weights")


@pytest.mark.parametrize(("fam", "kw"), WITH_INFINITY)
def test_cli_flow_sites_physical(fam, kw, tmp_path):
    m = _model(fam, kw)
    X0 = np.round(np.random.default_rng(8).normal(size=m.n_state), 3)
    extra = _cli_family(fam, kw)
    init = ",".join(repr(float(v)) for v in X0)
    code = main_quiet("flow", "--sites", "-1:1,0.3:3,1.2:2", "--init", init,
                      "--hamiltonian", "physical", "--dt", "0.05", "--steps", "10", "--out", tmp_path / "f", *extra)
    assert code == 0
    run = json.loads((tmp_path / "f" / "run.json").read_text())
    assert np.array_equal(run["map"]["weights"], m.physical_hamiltonian().weights)
    X = jg.run.load(tmp_path / "f").X
    # the flow of H: H and every integral conserved (DOP853 at rtol 1e-12 over t = 0.5: 1e-10 absolute), and it
    # moves (a zero Hamiltonian would also conserve everything)
    H = m.physical_hamiltonian()
    assert np.allclose(H(X), H(X0), rtol=0, atol=1e-10)
    assert np.allclose(m.integrals(X), m.integrals(X0), rtol=0, atol=1e-10)
    assert np.linalg.norm(X[-1] - X0) > 1e-2
    # the first step agrees with Ẋ = Π ∇H (finite difference in t: O(dt) = 5e-2 relative)
    v = H.vector_field(X0)
    assert np.linalg.norm((X[1] - X0) / 0.05 - v) < 0.1 * np.linalg.norm(v)


# --------------------------------------------------------------------------------------------- plot, animate
@pytest.fixture(scope="module", params=FAMILIES, ids=[f for f, _ in FAMILIES])
def chain_runs(request, tmp_path_factory):
    fam, kw = request.param
    d = tmp_path_factory.mktemp(fam)
    extra = _cli_family(fam, kw)
    sites = ["--sites", "-1:1,0.3:3,1.2:2", "--eta", "0.5+0.05i"]
    assert main_quiet("ensemble", *sites, "--orbits", "3", "--steps", "30", "--out", d / "e", *extra) == 0
    m = _model(fam, kw)
    X0 = np.round(np.random.default_rng(8).normal(size=m.n_state), 3)
    assert main_quiet("orbit", *sites, "--init", ",".join(repr(float(v)) for v in X0), "--steps", "30", "--no-plots",
                      "--out", d / "o", *extra) == 0
    return d, m


def _no_top_figures(monkeypatch):
    """The top's figures of a chain state (jg.integrals of 3M numbers, the material point) must not be drawn."""
    from jetgaudin.plotting import _animate, _files

    def refuse(*a, **k):
        raise AssertionError("a top's figure drawn for a chain run")

    monkeypatch.setattr(_files.jg, "integrals", refuse)
    monkeypatch.setattr(_files, "figure_points_3d", refuse)
    monkeypatch.setattr(_animate, "point_sets", refuse)


def test_plot_of_chain_runs_draws_the_chain_figures(chain_runs, monkeypatch, tmp_path):
    from jetgaudin import plotting

    d, m = chain_runs
    _no_top_figures(monkeypatch)
    for run, kw in ((d / "o", {}), (d / "e", {"orbit": 2}), (d / "e", {})):
        paths = plotting.save_run_figures(run, tmp_path / run.name, fmt="svg", **kw)
        assert sorted(p.name for p in paths) == ["chain_integrals.svg", "chain_y0.svg"]
    assert "orbit 0 of 3" in (tmp_path / "e" / "chain_y0.svg").read_text()  # the ensemble's orbit is named
    # the figures' data: each site's y_0 and the model's integrals (the model rebuilt from run.json)
    r = plotting.open_run(d / "e", orbit=2)
    assert r.model() == m
    assert main_quiet("plot", d / "o", "--out", tmp_path / "cli") == 0
    assert (tmp_path / "cli" / "chain_y0.png").exists() and not (tmp_path / "cli" / "figure1.png").exists()


def test_animate_of_chain_runs_moves_each_sites_y0(chain_runs, monkeypatch, tmp_path):
    from PIL import Image

    from jetgaudin import plotting

    d, m = chain_runs
    _no_top_figures(monkeypatch)
    path = plotting.animate_run(d / "e", tmp_path / "a.gif", orbit=1, frames=6, dpi=30)
    with Image.open(path) as im:
        assert im.n_frames == 6
    assert main_quiet("animate", d / "o", "--out", tmp_path / "b.gif", "--frames", "4", "--dpi", "30") == 0
    assert (tmp_path / "b.gif").stat().st_size > 0
