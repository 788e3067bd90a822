"""What every part of the numbers tooling shares: where the sources are, the shipped trees,
how rung values are displayed, and how a number is stored in docs/numbers.json (rounded to
:data:`DIGITS` significant digits; a list is a [min, max] range)."""

from __future__ import annotations

import math
from pathlib import Path

from treeimpact.compare.report.trunks import TRUNKS_JSON  # noqa: F401 - bench_trunks.py's file

ROOT = Path(__file__).resolve().parents[2]
NUMBERS = ROOT / "docs" / "numbers.json"
CONTACT_FIT = ROOT / "docs" / "results" / "contact-fit.json"
IDENTIFY_VALIDATION = ROOT / "docs" / "results" / "identify-validation.json"
BENCHMARKS = ROOT / "benchmarks" / "results"
#: The shipped trees, in the order the pages list them.
TREES = ("open-center", "central-leader", "realistic-crown")
#: How the rungs' values are quoted: metric -> (scale from SI, unit).
DISPLAY = {"T0": (1e3, "ms"), "x0": (1e3, "mm"), "V": (1.0, "m/s"), "x_max": (1e3, "mm"),
           "t_xmax": (1e3, "ms"), "t_sep": (1e3, "ms"), "impact_loss": (1.0, "J"),
           "energy_transferred": (1.0, "J"), "theta_b": (180.0 / math.pi, "deg"),
           "energy_delivered": (1.0, "J"), "contact_dissipation": (1.0, "J"),
           "rebound_energy": (1.0, "J"), "impulse": (1.0, "N s"), "peak_force": (1e-3, "kN"),
           "contact_episodes": (1.0, "1"), "crown_peak": (1e3, "mm"),
           "crown_peak_acceleration": (1.0, "m/s^2")}
#: Relative difference allowed between a report's numbers and the cheap part rerun beside
#: it by ``numbers`` (:func:`write_numbers`: one machine, one BLAS kernel, so deterministic
#: runs; the file keeps 8 significant digits). Across machines the numbers are compared at
#: the digits the pages print instead (:func:`check_now`): another CPU's BLAS kernel moves
#: the last bits, and a difference of nearly equal values (beam.*.vs48_pct) by 1e-5 of
#: itself.
RECOMPUTE_REL = 1e-6
#: Significant digits kept in docs/numbers.json.
DIGITS = 8


def finite(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def rounded(v):
    if isinstance(v, list):
        return [rounded(x) for x in v]
    return float(f"{v:.{DIGITS}g}") if finite(v) else v


def span(values) -> list | None:
    vals = [v for v in values if finite(v)]
    return [min(vals), max(vals)] if vals else None


def put(out: dict, key: str, value) -> None:
    if value is None:
        return
    if isinstance(value, list):
        if not value or not all(finite(v) for v in value):
            return
    elif not finite(value):
        return
    out[key] = rounded(value)


def per_tree(out: dict, key: str, by_tree: dict, *, spans: bool = True) -> None:
    """key.<tree> for each tree, key.trees (the list in :data:`TREES` order, when every
    tree has it), key (the [min, max] span) and abs.key (the span of |value|)."""
    for t, v in by_tree.items():
        put(out, f"{key}.{t}", v)
        if spans and finite(v) and v < 0:
            put(out, f"abs.{key}.{t}", abs(v))
        elif spans:
            put(out, f"abs.{key}.{t}", v)
    vals = [by_tree.get(t) for t in TREES]
    if all(finite(v) for v in vals):
        put(out, f"{key}.trees", vals)
    if spans:
        put(out, key, span(by_tree.values()))
        put(out, f"abs.{key}", span([abs(v) for v in by_tree.values() if finite(v)]))
