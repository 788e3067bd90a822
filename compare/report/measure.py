"""What to measure first, in words: the Sobol part of a study's sensitivity study
(compare.studies.sobol) carried into the report's answer rows, each gap's verdict worded by
the stated rule (:func:`compare.studies.sobol.verdict_text`) and one sentence per tree
naming the measurement that matters most for the headline gaps (:func:`first_text`)."""

from __future__ import annotations

from ..studies.sobol import HEADLINE
from .base import input_name, sobol_verdict

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


def _share(idx: dict) -> str:
    """An input's ST with its interval and the N/2 change: 'ST 0.62 +- 0.23, N/2 change
    -0.27'."""
    text = f"ST {idx['ST']:.2f} +- {idx['ST_conf']:.2f}"
    return text + (f", N/2 change {idx['ST_change']:+.2f}" if "ST_change" in idx else "")


def first_text(sobol: dict) -> str:
    """What one tree's ``sobol`` analysis says to measure first: per headline gap (compare.studies.sobol.HEADLINE) the
    measurement that fixes its settled leading input ('x_max: a static push test (root
    compliance, ST 0.62 +- 0.10)'), or, unsettled, the tied inputs' measurements ('one of
    ...'), or that no input moves it."""
    parts = []
    for key in HEADLINE:
        out = sobol["outputs"].get(key)
        if out is None:
            continue
        first = sobol["measure_first"]["first"].get(key, {})
        gap = GAP_WORDS.get(key, key)
        if out.get("status") == "settled":
            n = first["inputs"][0]
            parts.append(f"for {gap}, {first['measurements'][0]} ({input_name(n)}, "
                         f"{_share(out['indices'][n])}; settled)")
        elif out.get("status") == "unsettled":
            tied = "; ".join(f"{m} ({input_name(n)}, {_share(out['indices'][n])})"
                             for n, m in zip(first["inputs"], first["measurements"]))
            parts.append(f"for {gap}, unsettled between {tied}")
        else:
            parts.append(f"for {gap}, none (no input moves it)")
    return "; ".join(parts) + "."


def in_short_text(answer: list[dict]) -> str | None:
    """The answer's third short item: what to measure first on each tree with a Sobol
    analysis (its N and evaluations said), or None when no row has one."""
    rows = [a for a in answer if a.get("measure_first")]
    if not rows:
        return None
    s = rows[0]["sobol"]
    return (f"What to measure first (each measurement's share of the gap's variance over "
            f"the unmeasured inputs, Sobol total index ST with its "
            f"{100 * s['conf_level']:.0f} % interval, N = {s['n']}, {s['evaluations']} "
            f"evaluations per tree; settled only when the leading input's interval clears "
            f"every other's and it leads at N/2 too): "
            + " ".join(a["measure_first"]["sentence"] for a in rows))
