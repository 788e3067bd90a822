"""Bounds on the pendulum's step (the compound pendulum against the linear one) and on the
two engines against each other, from the tree's own runs."""

from __future__ import annotations

from .base import Bound, Pair, register  # noqa: F401
