"""The backend rule of jetgaudin.maps, checked on every map that follows it (the chain maps join when they do).

One rule: ``backend=`` (alias ``kernel=``) in every constructor and in ``iterate``; the default ``AUTO``; a map
declares a compiled route by overriding ``_compiled_advance`` (``has_compiled``); ``resolved_backend(X, steps)``;
``"compiled"`` on a map without one is an InvalidParameterError; ``prepare_kernels()`` without arguments.
"""

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.backlund import kernels
from jetgaudin.ensemble import BatchBacklund
from jetgaudin.exact import ExactFlow
from jetgaudin.flows import FlowMap
from jetgaudin.maps import Backend, backend_option
from jetgaudin.midpoint import ImplicitMidpoint

from conftest import APPENDIX2_B, APPENDIX2_ETA, APPENDIX2_X0

X0 = np.asarray(APPENDIX2_X0)


def _maps(backend=None, kernel=None):
    """Every map class that follows the rule, built with ``backend``/``kernel`` (``None``: not given)."""
    kw = {} if kernel is None else {"kernel": kernel}
    return {
        "two_point": lambda: jg.TwoPointBacklund(APPENDIX2_B, APPENDIX2_ETA, "default", backend, **kw),
        "one_point": lambda: jg.OnePointBacklund(APPENDIX2_B, APPENDIX2_ETA, "default", False, backend, **kw),
        "batch": lambda: BatchBacklund([APPENDIX2_B] * 2, [APPENDIX2_ETA] * 2, "default", None, None, backend, **kw),
        "flow": lambda: FlowMap(jg.physical_hamiltonian(3, APPENDIX2_B), 0.1, backend=backend, **kw),
        "exact": lambda: ExactFlow(jg.physical_hamiltonian(3, APPENDIX2_B), 0.05, backend=backend, **kw),
        "midpoint": lambda: ImplicitMidpoint(jg.physical_hamiltonian(3, APPENDIX2_B), 0.05, backend=backend, **kw),
    }


HAS_COMPILED = {"two_point": True, "one_point": False, "batch": True, "flow": False, "exact": True,
                "midpoint": False}


def _state(name):
    return np.stack([X0, X0]) if name == "batch" else X0


@pytest.mark.parametrize("name", list(HAS_COMPILED))
def test_default_is_auto_and_has_compiled_is_declared(name):
    m = _maps()[name]()
    assert m.backend is Backend.AUTO
    assert m.has_compiled is HAS_COMPILED[name]
    # AUTO on a map without a compiled route is the NumPy route, whatever the run length
    if not HAS_COMPILED[name]:
        assert m.resolved_backend(_state(name), 10**9) is Backend.NUMPY


@pytest.mark.parametrize("name", list(HAS_COMPILED))
@pytest.mark.parametrize("value", ["numpy", Backend.NUMPY, "auto"])
def test_backend_and_its_alias_kernel_in_the_constructor(name, value):
    by_backend = _maps(backend=value)[name]()
    by_kernel = _maps(kernel=value)[name]()
    assert by_backend.backend is by_kernel.backend is Backend.parse(value)
    assert by_backend.resolved_backend(_state(name), 5) is by_kernel.resolved_backend(_state(name), 5)
    assert by_backend.describe() == by_kernel.describe()


@pytest.mark.parametrize("name", list(HAS_COMPILED))
def test_compiled_is_refused_by_a_map_without_a_compiled_route(name):
    if HAS_COMPILED[name]:
        assert _maps(backend="compiled")[name]().resolved_backend(_state(name), 1) is Backend.COMPILED
        return
    for make in (_maps(backend="compiled")[name], _maps(kernel="compiled")[name]):
        with pytest.raises(jg.InvalidParameterError, match="no compiled route"):
            make()
    m = _maps()[name]()
    with pytest.raises(jg.InvalidParameterError, match="no compiled route"):
        m.iterate(_state(name), 1, backend="compiled")
    with pytest.raises(jg.InvalidParameterError, match="no compiled route"):
        m.iterate(_state(name), 1, kernel="compiled")


def test_backend_and_kernel_must_agree():
    assert backend_option(None, None) is None
    assert backend_option("numpy", Backend.NUMPY) is Backend.NUMPY
    assert backend_option("auto", "numpy") is Backend.NUMPY  # "auto" is no preference: it yields
    assert backend_option("compiled", "auto") is Backend.COMPILED
    assert backend_option("auto", None) is Backend.AUTO
    assert jg.TwoPointBacklund(1.0, 5 + 0.1j, backend="auto", kernel="numpy").backend is Backend.NUMPY
    with pytest.raises(jg.InvalidParameterError, match="disagree"):
        backend_option("numpy", "compiled")
    with pytest.raises(jg.InvalidParameterError, match="disagree"):
        jg.TwoPointBacklund(1.0, 5 + 0.1j, backend="numpy", kernel="compiled")
    with pytest.raises(jg.InvalidParameterError, match="must be 'auto', 'numpy', 'compiled' or 'gpu'"):
        jg.TwoPointBacklund(1.0, 5 + 0.1j, backend="fast")


@pytest.mark.parametrize("name", list(HAS_COMPILED))
def test_iterate_takes_backend_and_kernel(name):
    m = _maps()[name]()
    X = _state(name)
    a = m.iterate(X, 3, backend="numpy")
    b = m.iterate(X, 3, kernel="numpy")
    assert np.array_equal(a, b)
    if HAS_COMPILED[name]:
        c = m.iterate(X, 3, backend="compiled")
        d = m.iterate(X, 3, kernel=Backend.COMPILED)
        assert np.array_equal(c, d)
        # the two routes: the same orbit to round-off (tests/test_routes.py states the bound for the two-point map;
        # 1e-12 here, 3 steps, also covering the exact flow's solved parameters and rotation)
        assert np.max(np.abs(c - a)) <= 1e-12 * np.max(np.abs(a))


@pytest.mark.parametrize("backend", ["numpy", "compiled"])
def test_batch_member_equals_the_single_orbit_on_each_route(backend):
    # BatchBacklund follows the rule: on either route, orbit i equals the single-orbit map on the same route bit
    # for bit (the NumPy route: the reference step orbit by orbit; the compiled route: the batch kernels)
    X = np.stack([X0, 0.9 * X0])
    B = BatchBacklund([1.0, 1.3], [APPENDIX2_ETA, 2 - 1j], backend=backend)
    orbit = B.iterate(X, 20)
    for i, (b, eta) in enumerate([(1.0, APPENDIX2_ETA), (1.3, 2 - 1j)]):
        assert np.array_equal(orbit[:, i], jg.TwoPointBacklund(b, eta, backend=backend).iterate(X[i], 20))


def test_resolved_backend_argument_order_is_x_then_steps():
    m = jg.TwoPointBacklund(1.0, 5 + 0.1j)
    assert m.resolved_backend(X0, 0) is Backend(kernels.auto_kernel(0, 9))
    assert m.resolved_backend(X0, 10**9) is Backend.COMPILED  # past every threshold of auto_kernel
    assert jg.TwoPointBacklund(1.0, 5 + 0.1j, backend="numpy").resolved_backend(X0, 10**9) is Backend.NUMPY


def test_prepare_kernels_without_arguments_prepares_every_kernel(monkeypatch):
    # no arguments: every kernel the map could need (kernels.warmup, tested in test_kernels.py); maps without a
    # compiled route and the NumPy route have nothing to prepare
    calls = []
    monkeypatch.setattr(kernels, "warmup", lambda notify=None: calls.append(notify) or "report")
    assert jg.TwoPointBacklund(1.0, 5 + 0.1j).prepare_kernels() == "report"
    assert BatchBacklund([1.0], [5 + 0.1j]).prepare_kernels() == "report"
    assert len(calls) == 2
    assert jg.TwoPointBacklund(1.0, 5 + 0.1j, backend="numpy").prepare_kernels() is None
    assert jg.OnePointBacklund(1.0, 5 + 0.1j).prepare_kernels() is None
    assert FlowMap(jg.physical_hamiltonian(3, 1.0), 0.1).prepare_kernels() is None
    assert len(calls) == 2


@pytest.mark.parametrize("name", list(HAS_COMPILED))
def test_description_round_trip_keeps_the_backend(name):
    if name == "batch":
        pytest.skip("ensembles record their inputs, not a map description")
    m = _maps(backend="numpy")[name]()
    assert jg.maps.map_from_description(m.describe()).backend is Backend.NUMPY


def test_a_backwards_flow_map_runs_through_the_run_layer(tmp_path):
    # the run layer records the route AUTO chose on a copy of the map that is not validated again: a flow map run
    # backwards (FlowMap.inverse(), dt < 0, which the constructor refuses) still runs, recorded as "numpy"
    from jetgaudin import run as rl

    F = FlowMap(jg.physical_hamiltonian(3, APPENDIX2_B), 0.1).inverse()
    assert F.dt == -0.1 and F.backend is Backend.AUTO
    res = rl.start(rl.RunSpec(F, X0, 2, program="test"), tmp_path / "f")
    assert res.state is rl.RunStatus.COMPLETED and res.spec.map.backend is Backend.NUMPY and res.spec.map.dt == -0.1
