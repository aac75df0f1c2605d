"""jetgaudin: jet-extended su(2) Gaudin models, the generalised Lagrange top and its
Bäcklund discretisation (Musso, Petrera, Ragnisco, Satta)."""

from . import _errors, _startup, hamiltonians  # noqa: F401  (_startup before NumPy: the command line's start-up guard)
from ._errors import *  # noqa: F403  (the exception hierarchy: all of _errors.__all__ is public)
from .algebra import bracket, casimirs, hamiltonian_vector_field, poisson_tensor, structure_constants
from .backlund import MapProperties, OnePointBacklund, TwoPointBacklund
from .events import find_events, poincare_section
from .exact import ExactFlow, exact_parameters
from .exact_chain import ChainExactFlow
from .flows import FlowMap, Trajectory, integrate
from .gaudin import (
    ChainHamiltonian,
    ChainOnePointBacklund,
    ChainTwoPointBacklund,
    GaudinModel,
    SunGaudinModel,
    SunTwoPointBacklund,
    clebsch_top,
    gaudin_magnet,
    lagrange_chain,
    parse_sites,
    twisted_chain,
)
from .hamiltonians import *  # noqa: F403  (all of hamiltonians.__all__ is public)
from .lax import lax_matrix, r_matrix, uvw
from .lie import SU, su
from .maps import Advance, Backend, Branch, Map, map_from_description
from .physical import heavy_top, kirchhoff_clebsch
from .solve import solve
from .spectral import branch_points, integral_gradients, integrals, nu, nu_squared
from .systems import GaudinTop, generalized_lagrange_top, lagrange_top, material_point

__version__ = "0.1.0"

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

__all__ = [
    "__version__",
    *_errors.__all__,
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
    "ExactFlow",
    "exact_parameters",
    "ChainExactFlow",
    "solve",
    "heavy_top",
    "kirchhoff_clebsch",
    "find_events",
    "poincare_section",
    "OnePointBacklund",
    "TwoPointBacklund",
    "Trajectory",
    "integrate",
    *hamiltonians.__all__,
    "GaudinTop",
    "lagrange_top",
    "generalized_lagrange_top",
    "material_point",
    "GaudinModel",
    "ChainHamiltonian",
    "ChainTwoPointBacklund",
    "ChainOnePointBacklund",
    "gaudin_magnet",
    "clebsch_top",
    "lagrange_chain",
    "twisted_chain",
    "parse_sites",
    "su",
    "SU",
    "SunGaudinModel",
    "SunTwoPointBacklund",
    *_LAZY,
]


def __getattr__(name):
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'jetgaudin' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
