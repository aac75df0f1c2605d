r"""The route table of :func:`jetgaudin.solve`: for every model's Hamiltonian and every method, the map that advances
a state by one time step, or a typed refusal that says why there is none (issue 33: ``solve`` has no top/chain
branch).

A Hamiltonian follows the protocol :class:`jetgaudin.hamiltonians.SolveHamiltonian`; its ``route_kind`` names its
rows here:

============  =======================================  ==========================================  ===================
method        ``"top"`` (:class:`~jetgaudin.Integral`  ``"chain"`` (``model.hamiltonian(w)``,      ``"sun"`` (an su(n)
              ``Hamiltonian``)                         every su(2) family)                          chain)
============  =======================================  ==========================================  ===================
``exact``     :class:`~jetgaudin.ExactFlow`            :class:`~jetgaudin.ChainExactFlow`           ``SunExactFlow``
                                                                                                    (``n = 3``)
``bt``        :class:`~jetgaudin.exact.MatchedBack`    the exact flow where it is **one** two-      refused
              ``lund``                                 point map and a rotation (e.g. two rational
                                                       sites, or one of order 2); else refused
``midpoint``  :class:`~jetgaudin.midpoint.Implicit`    the same                                     the same
              ``Midpoint``
``kahan``     :class:`~jetgaudin.kahan.KahanMap`       the same                                     refused (not
                                                                                                    quadratic)
``dop853``,   :func:`jetgaudin.integrate` (adaptive; heyoka's compiled integrator cached per        ``heyoka``:
``heyoka``    Hamiltonian, :func:`jetgaudin.flows._heyoka_integrator`)                              ``n ≤ 3``
============  =======================================  ==========================================  ===================

**The matched two-point map ("bt") of a chain.**  A top's :class:`~jetgaudin.exact.MatchedBacklund` is one two-point
map per step with its ``H_2`` weight matched (and the ``H_1`` rotation undone).  A chain's exact step
(:class:`~jetgaudin.ChainExactFlow`) needs ``k = (matched integrals) − (rotation) − (identities)`` maps; where
``k = 1`` the matched map *is* that step (one map and a rotation), and where ``k > 1`` one map cannot match the
chain's ``k + 1`` commuting weights: ``"bt"`` is refused naming ``k`` and pointing to ``"exact"``.

**The top as a one-site model.**  A chain that is a top (``GaudinModel.is_top``: one rational site at 0, ``b ≠ 0``;
order ``N ≥ 2``) takes the top's rows for ``"exact"`` and ``"bt"``: its ``H.as_top()`` with
:class:`~jetgaudin.ExactFlow` / :class:`~jetgaudin.exact.MatchedBacklund` and their hand-tuned kernels (the same
flow to round-off as :class:`~jetgaudin.ChainExactFlow`, ``tests/test_top_as_model.py``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ._errors import InvalidParameterError
from .hamiltonians import SolveHamiltonian

__all__ = ["ROUTES", "Route", "check_method", "method_map", "ADAPTIVE"]

#: the adaptive methods (:func:`jetgaudin.integrate`; no map)
ADAPTIVE = ("dop853", "heyoka")


@dataclass(frozen=True)
class Route:
    """One row of the table: ``build(H, dt, substeps, backend) -> Map`` (``None``: an adaptive method, integrated by
    :func:`jetgaudin.integrate`) and ``check(H)``, which raises a typed refusal where the method does not apply."""

    build: Callable[[Any, float, int, str], Any] | None = None
    check: Callable[[Any], None] | None = None


def _exact_top(H, dt, substeps, backend):
    from .exact import ExactFlow

    return ExactFlow(H, dt, substeps, backend)


def _bt_top(H, dt, substeps, backend):
    from .exact import MatchedBacklund

    return MatchedBacklund(H, dt, substeps, backend)


def _midpoint(H, dt, substeps, backend):
    from .midpoint import ImplicitMidpoint

    return ImplicitMidpoint(H, dt, backend)


def _kahan(H, dt, substeps, backend):
    from .kahan import KahanMap

    return KahanMap(H, dt, backend)


def _top_view(H):
    """The top's Hamiltonian where the chain is a top (one rational site at 0, ``b ≠ 0``, order ``N ≥ 2``: the
    hand-tuned top route, ``GaudinModel.is_top``), else ``None``."""
    return H.as_top() if H.model.is_top and H.model.M >= 2 and H.weights.ndim == 1 else None


def _exact_chain(H, dt, substeps, backend):
    if H.model.constants is not None:  # sites with jet constants: the reduced model's step conjugated by T
        from .gaudin._site_constants import conjugated

        return conjugated(H.model, _exact_chain(H.model.reduced.hamiltonian(H.weights), dt, substeps, backend))
    top = _top_view(H)
    if top is not None:  # the route table's top entry: the top's ExactFlow and its kernels
        return _exact_top(top, dt, substeps, backend)
    from .exact_chain import ChainExactFlow

    return ChainExactFlow(H, dt, substeps=substeps)


def _bt_chain(H, dt, substeps, backend):
    top = _top_view(H)
    return _bt_top(top, dt, substeps, backend) if top is not None else _exact_chain(H, dt, substeps, backend)


def chain_maps_per_step(H) -> int:
    """``k``: the two-point maps of one exact step of the chain Hamiltonian ``H`` (module doc)."""
    from .exact_chain import ChainExactFlow

    keep, E, _ = ChainExactFlow(H.model.reduced.hamiltonian(H.weights), 1.0)._design
    return int(keep.sum()) - int(E.shape[1])


def _check_bt_chain(H) -> None:
    if _top_view(H) is not None:
        return
    k = chain_maps_per_step(H)
    if k != 1:
        raise InvalidParameterError(
            f"method='bt': this chain has no matched two-point map: its exact time step composes k = {k} commuting "
            f"two-point maps (one per matched integral, less the rotation and the identities), and one map cannot "
            f"match its {k + 1} weights; use method='exact' (the exact flow), 'midpoint', 'kahan', 'dop853' or "
            "'heyoka'")


def _sun_check(method: str) -> Callable[[Any], None]:
    def check(H) -> None:
        from .gaudin.sun_solve import check_solve_method

        check_solve_method(H.model, method)

    return check


def _exact_sun(H, dt, substeps, backend):
    return H.model.exact_flow(H, dt, substeps)


#: ``(route_kind, method) -> Route``: the one table (module doc)
ROUTES: dict[tuple[str, str], Route] = {
    ("top", "exact"): Route(_exact_top),
    ("top", "bt"): Route(_bt_top),
    ("top", "midpoint"): Route(_midpoint),
    ("top", "kahan"): Route(_kahan),
    ("top", "dop853"): Route(),
    ("top", "heyoka"): Route(),
    ("chain", "exact"): Route(_exact_chain),
    ("chain", "bt"): Route(_bt_chain, _check_bt_chain),
    ("chain", "midpoint"): Route(_midpoint),
    ("chain", "kahan"): Route(_kahan),
    ("chain", "dop853"): Route(),
    ("chain", "heyoka"): Route(),
    ("sun", "exact"): Route(_exact_sun, _sun_check("exact")),
    ("sun", "bt"): Route(None, _sun_check("bt")),
    ("sun", "midpoint"): Route(_midpoint),
    ("sun", "kahan"): Route(None, _sun_check("kahan")),
    ("sun", "dop853"): Route(),
    ("sun", "heyoka"): Route(None, _sun_check("heyoka")),
}


#: the types already found to be :class:`SolveHamiltonian` (the runtime protocol check walks its members: ~11 µs a
#: call, twice per ``jg.solve``; the members are the classes' own methods, properties and class variables)
_HAMILTONIAN_TYPES: set[type] = set()


def _is_hamiltonian(H) -> bool:
    if type(H) in _HAMILTONIAN_TYPES:
        return True
    if isinstance(H, SolveHamiltonian):
        _HAMILTONIAN_TYPES.add(type(H))
        return True
    return False


def _route(H, method: str) -> Route:
    if not _is_hamiltonian(H):
        raise InvalidParameterError("H must be a Hamiltonian of a model: an IntegralHamiltonian (e.g. "
                                    "jg.physical_hamiltonian(N, b)) or a chain's model.hamiltonian(weights)")
    route = ROUTES.get((H.route_kind, method))
    if route is None:
        methods = sorted({m for k, m in ROUTES if k == H.route_kind})
        raise InvalidParameterError(f"method={method!r} is not a method of solve; use one of "
                                    f"{', '.join(map(repr, methods))}")
    return route


def check_method(H, method: str) -> None:
    """Raise the typed refusal of ``method`` for ``H`` where it does not apply (module doc); else nothing."""
    route = _route(H, method)
    if route.check is not None:
        route.check(H)


def method_map(H, method: str, dt: float, substeps: int = 1, backend: str = "auto"):
    """The map of one time step ``dt`` of ``H`` by the fixed-step ``method`` (``"exact"``, ``"bt"``, ``"midpoint"``,
    ``"kahan"``), refused with :class:`~jetgaudin.InvalidParameterError` where the table has none."""
    route = _route(H, method)
    if route.check is not None:
        route.check(H)
    if route.build is None:
        raise InvalidParameterError(f"method={method!r} is adaptive (jetgaudin.integrate), not a map of a time step")
    from .maps import Backend

    Backend.parse(backend)  # an unknown name is refused on every route (a route without a choice used to ignore it)
    return route.build(H, dt, substeps, backend)
