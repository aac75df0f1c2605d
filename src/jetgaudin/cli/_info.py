"""``jetgaudin info``: spectral data of one state (private)."""

from __future__ import annotations

import json
import math
from typing import Annotated

import numpy as np
import typer

import jetgaudin as jg

from .. import recording as rec
from . import _chains
from ._app import app
from ._common import (
    APPENDIX2_B,
    APPENDIX2_ETA,
    APPENDIX2_INIT,
    CliInputError,
    check_state_scale,
    console,
    one_line,
    parse_b,
    parse_eta,
    parse_init,
    reported_errors,
)
from ._common import complex_text as _fmt


def _canonical_leaf(X, tol):
    """``(answer, detail)``: whether ``X`` lies on the leaf (fo) of the canonical realisation, with the residuals."""
    from jetgaudin.canonical import leaf_residuals, on_canonical_leaf

    try:
        ok = bool(np.all(on_canonical_leaf(X, tol)))
        res = np.ravel(leaf_residuals(X))
    except jg.JetGaudinError as exc:
        return False, one_line(exc)
    return ok, "relative residuals of C^(1) = 0, C^(2) = 0, C^(3) = 1: " + ", ".join(f"{float(r):.2e}" for r in res)


def _c(z) -> list[float]:
    z = complex(z)
    return [z.real, z.imag]


@app.command()
def info(
    b: Annotated[float, typer.Option("--b", metavar="FLOAT",
            help="field strength b (field b e_3), nonzero (0 allowed with --sites)")
                 ] = APPENDIX2_B,
    eta: Annotated[str, typer.Option("--eta", metavar="COMPLEX",
            help="spectral parameter η, e.g. 5+0.1i")] = APPENDIX2_ETA,
    init: Annotated[
        str, typer.Option("--init", metavar=_chains.INIT_METAVAR, help=_chains.INIT_HELP)
    ] = APPENDIX2_INIT,
    tol: Annotated[float, typer.Option("--tol", help="tolerance of the canonical-leaf test")] = 1e-10,
    as_json: Annotated[bool, typer.Option("--json", help="print JSON instead of tables")] = False,
    plot: Annotated[
        str | None, typer.Option("--plot", help="also draw |ν²| and arg ν over the λ-plane into FILE (.png/.pdf/.svg)")
    ] = None,
    sites: Annotated[str | None, typer.Option("--sites", help=_chains.SITES_HELP)] = None,
    family: Annotated[str | None, typer.Option("--family", help=_chains.FAMILY_HELP)] = None,
    gamma: Annotated[str | None, typer.Option("--gamma", help=_chains.GAMMA_HELP)] = None,
    modulus: Annotated[str | None, typer.Option("--modulus", help=_chains.MODULUS_HELP)] = None,
    algebra: Annotated[str | None, typer.Option("--algebra", help=_chains.ALGEBRA_HELP)] = None,
) -> None:
    """Integrals, Casimirs, ν(η) on both roots, G_η, branch points, and whether the canonical realisation applies.
    With --sites: the chain's integrals h_(i,m), each marked Casimir or Hamiltonian, ν(η), G_η, branch points."""
    with reported_errors():
        fam = _chains.family_kw(sites, family, gamma, modulus=modulus, algebra=algebra)
        if sites is not None:
            return _chains.info(sites, b, eta, init, as_json, fam)
        if not (math.isfinite(tol) and tol > 0):
            raise CliInputError(f"--tol: the tolerance must be a finite number > 0, got {tol}")
        b = parse_b(b)
        eta_c = parse_eta(eta)
        X = np.array(parse_init(init))
        N = len(X) // 3
        check_state_scale(X, b)
        I = np.asarray(jg.integrals(X, b), dtype=float)
        C = np.asarray(jg.casimirs(X), dtype=float)
        d = {
            "N": N,
            "b": b,
            "eta": _c(eta_c),
            "state": X.tolist(),
            "integrals": dict(zip(rec.integral_names(N), I.tolist(), strict=True)),
            "casimirs": C.tolist(),
        }
        try:
            d["nu_default"] = _c(jg.nu(eta_c, X, b))
            d["nu_opposite"] = _c(jg.nu(eta_c, X, b, sheet=-1))
            if not all(map(math.isfinite, d["nu_default"] + d["nu_opposite"])):
                raise jg.InvalidParameterError("nu(eta) is not finite (the state or eta is too large)")
        except jg.JetGaudinError as exc:
            d["nu_default"] = d["nu_opposite"] = None
            d["nu_note"] = one_line(exc)
        try:
            d["G_eta"] = float(jg.interpolating_hamiltonian(X, b, eta_c))
            if not math.isfinite(d["G_eta"]):
                raise jg.InvalidParameterError("G_eta is not finite (the state or eta is too large)")
        except jg.JetGaudinError as exc:
            d["G_eta"] = None
            d["G_eta_note"] = one_line(exc)
        try:
            bp = np.asarray(jg.branch_points(X, b))
            d["branch_points"] = [_c(z) for z in np.ravel(bp) if np.isfinite(z)]
        except (jg.JetGaudinError, np.linalg.LinAlgError) as exc:
            d["branch_points"] = []
            d["branch_points_note"] = one_line(exc)
        if N == 3:
            from jetgaudin.canonical import leaf_casimirs

            d["material_point"] = np.asarray(jg.material_point(X)).tolist()
            d["casimirs_section3"] = dict(zip(("C^(1)", "C^(2)", "C^(3)"), leaf_casimirs(X).tolist(), strict=True))
        ok, detail = _canonical_leaf(X, tol)
        d["on_canonical_leaf"] = ok
        d["canonical_leaf_detail"] = detail
        if plot is not None:
            from .. import plotting

            fig = plotting.figure_spectral_plane(X, b, eta_c)
            typer.echo(f"wrote: {plotting.save_figure(fig, plot, 130)}", err=True)
    if as_json:
        typer.echo(json.dumps(d, indent=1))
        return
    from rich.table import Table

    con = console()
    t = Table(title=f"state with N = {N}, b = {b:g}", title_justify="left")
    t.add_column("quantity")
    t.add_column("value", justify="right")
    for k, v in d["integrals"].items():
        t.add_row(k, f"{v:.17g}")
    for k, v in enumerate(d["casimirs"], 1):
        t.add_row(f"Casimir C_{k} (Prop. 2)", f"{v:.17g}")
    for k, v in d.get("casimirs_section3", {}).items():
        t.add_row(f"Casimir {k} (Section 3)", f"{v:.17g}")
    eta_s = f"{eta_c.real:g}{eta_c.imag:+g}i"
    if d["nu_default"] is not None:
        t.add_row(f"ν({eta_s}), default root", _fmt(complex(*d["nu_default"])))
        t.add_row(f"ν({eta_s}), opposite root", _fmt(complex(*d["nu_opposite"])))
    else:
        t.add_row(f"ν({eta_s})", f"undefined: {d['nu_note']}")
    t.add_row(f"G_η, η = {eta_s}", f"{d['G_eta']:.17g}" if d["G_eta"] is not None else f"undefined: {d['G_eta_note']}")
    if N == 3:
        t.add_row("material point x − z", ", ".join(f"{v:.6g}" for v in d["material_point"]))
    leaf = {True: "yes", False: "no", None: "unknown"}[ok]
    t.add_row("on the canonical leaf", f"{leaf}" + (f" ({detail})" if detail else ""))
    con.print(t)
    con.print("branch points (zeros of λ^2N ν²): " + ", ".join(_fmt(complex(*z)) for z in d["branch_points"]))
