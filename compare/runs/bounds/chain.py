"""Bounds on the discretised trunks (the engines' hinged chain and MuJoCo's rod) against the
exact continuum: what the tree's own segments leave."""

from __future__ import annotations

from .base import Bound, Pair, register  # noqa: F401
