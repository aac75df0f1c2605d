"""Bäcklund transformations (Section 6, Appendices 1-2)."""

from .maps import MapProperties, OnePointBacklund, TwoPointBacklund

__all__ = ["MapProperties", "OnePointBacklund", "TwoPointBacklund"]
