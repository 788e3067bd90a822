"""The report's answer, first screen first: how far the paper's 1-DOF model is from the
continuum trunk (:func:`one_dof_answer`, with each cell's band over the unmeasured inputs
from a study's sensitivity part) and up to which e each consequence of "e is small" holds
(:func:`small_e_rows`), and both halves in two sentences (:func:`in_short`)."""

from __future__ import annotations

import math

import numpy as np

from ..runs.rungs import RungKind
from ..runs.verdicts import validity_tolerance
from ..studies.small_e import bracket_text
from .base import deciding

#: The quantities the answer leads with, what a harvester designer needs of the 1-DOF model:
#: (metric, label, display scale, display unit). Whole-event metrics, robust to chattering.
ANSWER_METRICS = (("x_max", "x_max", 1e3, "mm"),
                  ("energy_delivered", "energy to tree", 1.0, "J"),
                  ("crown_peak", "crown peak", 1e3, "mm"),
                  ("crown_peak_acceleration", "crown acceleration*", 1e-3, "km/s^2"),
                  ("peak_force", "peak force*", 1e-3, "kN"))
#: Each answer metric's glossary term (docs/glossary.md), its column's tooltip.
ANSWER_TERMS = {"x_max": "x_max", "energy_delivered": "energy delivered",
                "crown_peak": "crown peak", "crown_peak_acceleration": "crown acceleration",
                "peak_force": "peak force"}


def one_dof_answer(scen_sections) -> list[dict]:
    """Per scenario (one of ``scen_sections``, the report's scenario sections), the answer
    first: how far the paper's 1-DOF model is from the continuum
    trunk (the beam rung, same pad; the engines' chains agree with it) on the
    :data:`ANSWER_METRICS` at the scenario's contact, and whether the 1-DOF model explains
    the continuum's record at all (the full-record fit). The 1-DOF value is the paper's
    (Newton) model's, or the soft SDOF's with the same pad where Newton's impulses have none
    (force, acceleration). Within compare.tree.ladder.validity_tolerance it is good enough."""
    tolerance = validity_tolerance()
    out = []
    for s in scen_sections:
        L = s.ladder
        chains = [r for r in L.rungs if r.rung.kind == RungKind.BEAM and r.ok]
        ref = L.rungs[0]
        soft = [r for r in L.rungs if r.rung.kind == RungKind.CONTACT and r.ok]
        if not chains or not ref.ok:
            out.append({"scenario": L.name, "available": False, "why": _why_no_answer(L)})
            continue
        rows = {}
        for m, label, scale, unit in ANSWER_METRICS:
            v0, source = ref.values.get(m, math.nan), ref.rung.id
            if not math.isfinite(v0) and soft:
                v0, source = soft[0].values.get(m, math.nan), soft[0].rung.id
            v = float(np.mean([c.values.get(m, math.nan) for c in chains]))
            rows[m] = {"one_dof": v0, "flexible": v, "label": label, "scale": scale,
                       "unit": unit, "one_dof_rung": source,
                       "rel": (v - v0) / abs(v0) if v0 and math.isfinite(v0) else math.nan}
        fits = {f["rung"]: f for f in getattr(s, "fits", [])}
        explained = [fits[c.rung.id]["explained"] for c in chains
                     if c.rung.id in fits and "explained" in fits[c.rung.id]]
        contact = L.scenario.contact
        pads = {"one_dof": soft[0] if soft else None, "continuum": chains[0]}
        out.append({"scenario": L.name, "available": True, "metrics": rows,
                    "pad": {side: {"first_contact_duration": r.result.metrics.get(
                        "first_contact_duration") if r else None,
                        "damping_ratio": r.result.model.get("pad_damping_ratio") if r else None}
                        for side, r in pads.items()},
                    "good_enough": {m: abs(r["rel"]) <= tolerance
                                    for m, r in rows.items()},
                    "explained": bool(explained) and all(explained),
                    "pad_loss": {"continuum": float(np.mean(
                        [c.values.get("contact_dissipation", math.nan) for c in chains])),
                        "one_dof": ref.values.get("contact_dissipation", math.nan)},
                    "contact_duration": contact.duration, "restitution": contact.restitution})
    return out


def with_sensitivity(answer: list[dict], studies) -> None:
    """Each ``answer`` row with its cells' bands over the unmeasured inputs and the inputs
    that decide each, from the first of ``studies`` (the report's study sections) with a
    sensitivity part (compare.studies.sensitivity); ``trajectories`` and ``held`` (the measured
    inputs) beside them. Changes the rows in place."""
    sens = next((s.study["sensitivity"] for s in studies
                 if s.study and s.study.get("sensitivity")), {})
    trees = sens.get("trees", {})
    for row in answer:
        tree = trees.get(row["scenario"]) or {}
        row["sensitivity"] = {k: {**v, "deciding_text": deciding(v)}
                              for k, v in (tree.get("outputs") or {}).items()}
        row["sensitivity_design"] = {k: tree.get(k) for k in ("trajectories", "evaluations",
                                                               "held", "conf_level")} \
            if tree else {}


def grid_text(grid) -> str:
    """The e grid of the small-e curves as the table's caption says it: '0.005 on [0, 0.05],
    then 0.05 to 0.9' (each run of equal steps, rounded to 1e-6)."""
    steps = [round(b - a, 6) for a, b in zip(grid, grid[1:])]
    parts, start = [], 0
    for i in range(1, len(steps) + 1):
        if i == len(steps) or steps[i] != steps[start]:
            parts.append(f"{steps[start]:g} on [{grid[start]:g}, {grid[i]:g}]")
            start = i
    return ", then ".join(parts)


def small_e_rows(trees: dict) -> list[dict]:
    """The small-e table's rows from ``trees`` (tree -> its small-e answers,
    :func:`compare.studies.small_e.small_e_answer`): per approximation its label, what it is
    compared with, and per tree {holds (text), at_e (relative error at the tree's e), e,
    flag (beyond the tolerance at the tree's e)}."""
    tol = validity_tolerance()
    names = list(next(iter(trees.values()))) if trees else []
    rows = []
    for name in names:
        cells = {}
        for tree, answers in trees.items():
            a = answers[name]
            at_e = a["error_at_e"]
            at_e = at_e if at_e is not None and math.isfinite(at_e) else None  # n/a
            cells[tree] = {"holds": holds_text(a), "at_e": at_e, "e": a["e"],
                           "flag": not (at_e is not None and math.isfinite(at_e)
                                        and abs(at_e) <= tol),
                           "not_small_e": a["bracket"] is None and a["holds_up_to_e"] == 0.0}
        first = next(iter(trees.values()))[name]
        rows.append({"name": name, "label": first["label"], "what": first["what"],
                     "cells": cells})
    return rows


def holds_text(a: dict) -> str:
    """'0.375-0.380' (the crossing's bracket, rounded outward; 'not monotone' before it when
    the curve is not, '; 2nd strike from e = 0.2 (first contact only: 0.215-0.220)' when
    the exact run it counts strikes again), '>= 0.9' (the whole range), or '0: -25 % at
    e = 0' (not a small-e effect; a 1-DOF trunk's gap adds from which e it moves by more than
    the validity tolerance in points, :func:`small_e_curves.steady_bracket`)."""
    if a["bracket"] is not None:
        text = bracket_text(a["bracket"])
        if not a.get("monotone", True):
            text = f"not monotone (exits {text})"
        if a.get("second_strike_from") is not None:
            text += f"; 2nd strike from e = {a['second_strike_from']:g}"
            if a.get("first_contact_bracket") is not None:
                text += f" (first contact only: {bracket_text(a['first_contact_bracket'])})"
        return text
    if a["holds_up_to_e"] > 0:
        return f">= {a['holds_up_to_e']:g}"
    z, split = a["error_at_zero"], a.get("split_at_zero")
    if split and math.isfinite(z) and all(math.isfinite(v) for v in split.values()):
        return (f"0: {100 * z:+.0f} % at e = 0 (10 ms fit {100 * split['fit']:+.0f} %, "
                f"eq 46 damped omega {100 * split['reading']:+.0f} %)")
    if z is None or not math.isfinite(z):
        return "0: no value at e = 0"
    text, tol = f"0: {100 * z:+.0f} % at e = 0", 100 * validity_tolerance()
    if a.get("steady_bracket") is not None:
        text += f"; moves > {tol:.0f} points from e = {bracket_text(a['steady_bracket'])}"
    elif "steady_up_to_e" in a:
        text += f"; within {tol:.0f} points of it for every e"
    return text


def span_text(values, fmt, sep="-") -> str:
    """``values``' lowest and highest, each as ``fmt`` prints it, joined by ``sep``; one
    number when both print alike."""
    lo, hi = min(values), max(values)
    return fmt(lo) if fmt(lo) == fmt(hi) else f"{fmt(lo)}{sep}{fmt(hi)}"


def _inner(v) -> str:
    """A crossing's inner end (an e up to which something holds) rounded inward to 0.001,
    as its bracket is printed outward (``small_e_curves.bracket_text``)."""
    return f"{math.floor(1000 * v + 1e-6) / 1000:.3f}"


def pct_text(v) -> str:
    """A relative difference ``v`` (1) as a signed whole percentage, without the unit."""
    return f"{100 * v:+.0f}"


def _steady(trees: dict, tol: float) -> str:
    """The words for where the 1-DOF trunk's gaps stop being the trunk's alone: each gap
    stays within ``tol`` (as points) of its e = 0 value up to the bracket the small-e
    answers ``trees`` hold (``steady_bracket``); "" when no gap has one."""
    parts = []
    first = next(iter(trees.values()))
    for name, a in first.items():
        if "steady_up_to_e" not in a:
            continue
        label = a["label"].split(": ", 1)[-1]
        ups = [t[name]["steady_up_to_e"] for t in trees.values() if "steady_up_to_e" in t[name]]
        whole = all(t[name].get("steady_bracket") is None for t in trees.values())
        parts.append(f"{label} over the whole range" if whole
                     else f"{label} up to e = {span_text(ups, _inner)}")
    if not parts:
        return ""
    return (f"; the trunk alone sets them (within {100 * tol:.0f} points of their e = 0 "
            "value) for " + ", ".join(parts) + ", and beyond that e moves them too")


def _why_no_answer(ladder) -> str:
    """Why ``ladder`` gives no 1-DOF answer: its failed reference (the paper's model) and
    continuum rungs with their reasons, '<rung>: <reason>' joined by '; '."""
    needed = [r for r in ladder.rungs if r is ladder.rungs[0] or r.rung.kind == RungKind.BEAM]
    failed = [f"{r.rung.id}: {r.reason or 'failed'}" for r in needed if not r.ok]
    return "; ".join(failed) or "no continuum rung was run"


def in_short(one_dof: list[dict], trees: dict) -> dict:
    """Both halves of the answer in a sentence each (plain text), from the answer rows
    ``one_dof`` (:func:`one_dof_answer`) and the small-e answers per tree ``trees``:
    {"one_dof": ..., "small_e": ...}."""
    tol = validity_tolerance()
    rows = [a for a in one_dof if a.get("available")]
    out = {}
    if rows:
        gaps = {m: [a["metrics"][m]["rel"] for a in rows] for m in ("x_max",
                                                                     "energy_delivered")}
        es = sorted({a["restitution"] for a in rows})
        out["one_dof"] = (
            f"The 1-DOF trunk: at each tree's own pad and e ({', '.join(f'{e:g}' for e in es)}) "
            f"the paper's 1-DOF model is {span_text(gaps['x_max'], pct_text, '..')} % off the "
            f"continuum trunk on x_max and {span_text(gaps['energy_delivered'], pct_text, '..')} % "
            f"on the energy delivered ({100 * tol:.0f} % counts as good enough).")
    missing = [a for a in one_dof if not a.get("available")]
    if missing:
        none = "; ".join(f"{a['scenario']} ({a['why']})" for a in missing)
        out["one_dof"] = (out.get("one_dof", "The 1-DOF trunk:") +
                          f" No answer for {none}.")
    if trees:
        out["small_e"] = _small_e_sentence(trees, tol)
    return out


def _small_e_sentence(trees: dict, tol: float) -> str:
    """The small-e half in one sentence (:func:`in_short`): up to which e each consequence
    holds, which are off already at e = 0 (not small-e effects), which have no value at
    e = 0 on any tree (no verdict) and which none at any e (no answer: not an effect)."""
    held, off, trunk, none, unset = [], [], [], [], []
    first = next(iter(trees.values()))
    for name in first:
        answers = [t[name] for t in trees.values()]
        label = first[name]["label"].split(": ", 1)[-1]  # "1-DOF trunk: x_max" -> x_max
        zeros = [a["error_at_zero"] for a in answers]
        if not any(_finite(v) for a in answers for v in a["errors"]):
            none.append(label)
        elif all(a["bracket"] is None and a["holds_up_to_e"] == 0.0 for a in answers):
            if not any(map(_finite, zeros)):  # neither held nor off: nothing at e = 0
                unset.append(label)
                continue
            part = _at_zero_part(label, dict(zip(trees, zeros)))
            (trunk if first[name].get("model") == "continuum" else off).append(part)
        else:
            held.append(_held_part(trees, name, answers, label))
    text = ""
    if held or off or trunk:
        text = (f"Small e: each consequence stays within {100 * tol:.0f} % of the exact result "
                + ("up to e = " + ", ".join(held) if held else "at no e") + ".")
    if off:
        text += " Off already at e = 0, so not small-e effects: " + ", ".join(off) + "."
    if trunk:
        text += (" Nor does e make the 1-DOF trunk's gaps: " + ", ".join(trunk)
                 + " already at e = 0" + _steady(trees, tol) + ".")
    if unset:
        text += ((" " if text else "Small e: ") + "No verdict on " + ", ".join(unset)
                 + ": no value at e = 0 on any tree (the table has the e that have one).")
    if none:
        text += ((" " if text else "Small e: ") + "No answer for " + ", ".join(none)
                 + ": no value at any e of any tree (the runs' reasons are in the table).")
    return text


def _at_zero_part(label: str, zeros: dict) -> str:
    """'LABEL +a..+b %': the e = 0 errors ``zeros`` (tree -> error) that exist, naming the
    trees where one does not (a sentence reads no cell that does not exist)."""
    have = [z for z in zeros.values() if _finite(z)]
    lacking = [tree for tree, z in zeros.items() if not _finite(z)]
    text = f"{label} {span_text(have, pct_text, '..')} %"
    return text + (f" (no value at e = 0 on {', '.join(lacking)})" if lacking else "")


def _finite(v) -> bool:
    return v is not None and math.isfinite(v)


def _held_part(trees: dict, name: str, answers: list, label: str) -> str:
    """'0.1..0.3 for LABEL (notes)': the e up to which consequence ``name`` holds on each
    tree, with its trees where it is not monotone or counts a second strike."""
    ups = [a["holds_up_to_e"] for a in answers]
    notes = [f"not monotone on {tree}" for tree, t in trees.items()
             if not t[name].get("monotone", True)] + [
        f"counting a second strike on {tree}" for tree, t in trees.items()
        if t[name].get("second_strike_from") is not None]
    return f"{span_text(ups, _inner)} for {label}" + (f" ({'; '.join(notes)})" if notes else "")
