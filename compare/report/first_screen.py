"""The answer's first screen in short plain sentences (issue 53): one item per half of the
answer, each item's sentences generated from the report's numbers by the rule its function
states and linked to the section that backs it (``anchor``), and the answer table's ranges
over the unmeasured inputs with the words that say what they are (:func:`with_ranges`).

The counting rule the tests hold the items to (:func:`words`, :func:`sentences`): a word is
a whitespace-separated token with a letter or a digit in it ("+9", "x_max", "1-DOF"; not
"%" or "->"); a sentence ends at ". ", "; " or the item's end. Plain words: no estimator
names, no "N/2", no brackets of e (the sections below have them).
"""

from __future__ import annotations

import math
import re

from ..runs.rungs import RungKind
from .answer import ANSWER_METRICS, ANSWER_TERMS, pct_text, span_text
from .base import input_name

#: The prefix of a documented finding's name that says which assumption it is about
#: (compare/runs/tolerances.toml ``[[finding]] name``); the rest names the physical cause.
ASSUMPTION = "1-DOF assumption: "
#: The headline gaps of the measure-first item, as its sentences say them.
HEADLINE_WORDS = {"gap.x_max": "x_max", "gap.energy_delivered": "energy delivered"}


def words(text: str) -> list[str]:
    """The words of ``text`` by the module's counting rule."""
    return [w for w in text.split() if re.search(r"[A-Za-z0-9]", w)]


def sentences(text: str) -> list[str]:
    """The sentences of ``text`` by the module's counting rule (ends at '. ', '; ', end)."""
    return [s for s in re.split(r"(?<=[.;])\s+", text.strip()) if words(s)]


def _and(parts: list[str]) -> str:
    return parts[0] if len(parts) == 1 else f"{', '.join(parts[:-1])} and {parts[-1]}"


#: Each item's glossary term, whose one-line definition is the item's tooltip on the page.
TERMS = {"one_dof": "1-DOF model", "why": "gap", "small_e": "holds up to e",
         "measure_first": "what to measure first", "design": "design map"}


def first_screen(summary: dict, scen_sections) -> list[dict]:
    """The first screen's items from the page's ``summary`` (its answer rows, tolerance,
    small-e answers, findings and design answer) and the scenario sections
    ``scen_sections``, in order, each {key, anchor (the section backing it), term (its
    glossary term), text}: the 1-DOF gaps, why the largest gap of each tree, small e,
    what to measure first, the designer's choice (the last three only where the report has
    their part)."""
    why = why_text(summary["answer"], scen_sections)
    items = [("one_dof", "answer-one-dof", one_dof_text(summary["answer"])),
             ("why", "findings" if summary.get("findings") else "summary", why),
             ("small_e", "answer-small-e", small_e_text((summary.get("small_e") or {})
                                                        .get("trees") or {},
                                                        summary["answer_tolerance"])),
             ("measure_first", "answer-measure", measure_text(summary["answer"])),
             ("design", "answer-design", design_text(summary.get("design") or {}))]
    return [{"key": k, "anchor": a, "term": TERMS[k], "text": t} for k, a, t in items if t]


def one_dof_text(answer: list[dict]) -> str:
    """How far the paper's 1-DOF model is off the continuum on x_max and the energy
    delivered, the range over the ``answer`` rows' trees at their own pad and e; the trees
    without an answer and why (the tolerance is the table's and the small-e sentence's)."""
    rows = [a for a in answer if a.get("available")]
    text = ""
    if rows:
        x, en = (span_text([a["metrics"][m]["rel"] for a in rows], pct_text, " to ")
                 for m in ("x_max", "energy_delivered"))
        text = (f"The 1-DOF model is {x} % off the flexible trunk on x_max, {en} % on energy "
                "delivered.")
    missing = [f"{a['scenario']} ({a['why']})" for a in answer if not a.get("available")]
    if missing:
        text += (" " if text else "") + f"No 1-DOF answer for {'; '.join(missing)}."
    return text


def largest_gap(row: dict) -> str | None:
    """The metric of the answer table on which ``row``'s tree has its largest 1-DOF gap
    (the largest |continuum / 1-DOF - 1| of :data:`ANSWER_METRICS` with a finite value);
    None without one."""
    finite = [(abs(r["rel"]), m) for m, r in row["metrics"].items() if math.isfinite(r["rel"])]
    return max(finite)[1] if finite else None


def cause_of(section, metric: str) -> str | None:
    """The physical cause the report diagnoses for the continuum's gap on ``metric`` in the
    scenario ``section``: the documented finding its continuum (beam-kind) rung's check on
    that metric is recognised as (compare.runs.findings, from the tree's physics), less its
    :data:`ASSUMPTION` prefix; None when no finding is recognised."""
    beams = {r.rung.id for r in section.ladder.rungs if r.rung.kind == RungKind.BEAM}
    found = next((c.finding for c in section.checks
                  if c.rung in beams and c.metric == metric and c.finding), None)
    return found.removeprefix(ASSUMPTION) if found else None


def why_text(answer: list[dict], scen_sections) -> str:
    """Per tree of the ``answer`` rows (their sections ``scen_sections``) the physical cause
    of its largest 1-DOF gap (:func:`largest_gap`,
    :func:`cause_of`), one clause per cause naming its trees with the gap, in the trees'
    order, after "Largest gap: ": "A's peak force (-85 %) and B's energy delivered (+213 %):
    the pendulum meets the light clamp, not M_T; C's ..."; a tree whose gap no documented
    cause explains is said so."""
    sections = {s.ladder.name: s for s in scen_sections}
    groups: dict = {}
    for row in answer:
        m = largest_gap(row) if row.get("available") else None
        if m is None or row["scenario"] not in sections:
            continue
        said = ANSWER_TERMS.get(m, m)
        groups.setdefault(cause_of(sections[row["scenario"]], m), []).append(
            f"{row['scenario']}'s {said} ({pct_text(row['metrics'][m]['rel'])} %)")
    out = [f"{_and(trees)}: {cause}" if cause else
           f"{_and(trees)}: no documented cause matches (the ladder has the numbers)"
           for cause, trees in groups.items()]
    return f"Largest gap: {'; '.join(out)}." if out else ""


def _label(a: dict) -> str:
    """A small-e consequence's label without its parenthesis ('identified M_T (eq 44)' ->
    'identified M_T') or its model prefix ('1-DOF trunk: x_max' -> 'x_max')."""
    return re.sub(r"\s*\([^)]*\)", "", a["label"]).split(": ", 1)[-1]


def small_e_text(trees: dict, tol: float) -> str:
    """The small-e half by the rule: a consequence *holds* to the smallest e over the trees
    up to which it stays within ``tol`` of the exact result; those holding at every tree's
    own e in one sentence, those off at some tree's own e in the next, those off already
    at e = 0 (not small-e effects; the 1-DOF trunk's gaps among them) in the last; a
    consequence with no value at e = 0 (or at any e) on any tree: no verdict."""
    if not trees:
        return ""
    first = next(iter(trees.values()))
    keep, fail, off, trunk, none = [], [], [], [], []
    for name, a0 in first.items():
        answers = [t[name] for t in trees.values()]
        if all(a["bracket"] is None and a["holds_up_to_e"] == 0.0 for a in answers):
            finite = [a["error_at_zero"] for a in answers if a["error_at_zero"] is not None
                      and math.isfinite(a["error_at_zero"])]
            if not finite:
                none.append(_label(a0))
            elif a0.get("model") == "continuum":
                trunk.append(_label(a0))
            else:
                off.append(_label(a0))
            continue
        up = min(a["holds_up_to_e"] for a in answers)
        if all(a["holds_up_to_e"] >= a["e"] for a in answers):
            keep.append(f"{math.floor(100 * up + 1e-6) / 100:.2f} for {_label(a0)}")
        else:
            fail.append(_label(a0))
    out = []
    if keep:
        out.append(f"Small e holds within {100 * tol:.0f} % up to e = {_and(keep)}.")
    if fail:
        whose = "some tree's" if len(trees) > 1 else "the tree's"
        out.append(f"{'It' if keep else 'Small e'} fails at {whose} own e for {_and(fail)}.")
    if off or trunk:
        off = off + (["both 1-DOF gaps" if len(trunk) == 2 else "1-DOF gaps"] if trunk else [])
        out.append(f"Off even at e = 0, not from e: {_and(off)}.")
    if none:
        out.append(f"No verdict on {_and(none)}: no value at e = 0.")
    return " ".join(out)


def measure_text(answer: list[dict]) -> str:
    """Per headline gap, the input to measure first on each tree of the ``answer`` rows
    (their ``measure_first``): its settled leader by the
    variance-share rule (compare.studies.sobol.verdict), trees with the same leader named
    together; trees where no input leads yet said so. "" without a Sobol analysis."""
    rows = [a for a in answer if (a.get("measure_first") or {}).get("first")]
    if rows and all(f["status"] != "settled" for a in rows
                    for f in a["measure_first"]["first"].values()):
        gaps = _and([g for k, g in HEADLINE_WORDS.items()
                     if any(k in a["measure_first"]["first"] for a in rows)])
        return (f"Measure first: no input leads yet for {gaps} on "
                f"{_and([a['scenario'] for a in rows])}.")
    out = []
    for key, gap in HEADLINE_WORDS.items():
        leads: dict = {}
        for a in rows:
            first = a["measure_first"]["first"].get(key)
            if first is None:
                continue
            lead = input_name(first["inputs"][0]) if first["status"] == "settled" else None
            leads.setdefault(lead, []).append(a["scenario"])
        if not leads:
            continue
        named = [f"{lead} on {_and(trees)}" for lead, trees in leads.items() if lead]
        open_ = leads.get(None)
        lead = "Measure first, for" if not out else "For"
        parts = named
        parts += [f"undecided on {_and(open_)}"] if open_ else []
        out.append(f"{lead} {gap}: {'; '.join(parts)}.")
    return " ".join(out)


def design_text(design: dict) -> str:
    """Per tree with a design study: the nearest choice on its first map that keeps the 1-DOF
    model within both targets, in the designer's units, or that none on the map does."""
    out = []
    for tree, a in design.items():
        levels = a["levels"]
        first = (a.get("nearest") or {}).get(a["first_pair"])
        c = (first or {}).get("choice")
        target = f"within {100 * levels[0]:.0f} % on x_max, {100 * levels[1]:.0f} % on energy"
        if c:
            out.append(f"Design for {tree}: clamp at {c['clamp_height']:.3g} m, a "
                       f"{c['impactor_mass']:.3g} kg impactor, a "
                       f"{1e3 * c['contact_duration']:.3g} ms pad: {target}.")
        else:
            out.append(f"Design for {tree}: no clamp and pad on the map keeps "
                       f"it {target}.")
    return " ".join(out)


def with_ranges(answer: list[dict]) -> dict:
    """The answer table's ranges over the unmeasured inputs, one kind for the whole table:
    each row's ``range`` {metric: {low, high, bar}} from the Sobol design's evaluations when
    every answered row has one, else the Morris screening's, else none; ``bar``: where the
    range and the tree's own value sit on the column's common scale (percent of its width;
    the scale spans every row's range, value and 0). Returns the table's {kind, evaluations
    per tree, inputs (the free inputs in words), held (trees holding measured inputs)}, or
    {} without a range. Changes the rows in place."""
    rows = [a for a in answer if a.get("available")]
    if rows and all((a.get("sobol") or {}).get("outputs") for a in rows):
        kind = "sobol"
        part = {a["scenario"]: a["sobol"]["outputs"] for a in rows}
        evals = {a["scenario"]: a["sobol"]["evaluations"] for a in rows}
        names = [n for a in rows for n in a["sobol"]["names"]]
    elif rows and all(a.get("sensitivity") for a in rows):
        kind = "morris"
        part = {a["scenario"]: a["sensitivity"] for a in rows}
        evals = {a["scenario"]: a["sensitivity_design"].get("evaluations") for a in rows}
        names = [n for a in rows for n in next(iter(a["sensitivity"].values()))["indices"]]
    else:
        return {}
    for m, *_ in ANSWER_METRICS:
        cells = {t: p.get(f"gap.{m}") for t, p in part.items()}
        cells = {t: c for t, c in cells.items() if c and "low" in c}
        values = [v for t, c in cells.items() for v in (c["low"], c["high"])] + [0.0] + [
            a["metrics"][m]["rel"] for a in rows if math.isfinite(a["metrics"][m]["rel"])]
        lo, hi = min(values), max(values)
        for a in rows:
            c = cells.get(a["scenario"])
            if c is None:
                continue
            at = a["metrics"][m]["rel"]
            a.setdefault("range", {})[m] = {"low": c["low"], "high": c["high"],
                                            "bar": _bar(c["low"], c["high"], at, lo, hi)}
    held = [a["scenario"] for a in rows if (a.get("sensitivity_design") or {}).get("held")]
    return {"kind": kind, "evaluations": sorted(set(evals.values()), key=str),
            "inputs": _and([input_name(n) for n in dict.fromkeys(names)]), "held": held}


def _bar(low: float, high: float, at: float, lo: float, hi: float) -> dict:
    """Percent positions on [lo, hi]: the range's left end and width, the value and 0."""
    span = (hi - lo) or 1.0

    def pos(v):
        return round(100 * (v - lo) / span, 1)

    return {"left": pos(low), "width": max(round(pos(high) - pos(low), 1), 0.5),
            "at": pos(at) if math.isfinite(at) else None, "zero": pos(0.0)}
