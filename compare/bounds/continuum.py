"""Bounds on the continuum's physical steps (Timoshenko against Euler-Bernoulli, the pad's
convention) from the tree's own geometry and masses."""

from __future__ import annotations

from .base import Bound, Pair, register  # noqa: F401
