"""docs/glossary.md (issue 26 item 6): every term of the report's vocabulary has an entry,
every equation the report and its code cite is restated there, and the README links it on
its first screen."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
GLOSSARY = ROOT / "docs" / "glossary.md"

#: The words the report (compare/report/templates, its findings and reasons) uses that a
#: newcomer has to look up (issue 26: "words used before they are explained").
REPORT_TERMS = (
    "1-DOF model", "SDOF", "the paper's model", "Newton impacts", "ladder", "rung", "step",
    "continuum", "Euler-Bernoulli", "Timoshenko", "chain", "flex", "segments", "elements",
    "engine numerics", "discretisation", "pendulum linearisation", "full pendulum",
    "billet", "backend", "pad", "k_c", "c_c", "contact duration", "collision duration",
    "soft contact", "e\\*", "calibration", "restitution convention",
    "effective mass at the clamp", "pad damping ratio", "first contact", "chattering",
    "contact episodes", "impact process", "moving together", "common velocity", "tau",
    "A_x", "impact loss", "energy transferred", "rebound angle", "energy delivered",
    "contact dissipation", "rebound energy", "whole-event metrics", "impulse", "peak force",
    "crown", "crown peak", "crown acceleration", "means over t_c", "ledger",
    "ledger residual", "gap", "answer table", "M_T", "K_T", "C_T", "static mode shape",
    "dynamic mass", "omega_n", "xi", "b", "u1", "crown ratio", "root spring", "root share",
    "truth", "the paper's procedure", "readings", "full-record fit", "explained",
    "not fixed", "identifiable", "band", "Not compared", "sweep", "study", "validity map",
    "dominating rung", "contact scan", "crossing", "sensitivity", "mu\\*",
    "Sobol indices", "ST", "N/2 change", "settled", "unsettled", "what to measure first",
    "speed-accuracy curve", "range over the unmeasured inputs", "design map",
    "designer's choice")


def _bold() -> list[str]:
    return re.findall(r"\*\*((?:\\\*|[^*])+?)\*\*", GLOSSARY.read_text())


def _has_entry(term: str, bold: list[str]) -> bool:
    return any(re.search(rf"(?<![\w*]){re.escape(term)}(?![\w*])", b) for b in bold)


def test_every_report_term_has_an_entry():
    bold = _bold()
    missing = [t for t in REPORT_TERMS if not _has_entry(t, bold)]
    assert not missing, f"docs/glossary.md has no entry for {missing}"


def glossary_problems(metrics) -> list[str]:
    """What the glossary lacks for the metric declarations ``metrics``
    (analytic.metrics.METRICS): an entry for each one's label, and each equation it
    declares restated."""
    bold, restated, out = _bold(), _restated(), []
    for m in metrics:
        if not _has_entry(m.label, bold):
            out.append(f"{m.name}: no glossary entry {m.label!r}")
        out += [f"{m.name}: eq {c} not restated" for c in sorted(_cited(m.equation))
                if not _covered(c, restated)]
    return out


def test_every_metric_and_rung_kind_of_the_report_has_an_entry():
    from treeimpact.analytic.metrics import METRICS
    from treeimpact.compare.runs.rungs import RungKind

    text = GLOSSARY.read_text()
    assert glossary_problems(METRICS) == []
    letters = [k.letter for k in RungKind if f" {k.letter} " not in text.split("## Models")[1]]
    assert not letters, f"rung letters the maps print but the glossary does not: {letters}"


def _cited(text: str) -> set[str]:
    """The equations a text cites: 'eq 56' -> {'56'}, 'eqs 12-35' -> {'12-35'},
    'eqs 21, 54' -> {'21', '54'}."""
    out = set()
    for m in re.finditer(r"\beqs? (\d+(?:\s*[-,]\s*\d+)*)", text):
        for part in re.split(r"\s*,\s*", m[1]):
            out.add(re.sub(r"\s*-\s*", "-", part))
    return out


def _restated() -> set[str]:
    section = GLOSSARY.read_text().split("## The paper's equations")[1].split("\n## ")[0]
    return {m for m in re.findall(r"^- \*\*eqs? ([\d-]+)\*\*", section, flags=re.M)}


def _covered(cited: str, restated: set[str]) -> bool:
    """Whether the glossary restates a ``cited`` equation: itself, or a range's ends."""
    return cited in restated or ("-" in cited and all(e in restated
                                                       for e in cited.split("-")))


def test_every_equation_the_report_cites_is_restated():
    sources = [*sorted((ROOT / "compare" / "report" / "templates").glob("*.j2")),
               *sorted((ROOT / "compare").rglob("*.py")), ROOT / "compare" / "runs" / "tolerances.toml"]
    cited = set().union(*(_cited(p.read_text()) for p in sources if "test_" not in p.name))
    restated = _restated()
    assert {"56", "44", "12-35"} <= cited
    missing = sorted(c for c in cited if not _covered(c, restated))
    assert not missing, f"docs/glossary.md does not restate eq(s) {missing}"


@pytest.mark.parametrize("text, cited", [("eq 56 and eqs 12-35", {"56", "12-35"}),
                                         ("(eqs 21, 54)", {"21", "54"})])
def test_citations_are_read(text, cited):
    assert _cited(text) == cited


def test_the_readme_links_the_glossary_on_its_first_screen():
    first_screen = "\n".join((ROOT / "README.md").read_text().splitlines()[:25])
    assert "(docs/glossary.md)" in first_screen


def test_every_tooltip_the_report_asks_for_is_a_glossary_entry():
    """The page's tooltips (issue 53 item 4) come from one lookup of the glossary
    (compare/report/glossary.py): every term a template passes to ``|tip`` and every term of
    the first screen's items and answer columns has its entry, and its tooltip is that
    entry's first definition on one line."""
    from treeimpact.compare.report.answer import ANSWER_TERMS
    from treeimpact.compare.report.first_screen import TERMS
    from treeimpact.compare.report.glossary import LINE, entries, tip

    templates = "".join(p.read_text() for p in
                        (ROOT / "compare" / "report" / "templates").glob("*.j2"))
    asked = set(re.findall(r"'([^']+)'\|tip", templates)) | set(TERMS.values()) | set(
        ANSWER_TERMS.values())
    assert {"e", "x_max", "full-record fit"} <= asked
    bold = _bold()
    for term in sorted(asked):
        assert _has_entry(term, bold), term
        line = tip(term)
        assert line.startswith(f"{term}: ") and "\n" not in line
        assert len(line) <= len(term) + 2 + LINE + 4  # "term: " and the cut's " ..."
    assert tip("x_max") == ("x_max: the largest trunk displacement at the clamp and its "
                            "time")  # the entry's text up to its next term
    with pytest.raises(KeyError, match="no entry for 'no such term'"):
        tip("no such term")
    assert len(entries()) > len(REPORT_TERMS)
