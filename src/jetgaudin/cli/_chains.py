"""``--sites``: the chain versions of ``orbit``, ``ensemble``, ``info``, ``flow`` (issue 12; private).

Text to values only: the rules (distinct real sites, orders ``N_i >= 1``, ``Re η`` off the sites, ``Im η != 0``, the
state length ``3M``) are the library's (:func:`jetgaudin.gaudin.parse_sites`, :class:`jetgaudin.gaudin.GaudinModel`,
:class:`jetgaudin.ChainTwoPointBacklund`); this module names the option in the one-line error.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ._common import MAX_N, CliInputError, blame, complex_text, one_line, parse_b, to_float

SITES_HELP = ('chain sites "λ1:N1,λ2:N2,..." (distinct real positions, integer orders N_i >= 1), e.g. '
              '"-1:2,0.5:3,2:1"; --init then takes 3M numbers (--algebra suN: (N²−1)M), M = N1 + N2 + ... '
              '[default: one site 0:N, '
              "N = len(--init)/3]")


FAMILY_HELP = ("the Gaudin family of --sites: 'rational' (XXX, the paper's), 'trigonometric' (XXZ, anisotropy "
               "--gamma) or 'elliptic' (XYZ, modulus --modulus, b = 0) [default: rational]")
GAMMA_HELP = "anisotropy γ > 0 of --family trigonometric (sites distinct modulo π/γ) [default: 1]"
MODULUS_HELP = ("modulus k in [0, 1) of --family elliptic (sites distinct modulo 2K(k), |Im η| < 0.9 K'(k)); "
                "required by it")
#: ``--init`` of orbit, flow and info: the count for a top and for a chain of either algebra
INIT_METAVAR = "X1,X2,..."
INIT_HELP = ("the state, comma-separated numbers y_0, y_1, ...: 3N for a top of jet order N (N inferred); with --sites "
             "3M (M = N_1 + N_2 + ..., site by site); with --algebra su3 8M (suN: N²−1 per site and order)")
ALGEBRA_HELP = ("the Lie algebra of --sites: su2 (the default) or suN, e.g. su3 (rational family; --init then takes "
                "(N²−1)M numbers, --b is the field along λ_3; docs/sun.md)")


def algebra_kw(sites: str | None, algebra: str | None, fam: dict) -> dict:
    """``{"algebra": "su(n)"}`` for :func:`chain_model` from ``--algebra`` (nothing for su(2), today's models); one
    line naming the option otherwise."""
    if algebra is None:
        return {}
    import jetgaudin as jg
    from jetgaudin.lie import parse_algebra

    if sites is None:
        raise CliInputError("--algebra: su(n) models are chains; give --sites (e.g. --sites 0:1,1:1)")
    try:
        alg = parse_algebra(algebra)
    except jg.JetGaudinError as exc:
        raise CliInputError("--algebra: " + one_line(exc)) from None
    if alg.n == 2:
        return {}
    if fam.get("family", "rational") != "rational":
        raise CliInputError(f"--algebra: {alg.name} models are rational only; drop --family/--gamma/--modulus")
    return {"algebra": alg.name}


def family_kw(sites: str | None, family: str | None, gamma: str | None, record: dict | None = None, *,
              modulus: str | None = None, algebra: str | None = None) -> dict:
    """``{"family": …, "gamma": …, "modulus": …}`` for :func:`chain_model` from ``--family`` / ``--gamma`` /
    ``--modulus`` (or, when all are absent, from a recorded run's map description, ``record``), and ``"algebra"``
    from ``--algebra`` (:func:`algebra_kw`); one line naming the option otherwise."""
    fam = _family_kw(sites, family, gamma, record, modulus=modulus)
    return {**fam, **algebra_kw(sites, algebra, fam)}


def _family_kw(sites: str | None, family: str | None, gamma: str | None, record: dict | None = None, *,
               modulus: str | None = None) -> dict:
    m = (record or {}).get("map", {})
    if family is None and gamma is None and modulus is None:
        return {k: m[k] for k in ("family", "gamma", "modulus") if k in m}
    if family is None and str(m.get("kind", "")).startswith("chain_"):  # --init-from a chain: its family is kept
        implied = "elliptic" if modulus is not None else "trigonometric"
        if m.get("family", "rational") != implied:
            opt = "--gamma" if gamma is not None else "--modulus"
            raise CliInputError(f"{opt}: the run of --init-from is a {m.get('family', 'rational')} chain; {opt} would "
                                f"make it {implied}: drop {opt}, or give --family {implied} to change the family")
    if sites is None:
        opt = "--family" if family is not None else "--gamma" if gamma is not None else "--modulus"
        raise CliInputError(f"{opt}: the Gaudin families are chains; give --sites (e.g. --sites 0:1,1:1)")
    from jetgaudin.families import family_names

    fam = family or ("elliptic" if modulus is not None else "trigonometric")
    if fam not in family_names():
        raise CliInputError(f"--family: unknown family {fam!r}; give one of {', '.join(family_names())}")
    if modulus is not None or fam == "elliptic":
        return _elliptic_kw(fam, gamma, modulus)
    if gamma is None:
        return {"family": fam}
    if fam != "trigonometric":
        raise CliInputError(f"--gamma: the {fam} family has no anisotropy; give --family trigonometric or drop --gamma")
    try:
        g = to_float(gamma, "--gamma")
    except (TypeError, ValueError):
        raise CliInputError(f"--gamma: the anisotropy must be a real number > 0, got {gamma!r}") from None
    return {"family": fam, "gamma": g}


def _elliptic_kw(fam: str, gamma: str | None, modulus: str | None) -> dict:
    if fam != "elliptic":
        raise CliInputError(f"--modulus: the {fam} family has no elliptic modulus; give --family elliptic or drop "
                            "--modulus")
    if gamma is not None:
        raise CliInputError("--gamma: the elliptic family has no anisotropy (its parameter is --modulus)")
    if modulus is None:
        raise CliInputError("--modulus: --family elliptic needs its modulus k in [0, 1), e.g. --modulus 0.5")
    try:
        k = to_float(modulus, "--modulus")
    except (TypeError, ValueError):
        raise CliInputError(f"--modulus: the modulus must be a real number in [0, 1), got {modulus!r}") from None
    return {"family": fam, "modulus": k}


def parse_chain_b(text: Any, option: str = "--b") -> float:
    """The field of a chain: real and finite; ``b = 0`` (the magnet without field) is allowed for the two-point map."""
    try:
        if to_float(text, option) == 0.0:
            return 0.0
    except (TypeError, ValueError):
        pass
    return parse_b(text, option)


def chain_model(sites: str, b: float, family: str = "rational", gamma: float | None = None,
                modulus: float | None = None, algebra: str = "su(2)"):
    """The :class:`~jetgaudin.gaudin.GaudinModel` of ``--sites`` in the field ``b e_3`` (``--family``, ``--gamma``,
    ``--modulus``: :func:`family_kw`)."""
    import jetgaudin as jg
    from jetgaudin.gaudin import GaudinModel, parse_sites

    if not str(sites).isascii() or "_" in str(sites):  # float() reads Unicode digits (١:3 was site 1.0) and 1_0
        raise CliInputError(f"--sites: {sites!r}: write the sites with ASCII digits, e.g. --sites -1:3,0.5:3")
    try:
        parsed = tuple(parse_sites(sites))
        M = sum(int(N) for _, N in parsed)
        if M > MAX_N:  # the chain's structure arrays grow as M^3 (2000 sites: 128 GiB asked for)
            raise CliInputError(f"--sites: the orders sum to M = {M}; the command line accepts M <= {MAX_N} (the "
                                "chain's arrays grow as M^3); use the library for larger chains")
        return GaudinModel(b, parsed, family, gamma, modulus, algebra)
    except jg.JetGaudinError as exc:
        msg = one_line(exc)
        if "gamma" in msg and "sites" not in msg:
            raise CliInputError("--gamma: " + msg) from None
        if "modulus" in msg:
            raise CliInputError("--modulus: " + msg) from None
        if "has no field" in msg:
            raise CliInputError("--b: " + msg) from None
        raise CliInputError("--sites: " + (msg[len("sites: "):] if msg.startswith("sites: ") else msg)) from None


def check_chain_state(model, X: Any, option: str = "--init") -> np.ndarray:
    """``X`` as a state of ``model`` (3M numbers); one line naming ``--sites`` otherwise."""
    X = np.asarray(X, dtype=float)
    if X.shape[-1] != model.n_state:
        sites = ",".join(f"{p:g}:{N}" for p, N in model.sites)
        d = model.n_state // model.M
        raise CliInputError(f"--sites: the sites {sites} need {'3M' if d == 3 else f'{d}M'} = {model.n_state} numbers "
                            f"in {option} (M = sum of the orders = {model.M}: one {d}-vector per site and order), got "
                            f"{X.shape[-1]}")
    return X


def chain_map(model, eta: complex, branch: str, kernel: str | None):
    """The real two-point map of the chain (``kernel``: the ``--kernel`` value, ``None`` for auto); an su(n) chain's
    ``B^(r)_η`` with ``--branch r`` (``default`` = 0)."""
    import jetgaudin as jg

    try:
        if isinstance(model, jg.SunGaudinModel):
            from jetgaudin.gaudin.sun_spectral import branch_index

            r = branch_index(model, int(branch) if str(branch).isdigit() else branch)
            return jg.SunTwoPointBacklund(model, eta, r, jg.Backend.parse(kernel or "auto"))
        return jg.ChainTwoPointBacklund(model, eta, jg.Branch.parse(su2_branch(branch)),
                                        jg.Backend.parse(kernel or "auto"))
    except jg.InvalidParameterError as exc:
        option = "--sites" if "is a site" in str(exc) else "--branch" if "branch must" in str(exc) else "--eta"
        raise CliInputError(f"{option}: {one_line(exc)}") from None


def su2_branch(branch: str) -> str:
    """``--branch`` of an su(2) model: ``0``, ``1`` are the default and opposite roots; one line for another r."""
    if str(branch).isdigit():
        if int(branch) > 1:
            raise CliInputError(f"--branch: an su(2) model has the branches 0 (default) and 1 (opposite), got "
                                f"{branch}; r = 2.. needs --algebra suN")
        return ("default", "opposite")[int(branch)]
    return str(branch)


def chain_flow_map(H: Any, dt: float, method: str, rtol: float):
    """The flow map of the chain Hamiltonian ``H`` over ``dt`` (tolerance ``rtol`` relative and absolute)."""
    from jetgaudin.flows import Method
    from jetgaudin.gaudin import ChainFlowMap

    return ChainFlowMap(H, dt, Method.parse(method), rtol, rtol)


def sites_of(record: dict) -> str | None:
    """The ``--sites`` text of a recorded chain run (its map description), else ``None``."""
    m = record.get("map", {})
    if not isinstance(m, dict) or not str(m.get("kind", "")).startswith("chain_"):
        return None
    try:
        return ",".join(f"{float(p)!r}:{int(N)}" for p, N in m["sites"])
    except (KeyError, TypeError, ValueError):
        raise CliInputError("--init-from: the run's map description has no usable sites; give --sites") from None


def multi_site(model) -> bool:
    """Whether the chain figures replace the paper's (more than one site, one site not of order 3, or a family other
    than the rational one; the same rule as :func:`jetgaudin.plotting.open_run`)."""
    return len(model.sites) > 1 or model.sites[0][1] != 3 or model.family.name != "rational" or \
        model.n_state != 3 * model.M  # su(n)


def info(sites: str, b: Any, eta: str, init: str, as_json: bool, fam: dict | None = None) -> None:
    """``jetgaudin info --sites``: the chain's integrals ``h_{i,m}`` (Casimir / Hamiltonian), ``ν(η)`` on both roots,
    ``G_η`` and the branch points of the state."""
    import json
    import math

    import typer

    import jetgaudin as jg

    from ._common import console, parse_eta, parse_init

    bb = parse_chain_b(b)
    eta_c = parse_eta(eta, pole_at_zero=False)
    model = chain_model(sites, bb, **(fam or {}))
    X = check_chain_state(model, parse_init(init, multiple=1 if isinstance(model, jg.SunGaudinModel) else 3))
    if isinstance(model, jg.SunGaudinModel):
        return _sun_info(model, X, eta_c, as_json)
    with blame("--init"):
        h = model.integrals(X)
    kinds = ["Casimir" if c else "Hamiltonian" for c in model.casimir_mask()]
    d: dict[str, Any] = {**model.describe(), "M": model.M, "eta": [eta_c.real, eta_c.imag],
                         "state": dict(zip(model.labels(), X.tolist(), strict=True)),
                         "integrals": [{"name": n, "kind": k, "value": float(v)}
                                       for n, k, v in zip(model.integral_labels(), kinds, h, strict=True)]}
    for key, fn in (("nu_default", lambda: model.nu(X, eta_c)), ("nu_opposite", lambda: model.nu(X, eta_c, sheet=-1)),
                    ("G_eta", lambda: model.interpolating_hamiltonian(X, eta_c))):
        try:
            z = complex(np.asarray(fn()))
            if not (math.isfinite(z.real) and math.isfinite(z.imag)):
                raise jg.InvalidParameterError("not finite (the state or eta is too large)")
            d[key] = z.real if key == "G_eta" else [z.real, z.imag]
        except jg.JetGaudinError as exc:
            d[key], d[key + "_note"] = None, one_line(exc)
    try:
        d["branch_points"] = [[z.real, z.imag] for z in np.ravel(model.branch_points(X)) if np.isfinite(z)]
    except (jg.JetGaudinError, np.linalg.LinAlgError) as exc:
        d["branch_points"], d["branch_points_note"] = [], one_line(exc)
    if as_json:
        typer.echo(json.dumps(d, indent=1))
        return

    con = console()
    sites_text = ", ".join(f"{p:g}:{N}" for p, N in model.sites)
    expansion = "b² + Σ h_(i,m) (λ − λ_i)^(−m)" if model.family.name == "rational" else (
        f"c0 + Σ h_(i,m) ψ_m(λ − λ_i), elliptic, k = {model.modulus:g}" if model.family.name == "elliptic" else
        f"b² − γ²J² + Σ h_(i,m) ψ_m(λ − λ_i), {model.family.name}, γ = {model.gamma:g}")
    t = _integrals_table(f"chain (λ:N) = {sites_text} (M = {model.M}), b = {bb:g}: integrals of ν² = {expansion}",
                         d["integrals"])
    eta_s = f"{eta_c.real:g}{eta_c.imag:+g}i"
    for key, label in (("nu_default", f"ν({eta_s}), default root"), ("nu_opposite", f"ν({eta_s}), opposite root")):
        t.add_row(label, "", f"{d[key][0]:.17g} {d[key][1]:+.17g} i" if d[key] is not None else
                  f"undefined: {d[key + '_note']}")
    t.add_row(f"G_η, η = {eta_s}", "", f"{d['G_eta']:.17g}" if d["G_eta"] is not None else
              f"undefined: {d['G_eta_note']}")
    con.print(t)
    con.print("branch points (zeros of ν²): " + ", ".join(complex_text(complex(x, y)) for x, y in d["branch_points"]))


def _integrals_table(title: str, integrals: list[dict]):
    """The rich table of ``info``'s integrals (name, kind, value to 17 digits), to which callers add rows."""
    from rich.table import Table

    t = Table(title=title, title_justify="left")
    for col in ("integral", "kind", "value"):
        t.add_column(col, justify="right" if col == "value" else "left")
    for row in integrals:
        t.add_row(row["name"], row["kind"], f"{row['value']:.17g}")
    return t


def _sun_info(model, X, eta_c: complex, as_json: bool) -> None:
    """``info --sites --algebra suN``: the integrals ``h^(k)_(j,m)`` (Casimir / Hamiltonian), the eigenvalue branches
    ``μ_r(η)`` and ``G^(r)_η``."""
    import json
    import math

    import typer

    import jetgaudin as jg

    from ._common import console

    with blame("--init"):
        h = model.integrals(X)
    kinds = ["Casimir" if c else "Hamiltonian" for c in model.casimir_mask()]
    d: dict[str, Any] = {**model.describe(), "M": model.M, "eta": [eta_c.real, eta_c.imag],
                         "state": dict(zip(model.labels(), X.tolist(), strict=True)),
                         "integrals": [{"name": n, "kind": k, "value": float(v)}
                                       for n, k, v in zip(model.integral_labels(), kinds, h, strict=True)],
                         "branches": []}
    for r in range(model.n):
        row: dict[str, Any] = {"r": r}
        try:
            mu = complex(np.asarray(model.eigenvalue(X, eta_c, r)))
            G = float(np.asarray(model.interpolating_hamiltonian(X, eta_c, r)))
            if not (math.isfinite(abs(mu)) and math.isfinite(G)):
                raise jg.InvalidParameterError("not finite (the state or eta is too large)")
            row.update(mu=[mu.real, mu.imag], G=G)
        except jg.JetGaudinError as exc:
            row.update(mu=None, G=None, note=one_line(exc))
        d["branches"].append(row)
    if as_json:
        typer.echo(json.dumps(d, indent=1))
        return
    sites_text = ", ".join(f"{p:g}:{N}" for p, N in model.sites)
    t = _integrals_table(f"{model.algebra.name} chain (λ:N) = {sites_text} (M = {model.M}): principal parts of "
                         "tr ℓ^k/k", d["integrals"])
    eta_s = f"{eta_c.real:g}{eta_c.imag:+g}i"
    for row in d["branches"]:
        r = row["r"]
        if row["mu"] is None:
            t.add_row(f"μ_{r}({eta_s}), G^({r})", "", f"undefined: {row['note']}")
        else:
            t.add_row(f"μ_{r}({eta_s})", "", f"{row['mu'][0]:.17g} {row['mu'][1]:+.17g} i")
            t.add_row(f"G^({r})_η", "", f"{row['G']:.17g}")
    console().print(t)
