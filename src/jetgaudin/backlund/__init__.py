"""Bäcklund transformations (Section 6, Appendices 1-2)."""

from .closed_form import one_point_closed_form, two_point_closed_form, two_point_matrices
from .generating import generating_function
from .maps import MapProperties, OnePointBacklund, TwoPointBacklund

__all__ = [
    "MapProperties",
    "OnePointBacklund",
    "TwoPointBacklund",
    "one_point_closed_form",
    "two_point_closed_form",
    "two_point_matrices",
    "generating_function",
]
