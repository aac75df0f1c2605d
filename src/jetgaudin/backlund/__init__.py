"""Bäcklund transformations (Section 6, Appendices 1-2)."""

from .closed_form import one_point_closed_form, two_point_closed_form, two_point_matrices
from .generating import generating_function
from .maps import Backend, Branch, MapProperties, OnePointBacklund, TwoPointBacklund, auto_kernel

__all__ = [
    "Backend",
    "Branch",
    "MapProperties",
    "OnePointBacklund",
    "TwoPointBacklund",
    "auto_kernel",
    "one_point_closed_form",
    "two_point_closed_form",
    "two_point_matrices",
    "generating_function",
]
