"""The answer in one minute (issue 53): the first screen's items rendered in both pages for
the shipped trees and for a user's tree unlike them (a light pendulum that bounces off after
one impact), counted by compare.report.first_screen's rule (a word: a whitespace token with
a letter or digit; a sentence ends at '. ', '; ' or the item's end); the table's heads in
plain words or with their glossary tooltip; the range under each cell named once; and the
cause of each tree's largest 1-DOF gap by the stated rule, checked against the findings
recognised from the tree's physics."""

from __future__ import annotations

import dataclasses
import html as _html
import importlib
import math
import re

import pytest

from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.compare.report import _page_summary, build_sections
from treeimpact.compare.report.base import environment, input_name
from treeimpact.compare.report.glossary import entries
from treeimpact.compare.runs.cache import RunCache

F = importlib.import_module("treeimpact.compare.report.first_screen")

#: The issue's budget: "at most about 150 words of answer, each sentence at most about 25".
MAX_WORDS, MAX_SENTENCE = 150, 25
#: Words the first screen leaves to the sections below (estimator names, the N/2 check, a
#: crossing's bracket of e such as "0.256-0.378", SALib's "+-").
NOT_PLAIN = re.compile(r"Sobol|Morris|\bST\b|mu\*|N/2|\+-|\d\.\d+-\d\.\d+")
#: Sobol base samples of the test's study: the smallest with an N/2 check (sobol.convergence).
SOBOL_N = 4


def _light_pendulum():
    """A user's tree unlike the shipped ones: central-leader struck by a 12 kg pendulum at
    e = 0.5, which bounces off after one impact (m / M_T = 0.11; no moving together)."""
    scen = load_scenario("central-leader")
    return dataclasses.replace(scen, name="light-pendulum",
                               impactor=dataclasses.replace(scen.impactor, mass=12.0),
                               contact=dataclasses.replace(scen.contact, restitution=0.5))


class _Study:
    """A study section as the answer reads it (``.study``): the sensitivity part of a real
    Sobol design of :data:`SOBOL_N` per tree run now on the sweep machinery."""

    def __init__(self, scens, folder):
        from treeimpact.compare.studies.sobol import analyse_sobol, sobol_sweep
        from treeimpact.compare.studies.study_inputs import free_inputs
        from treeimpact.compare.studies.sweep.run import run_sweeps

        trees = {}
        for s in scens:
            (res,) = run_sweeps([sobol_sweep(s, folder / s.name, SOBOL_N)], workers=0,
                                progress=False)
            trees[s.name] = {"sobol": analyse_sobol(res.table, SOBOL_N,
                                                    names=list(free_inputs(s)))}
        self.study = {"sensitivity": {"sobol": SOBOL_N, "trees": trees}}


def _pages(scens, folder) -> tuple[dict, str, str, list]:
    """(summary, report.md, report.html, scenario sections) of ``scens`` with the study."""
    sections = build_sections(scens, runs=RunCache(), engines=("no-such-engine",),
                              segments=4)
    sections["studies"].append(_Study(scens, folder))
    summary = _page_summary(sections)
    pages = [environment().get_template(f"report.{fmt}.j2").render(
        sections=[], parts=[], generated="now", summary=summary) for fmt in ("md", "html")]
    return summary, *pages, sections["scenarios"]


@pytest.fixture(scope="module", params=["shipped", "light-pendulum"])
def pages(request, tmp_path_factory):
    from treeimpact.compare.runs.cache import resolve_scenario

    scens = ([resolve_scenario(n) for n in ("central-leader", "open-center", "realistic-crown")]
             if request.param == "shipped" else [_light_pendulum()])
    return _pages(scens, tmp_path_factory.mktemp(request.param))


def _answer_md(md: str) -> list[str]:
    """The items of the md page's answer, as read: its numbered lines, links taken out."""
    part = md.split("## The answer", 1)[1].split('<a id="answer-one-dof">', 1)[0]
    items = re.findall(r"^\d+\. \[(.*)\]\(#[\w-]+\)$", part, flags=re.M)
    return items


def _answer_html(page: str) -> list[str]:
    part = page.split('<h2 id="answer">', 1)[1].split('<h3 id="answer-one-dof">', 1)[0]
    return [_html.unescape(re.sub(r"<[^>]+>", "", li))
            for li in re.findall(r"<li>(.*?)</li>", part, flags=re.S)]


def test_the_answer_reads_in_a_minute(pages):
    """Both pages show the same items; at most MAX_WORDS words, every sentence at most
    MAX_SENTENCE, none of the sections' technical notation."""
    summary, md, page, _ = pages
    items = _answer_md(md)
    assert items == _answer_html(page) == [i["text"] for i in summary["first_screen"]]
    text = " ".join(items)
    assert len(F.words(text)) <= MAX_WORDS, (len(F.words(text)), text)
    long = [s for s in F.sentences(text) if len(F.words(s)) > MAX_SENTENCE]
    assert not long, long
    assert not NOT_PLAIN.search(text), NOT_PLAIN.search(text)
    assert {"one_dof", "why", "small_e", "measure_first"} <= {i["key"] for i in
                                                              summary["first_screen"]}


def test_each_item_links_the_section_that_backs_it(pages):
    summary, md, page, _ = pages
    for item in summary["first_screen"]:
        assert f'<li><a href="#{item["anchor"]}" title="' in page
        assert f'id="{item["anchor"]}"' in page and f'<a id="{item["anchor"]}"></a>' in md \
            or item["anchor"] == "summary" and 'id="summary"' in page
        assert entries()[item["term"]].startswith(item["term"])  # its tooltip's entry


def test_the_1_dof_sentence_quotes_the_table(pages):
    """The x_max and energy ranges of the first item are the table's cells, rounded."""
    summary, *_ = pages
    rows = [a for a in summary["answer"] if a["available"]]
    text = summary["first_screen"][0]["text"]
    for m in ("x_max", "energy_delivered"):
        values = sorted(round(100 * a["metrics"][m]["rel"]) for a in rows)
        shown = f"{values[0]:+d}" + (f" to {values[-1]:+d}" if values[-1] != values[0] else "")
        assert f"{shown} %" in text, (m, shown, text)


def test_the_largest_gap_has_its_cause_from_the_trees_physics(pages):
    """Per tree: the metric named is the one of largest |gap| (from the ladder's rungs:
    the continuum against the paper's model, the soft SDOF where it has no value), and the
    cause is the finding compare.runs.findings recognises for that metric from the tree's
    physical quantities (loss_ratio, crown_factor, e), never its name."""
    from treeimpact.compare.report.answer import ANSWER_METRICS, ANSWER_TERMS
    from treeimpact.compare.runs.findings import TreePhysics, finding_for
    from treeimpact.compare.runs.rungs import RungKind

    summary, _, _, sections = pages
    why = next(i["text"] for i in summary["first_screen"] if i["key"] == "why")
    for s in sections:
        L = s.ladder
        beam = next(r for r in L.rungs if r.rung.kind == RungKind.BEAM and r.ok)
        soft = next(r for r in L.rungs if r.rung.kind == RungKind.CONTACT and r.ok)
        gaps = {}
        for m, *_ in ANSWER_METRICS:
            v0 = L.rungs[0].values.get(m, math.nan)
            v0 = v0 if math.isfinite(v0) else soft.values[m]
            gaps[m] = beam.values[m] / v0 - 1.0
        m = max(gaps, key=lambda k: abs(gaps[k]))
        said = f"{L.name}'s {ANSWER_TERMS[m]} ({100 * gaps[m]:+.0f} %)"
        assert said in why, (said, why)
        found = finding_for(L.tolerances, TreePhysics.of(L.scenario), RungKind.BEAM, m,
                            beam.rung.id)
        assert why.startswith("Largest gap: ")
        clause = next(x for x in why.removeprefix("Largest gap: ").rstrip(".").split("; ")
                      if said in x)
        if found is None:
            assert clause.endswith("no documented cause matches (the ladder has the numbers)")
        else:
            assert clause.endswith(": " + found["name"].removeprefix(F.ASSUMPTION)), clause


def test_the_headline_number_is_the_trees_own_and_its_range_says_what_it_is(pages):
    """Each cell's bold number is the gap at the tree's stated inputs; the range under it
    is the Sobol design's lowest to highest over the tree's free inputs, said once for the
    table with every input named; the bar's ends and tick sit where those numbers are on
    the column's common scale."""
    summary, md, page, _ = pages
    ranges = summary["answer_ranges"]
    assert ranges["kind"] == "sobol"
    caption = page.split('<h3 id="answer-one-dof">', 1)[1].split("<table", 1)[0]
    names = {n for a in summary["answer"] for n in a["sobol"]["names"]}
    assert all(input_name(n) in caption for n in names)
    assert caption.count("range over the unmeasured inputs</span>, the lowest to the highest") == 1
    assert "Morris" not in caption and "a range, not a probability interval" in caption
    for a in summary["answer"]:
        for m, r in a["range"].items():
            out = a["sobol"]["outputs"][f"gap.{m}"]
            assert (r["low"], r["high"]) == (out["low"], out["high"])
            lo = min(min(b["range"][m]["low"] for b in summary["answer"]), 0.0,
                     min(b["metrics"][m]["rel"] for b in summary["answer"]))
            hi = max(max(b["range"][m]["high"] for b in summary["answer"]), 0.0,
                     max(b["metrics"][m]["rel"] for b in summary["answer"]))
            at = 100 * (a["metrics"][m]["rel"] - lo) / (hi - lo)
            assert r["bar"]["at"] == pytest.approx(at, abs=0.05)  # printed to 0.1 %
            assert r["bar"]["left"] == pytest.approx(100 * (r["low"] - lo) / (hi - lo), abs=0.05)
            assert f'{100 * r["low"]:+.0f} to {100 * r["high"]:+.0f} %' in md


#: A head term a newcomer has to look up: a paper symbol or code name (an underscore, a
#: lone letter such as e, "1-DOF"), an abbreviation in capitals, or a starred mean.
SYMBOLIC = re.compile(r"_|\*|\bDOF\b|(?<![\w'])[A-Za-z](?![\w'])|\b[A-Z]{2,}\b")


def test_every_head_on_the_first_screen_is_plain_or_has_its_glossary_tooltip(pages):
    _, _, page, _ = pages
    part = page.split('<h2 id="answer">', 1)[1].split('<h3 id="answer-small-e">', 1)[0]
    heads = re.findall(r"<th([^>]*)>(.*?)</th>", part, flags=re.S)
    assert len(heads) >= 10
    tips = set(entries().values())
    for attrs, text in heads:
        words = _html.unescape(re.sub(r"<[^>]+>", " ", text))
        title = re.search(r'title="([^"]*)"', attrs)
        if title:
            assert _html.unescape(title[1]) in tips, (words, title[1])
        else:
            assert not SYMBOLIC.search(words), f"head {words!r} needs a glossary tooltip"


@pytest.mark.parametrize("text, n_words, lengths", [
    ("The model is +9 to +46 % off -> x_max; fine. Next one.", 11, [8, 1, 2]),
    ("Largest gap: a's x_max (+93 %): the pendulum meets the light clamp, not M_T.", 13, [13]),
])
def test_the_counting_rule(text, n_words, lengths):
    assert len(F.words(text)) == n_words
    assert [len(F.words(s)) for s in F.sentences(text)] == lengths


def test_a_tree_that_bounces_off_gets_its_whole_report(tmp_path):
    """The light pendulum has no moving together, so no ledger at T0 and no ledger figure:
    its scenario section renders without one (the page crashed on the missing figure), and
    the written pages' first screen is report.json's."""
    import json

    from treeimpact.compare.report import write_report

    paths = write_report(tmp_path, scenarios=[_light_pendulum()], runs=RunCache(),
                         engines=("no-such-engine",), segments=4)
    data = json.loads(paths["json"].read_text())
    texts = [i["text"] for i in data["answer"]["first_screen"]]
    assert _answer_md(paths["md"].read_text()) == texts
    assert _answer_html(paths["html"].read_text()) == texts
    page = paths["html"].read_text()
    assert "<h3>Energy ledger at T0</h3>" in page and 'alt="energy ledger"' not in page
