"""Multi-site jet-extended rational su(2) Gaudin models (chains) and their Bäcklund maps (issue 12).

See ``docs/chains.md``: the model, the state layout, the integrals (Casimirs and Hamiltonians), the maps,
the field ``b = 0``, the checks and the matching with the literature.
"""

from ._one_point import ChainOnePointBacklund
from .flow import ChainFlowMap
from .maps import ChainTwoPointBacklund
from .model import ChainHamiltonian, GaudinModel, clebsch_top, gaudin_magnet, lagrange_chain, parse_sites, twisted_chain
from .sun import SunGaudinModel
from .sun_exact import SunExactFlow
from .sun_maps import SunTwoPointBacklund

__all__ = [
    "GaudinModel",
    "ChainHamiltonian",
    "ChainTwoPointBacklund",
    "ChainOnePointBacklund",
    "ChainFlowMap",
    "parse_sites",
    "gaudin_magnet",
    "clebsch_top",
    "lagrange_chain",
    "twisted_chain",
    "SunGaudinModel",
    "SunTwoPointBacklund",
    "SunExactFlow",
]
