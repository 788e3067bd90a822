"""Per-tree tolerances: a bound derived from the physics or the numerics of the tree being
judged, evaluated on that tree's own runs, in place of one number measured on the shipped
trees.

A tolerance entry of compare/runs/tolerances.toml names a bound (``bound = "NAME"``) instead of a
fixed ``rel``; :func:`tree_entry` evaluates it on the comparison's :class:`Pair` (the
scenario, its physics and the two rungs' runs) and returns the entry with that tree's
``rel`` and the bound's words, with that tree's numbers, appended to its reason. A bound
registers itself beside its definition (:func:`register`); this package imports the modules
that hold them, so the registry is complete once it is imported.

Design notes: docs/ladder.md ("Tolerances per tree").
"""

from __future__ import annotations

from .base import (  # noqa: F401
    BOUNDS,
    READS_FLOOR,
    Bound,
    Pair,
    register,
    tree_entry,
    validate_bound,
)

# the modules that hold bounds, each registering its own (import order is registry order)
from . import chain, contact, continuum, pendulum  # noqa: E402,F401
