"""Bounds on the pad's steps: the soft SDOF against the Newton model and the engines' SDOF
against the soft one, from the tree's own collision duration, damping and step."""

from __future__ import annotations

from .base import Bound, Pair, register  # noqa: F401
