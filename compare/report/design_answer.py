"""The design answer of a report (issue 43): what a design study run beside the report
(``report --with-study design``, compare/report/validity/design_study.py) found for its tree, for
report.json's ``answer.design.<tree>`` and the page's first screen. Every sentence is the
study's own, read off its maps by the rule of docs/design-map.md; nothing is recomputed."""

from __future__ import annotations

from .study_kinds import StudyKind, register_kind

#: The pair whose figure the answer shows first: where to clamp against the pad (the two
#: choices a designer changes on a machine; the study's section shows all three maps).
FIRST_PAIR = ("a_over_l", "contact_duration")


#: The design map (compare/report/validity/design_study.py's design.json), rendered by design_body.
register_kind(StudyKind("design", "design.json", "pairs", "design_body", "d",
                        lambda d: {p.get("figure") for p in d["pairs"]}))


def design_answer(studies) -> dict:
    """tree -> its design answer, from each of ``studies`` (the report's study sections)
    holding a design study (``StudySection.kinds``): the operating point and the gaps
    there (fractions, continuum against the 1-DOF model), the sentence at the point, the
    nearest choice within both targets on each map, every sentence (its text, rule and what
    it read: the intervals ``within`` along an input, or the cell ``at``; the nearest
    choice's ``choice`` in the designer's units, compare.studies.design_choice), each map's axes,
    held inputs, gaps (``maps``, fractions by quantity, one row per y value) and figure
    (linked from the report's folder), and the tree as it is in the designer's units
    (``choice_at_point``, None when its own cell has no numbers)."""
    out = {}
    for section in studies:
        d = getattr(section, "kinds", {}).get("design", (None, None))[1]
        if d is None:
            continue
        maps = {_key(p["pair"]): {"x": p["x"], "y": p["y"], "held_at": p["held_at"],
                                  "maps": p["maps"], "figure": section.uri(p["figure"])}
                for p in d["pairs"]}
        nearest = {_key(p["pair"]): next((s for s in p["sentences"] if s["rule"] == "nearest"),
                                         None) for p in d["pairs"]}
        out[d["tree"]] = {
            "operating_point": d["operating_point"], "gaps_at_point": d["cell"],
            "levels": d["levels"], "at_point": d["at_point"],
            "choice_at_point": d.get("choice_at_point"),
            "nearest": {k: {"at": s["at"], "tolerances": s["tolerances"], "text": s["text"],
                            "choice": s.get("choice")}
                        for k, s in nearest.items() if s is not None},
            "sentences": [{"pair": _key(p["pair"]), **s} for p in d["pairs"]
                          for s in p["sentences"]],
            "first_pair": _key(FIRST_PAIR), "maps": maps,
            "anchor": section.anchor}
    return out


def in_short_text(design: dict) -> str:
    """The first screen's design item, "For a designer (TREE): ...": per tree of ``design``
    (:func:`design_answer`'s), the sentence at its operating point and the nearest choice
    within both targets on the :data:`FIRST_PAIR` map; "" without a design study."""
    if not design:
        return ""
    return "For a designer " + " ".join(f"({tree}): {tree_text(a)}"
                                        for tree, a in design.items())


def tree_text(answer: dict) -> str:
    """One tree's design answer (:func:`design_answer`'s value) in words: the sentence at its
    operating point and the nearest choice within both targets on the :data:`FIRST_PAIR`
    map."""
    first = answer["nearest"].get(answer["first_pair"])
    return answer["at_point"] + (f" {first['text']}" if first else "")


def _key(pair) -> str:
    return "-".join(pair)
