"""The design answer's numbers (report.json ``answer.design``, compare/report/design_answer.py)
as the pages quote them: per tree, the gaps at its operating point (%), each "along"
sentence's first interval (a/l and m/M_T in 1, contact durations in ms, e in 1) and each
map's nearest choice within both targets."""

from __future__ import annotations

from .base import put, rounded

#: How an input's values are quoted: input -> (scale from SI, key suffix).
SHOWN = {"a_over_l": (1.0, ""), "mass_ratio": (1.0, ""), "contact_duration": (1e3, "_ms"),
         "restitution": (1.0, "")}


def from_design(design: dict) -> dict:
    """``design.<tree>.gap_pct.<quantity>``, ``design.<tree>.<pair>.<quantity>.within<unit>``
    ([low, high] of the first interval; absent when none) and
    ``design.<tree>.<pair>.nearest.<input><unit>``."""
    out: dict = {}
    for tree, a in design.items():
        for q, gap in a["gaps_at_point"].items():
            put(out, f"design.{tree}.gap_pct.{q}", rounded(100.0 * gap))
        for s in a["sentences"]:
            if s["rule"] == "along" and s["within"]:
                scale, unit = SHOWN[s["along"]]
                put(out, f"design.{tree}.{s['pair']}.{s['quantity']}.within{unit}",
                    rounded([scale * v for v in s["within"][0]]))
        for pair, n in a["nearest"].items():
            for name, v in zip(pair.split("-"), n["at"]):
                scale, unit = SHOWN[name]
                put(out, f"design.{tree}.{pair}.nearest.{name}{unit}", rounded(scale * v))
    return out
