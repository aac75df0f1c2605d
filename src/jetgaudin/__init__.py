"""jetgaudin: jet-extended su(2) Gaudin models, the generalised Lagrange top and its
Bäcklund discretisation (Musso, Petrera, Ragnisco, Satta)."""

from ._errors import (
    BranchPointError,
    IntegrationError,
    InvalidParameterError,
    InvalidStateError,
    JetGaudinError,
    OffLeafError,
    RecordingError,
    RunDirectoryError,
    RunIOError,
    RunLockedError,
    SingularStepError,
)
from .algebra import bracket, casimirs, hamiltonian_vector_field, poisson_tensor, structure_constants
from .backlund import MapProperties, OnePointBacklund, TwoPointBacklund
from .flows import FlowMap, Trajectory, integrate
from .gaudin import (
    ChainHamiltonian,
    ChainOnePointBacklund,
    ChainTwoPointBacklund,
    GaudinModel,
    gaudin_magnet,
    lagrange_chain,
    parse_sites,
    twisted_chain,
)
from .hamiltonians import (
    IntegralHamiltonian,
    interpolating_flow_hamiltonian,
    interpolating_hamiltonian,
    interpolating_vector_field,
    interpolating_weights,
    physical_hamiltonian,
)
from .lax import lax_matrix, r_matrix, uvw
from .maps import Advance, Backend, Branch, Map, map_from_description
from .spectral import branch_points, integral_gradients, integrals, nu, nu_squared
from .systems import GaudinTop, generalized_lagrange_top, lagrange_top, material_point

__version__ = "0.1.0"

__all__ = [
    "__version__",
    "JetGaudinError",
    "InvalidStateError",
    "InvalidParameterError",
    "SingularStepError",
    "BranchPointError",
    "OffLeafError",
    "IntegrationError",
    "RecordingError",
    "RunDirectoryError",
    "RunLockedError",
    "RunIOError",
    "structure_constants",
    "poisson_tensor",
    "bracket",
    "hamiltonian_vector_field",
    "casimirs",
    "lax_matrix",
    "uvw",
    "r_matrix",
    "integrals",
    "integral_gradients",
    "nu",
    "nu_squared",
    "branch_points",
    "Map",
    "MapProperties",
    "Advance",
    "Backend",
    "Branch",
    "map_from_description",
    "FlowMap",
    "OnePointBacklund",
    "TwoPointBacklund",
    "Trajectory",
    "integrate",
    "IntegralHamiltonian",
    "physical_hamiltonian",
    "interpolating_hamiltonian",
    "interpolating_weights",
    "interpolating_flow_hamiltonian",
    "interpolating_vector_field",
    "GaudinTop",
    "lagrange_top",
    "generalized_lagrange_top",
    "material_point",
    "GaudinModel",
    "ChainHamiltonian",
    "ChainTwoPointBacklund",
    "ChainOnePointBacklund",
    "gaudin_magnet",
    "lagrange_chain",
    "twisted_chain",
    "parse_sites",
    "euler_to_state",
    "state_to_euler",
    "on_canonical_leaf",
    "leaf_residuals",
    "canonical_hamiltonian",
    "canonical_integrals",
    "canonical_vector_field",
]

# The canonical realisation builds its formulas with SymPy: import it on first use only, so that
# `import jetgaudin` (and long runs) stay light.
_LAZY = {
    "euler_to_state": "canonical",
    "state_to_euler": "canonical",
    "on_canonical_leaf": "canonical",
    "leaf_residuals": "canonical",
    "canonical_hamiltonian": "canonical",
    "canonical_integrals": "canonical",
    "canonical_vector_field": "canonical",
}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'jetgaudin' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
