"""What to measure first, in words: the Sobol part of a study's sensitivity study
(compare.studies.sobol) carried into the report's answer rows, each gap's verdict worded by
the stated rule (:func:`compare.studies.sobol.verdict_text`) and one sentence per tree
naming the measurement that matters most for the headline gaps (:func:`first_text`)."""

from __future__ import annotations

from ..studies.sobol import HEADLINE
from .base import input_name, share, sobol_verdict

#: The headline gaps as the sentence says them.
GAP_WORDS = {"gap.x_max": "x_max", "gap.energy_delivered": "the energy delivered",
             "gap.crown_peak": "the crown's peak",
             "gap.crown_peak_acceleration": "the crown's acceleration",
             "gap.peak_force": "the peak force"}


def with_sobol(answer: list[dict], studies) -> None:
    """Each ``answer`` row with ``sobol`` (its tree's Sobol analysis from the first of
    ``studies`` that has one, each output's verdict in words as ``text``) and
    ``measure_first`` (rows ranked, per headline gap the chosen inputs, ``sentence``);
    both {} without one. Changes the rows in place."""
    sens = next((s.study["sensitivity"] for s in studies
                 if s.study and (s.study.get("sensitivity") or {}).get("sobol")), {})
    for row in answer:
        tree = ((sens.get("trees") or {}).get(row["scenario"]) or {}).get("sobol") or {}
        if not tree.get("outputs"):
            row["sobol"], row["measure_first"] = {}, {}
            continue
        outputs = {k: {**v, "text": sobol_verdict(v)} for k, v in tree["outputs"].items()}
        row["sobol"] = {**tree, "outputs": outputs}
        said = first_text(row["sobol"])
        row["measure_first"] = {**tree["measure_first"], "said": said,
                                "sentence": f"{row['scenario']}: {said}"}


def _share(name: str, idx: dict) -> str:
    """An input and its ST with its interval: 'root compliance (ST 0.62 +- 0.23)'."""
    return f"{input_name(name)} (ST {share(idx['ST'])} +- {share(idx['ST_conf'])})"


def first_text(sobol: dict) -> str:
    """What one tree's ``sobol`` analysis says to measure first, per headline gap
    (compare.studies.sobol.HEADLINE): its settled leader and the measurement that fixes it
    ('the energy delivered: pad stiffness (ST 0.93 +- 0.30), by the contact force of one
    strike'), or, unsettled, the tied inputs ('x_max: unsettled between root compliance
    (ST 0.62 +- 0.23) and ...'), or that no input moves it."""
    parts = []
    for key in HEADLINE:
        out = sobol["outputs"].get(key)
        if out is None:
            continue
        first = sobol["measure_first"]["first"].get(key, {})
        gap = GAP_WORDS.get(key, key)
        if out.get("status") == "settled":
            n = first["inputs"][0]
            parts.append(f"{gap}: {_share(n, out['indices'][n])}, by "
                         f"{first['measurements'][0]}")
        elif out.get("status") == "unsettled":
            tied = [_share(n, out["indices"][n]) for n in first["inputs"]]
            names = tied[0] if len(tied) == 1 else \
                f"{', '.join(tied[:-1])} and {tied[-1]}"
            parts.append(f"{gap}: unsettled between {names}" if len(tied) > 1 else
                         f"{gap}: unsettled ({names} leads at N but not at N/2)")
        else:
            parts.append(f"{gap}: no input moves it")
    return "; ".join(parts) + "."


def in_short_text(answer: list[dict]) -> str | None:
    """The answer's third short item: what to measure first on each tree with a Sobol
    analysis (its N and evaluations said), or None when no row has one."""
    rows = [a for a in answer if a.get("measure_first")]
    if not rows:
        return None
    s = rows[0]["sobol"]
    counts = {a["sobol"]["evaluations"] for a in rows}
    evals = (f"{s['evaluations']} evaluations per tree" if len(counts) == 1 else
             "evaluations " + ", ".join(f"{a['scenario']} {a['sobol']['evaluations']}"
                                        for a in rows))
    return (f"What to measure first (the share of each gap's variance an unmeasured input "
            f"carries: Sobol ST with its {100 * s['conf_level']:.0f} % interval, N = "
            f"{s['n']}, {evals}; named only when its "
            f"interval clears every other's and it leads at N/2 too): "
            + " ".join(a["measure_first"]["sentence"] for a in rows))
