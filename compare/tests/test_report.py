"""The report: three files and its figures beside them, every number in the JSON, skips with
their reasons, figures with units on every axis, study directories as sections."""

from __future__ import annotations

import base64
import json
import math
import re

import pytest

from treeimpact.analytic.impact.simulate import simulate
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.analytic.paper.reproduction import reproduce
from treeimpact.compare.report import write_report
from treeimpact.compare.runs.cache import RunCache


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    """One scenario, the analytic rungs plus an engine that does not exist here."""
    out = tmp_path_factory.mktemp("report")
    cache = RunCache()
    paths = write_report(out, scenarios=["open-center"], runs=cache,
                         engines=("no-such-engine",), segments=4)
    return paths, cache


def test_three_files_and_figures_beside_a_page_under_1_mb(report):
    paths, _ = report
    assert set(paths) == {"html", "md", "json"}
    html = paths["html"].read_text()
    assert "<html" in html and html.rstrip().endswith("</html>")
    assert len(html.encode()) < 1_000_000
    srcs = re.findall(r'src="([^"]+)"', html)
    assert len(srcs) >= 5  # displacement, force, sequence, energy, identification
    assert all(s.startswith("figures/") and s.endswith(".png") for s in srcs)
    page_dir = paths["html"].parent
    for s in srcs:
        assert (page_dir / s).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", s
    assert not re.search(r'(href|src)="(https?:)?//', html)  # nothing fetched from outside
    md = paths["md"].read_text()
    assert set(re.findall(r"\]\((figures/[^)]+)\)", md)) == set(srcs)  # the same figures


def test_every_section_is_collapsible_and_tables_sort(report):
    paths, _ = report
    html = paths["html"].read_text()
    assert html.count('<details class="section"') == 4  # paper, open-center, trunks, runs
    assert 'id="scenario-open-center"' in html and "querySelectorAll(\"table\")" in html


def test_json_holds_the_numbers_of_the_page(report):
    paths, _ = report
    data = json.loads(paths["json"].read_text())
    scen = data["scenarios"]["open-center"]
    exact = simulate(load_scenario("open-center"))  # independent run
    rung1 = scen["rungs"][0]
    assert rung1["id"] == "analytic" and rung1["status"] == "ok"
    assert rung1["values"]["V"] == pytest.approx(exact.metrics["V"], rel=1e-12)
    assert scen["inputs"]["trunk"]["diameter"] == 0.142
    checks = scen["checks"]
    assert {"value", "reference_value", "rel_diff", "tolerance", "verdict", "reason"} <= set(
        checks[0])
    # Table 1, printed and recomputed, as analytic.paper.reproduction gives them
    ref = reproduce(with_restitution_estimates=False)
    assert data["paper"]["trees"]["open-center"]["M_T"]["recomputed"] == pytest.approx(
        ref["trees"]["open-center"]["M_T"]["recomputed"])
    assert len(data["paper"]["discrepancies"]) == len(ref["discrepancies"])
    # the energy ledger at T0 closes to the initial energy
    led = scen["energy_ledger"]["analytic"]
    assert abs(led["residual"]) < 1e-9
    html = paths["html"].read_text()
    assert f"{rung1['values']['x_max']:.4g}" in html


def test_skipped_rungs_are_listed_with_their_reason_everywhere(report):
    paths, cache = report
    reason = next(r.reason for r in cache if r.backend == "no-such-engine")
    assert "no-such-engine" in reason
    data = json.loads(paths["json"].read_text())
    not_run = data["summary"]["not_run"]
    assert {r["rung"] for r in not_run} == {"no-such-engine-sdof", "no-such-engine-chain4",
                                            "no-such-engine-chain4-full"}
    assert all(r["reason"] == reason for r in not_run)
    for fmt in ("html", "md"):
        text = paths[fmt].read_text()
        assert text.count("no-such-engine-chain4-full") >= 2
        assert reason.replace("'", "&#39;") in text or reason in text


def test_findings_are_flagged_in_the_page(report):
    paths, _ = report
    data = json.loads(paths["json"].read_text())
    found = [f for f in data["summary"]["findings"] if f["scenario"] == "open-center"]
    # the identification's finding on the Newton rung; the 1-DOF assumption's on the beam
    # rung (x_max, t_xmax, energies, crown motion), which needs no engine
    assert {f["finding"] for f in found} == {
        "e too large for the identification",
        "1-DOF assumption: the pendulum meets the light clamp, not M_T",
        "1-DOF assumption: the crown does not follow the static shape"}
    assert {(f["rung"], f["metric"]) for f in found if f["finding"].startswith("1-DOF")} == {
        ("beam", "x_max"), ("beam", "t_xmax"), ("beam", "energy_transferred"),
        ("beam", "energy_delivered"), ("beam", "contact_dissipation"), ("beam", "peak_force"),
        ("beam", "crown_peak"), ("beam", "crown_peak_acceleration")}
    assert all(f["verdict"] == "finding" for f in found)
    assert "e too large for the identification" in paths["html"].read_text()


def test_every_axis_has_a_unit(tmp_path):
    """Every figure of a scenario's section and the answer's (the small-e curves, the
    contact scan)."""
    from treeimpact.compare.report.answer_figures import small_e_figure
    from treeimpact.compare.report.scenario import ScenarioSection
    from treeimpact.compare.report.summary_figures import contact_scan_figure
    from treeimpact.compare.studies.small_e import small_e_answer, small_e_sweep
    from treeimpact.compare.studies.sweep.run import run_sweeps

    figs = []

    def keep(fig, stem):
        figs.append(fig)
        return f"figures/{stem}.png"

    scen = load_scenario("central-leader")
    (e_sweep,) = run_sweeps([small_e_sweep(scen, tmp_path)], workers=0)
    # fits=[]: the section draws from its ladder and ledgers, not the record fits (the same
    # PNG bytes with them made; 3 CPU-s less)
    ScenarioSection.from_runs(scen, RunCache(), e_sweep.table, engines=(), figure_sink=keep,
                              fits=[])
    assert len(figs) == 4  # displacement, force, sequence, energy
    figs.append(small_e_figure({scen.name: small_e_answer(scen, e_sweep.table)}, 0.05))
    scan = {"durations": [5e-4, 1e-3], "gaps": {"x_max": [0.1, 0.02]}, "tolerance": 0.05,
            "shortest": {"x_max": 1e-3}, "failed": [],
            "contact": {"soft": {"first_contact_duration": [3e-4, 9e-4]}}}
    figs.append(contact_scan_figure({scen.name: scan}, {scen.name: 5e-4}))
    unit = re.compile(r"\((ms|mm|kN|N s|m/s|J|%|1|s|m)\)")
    for fig in figs:
        for ax in fig.axes:
            if ax.get_xlabel():  # shared axes keep the label on one of them
                assert unit.search(ax.get_xlabel()), ax.get_xlabel()
            assert unit.search(ax.get_ylabel()) or not ax.get_ylabel(), ax.get_ylabel()
        assert any(ax.get_ylabel() for ax in fig.axes)


def test_study_directories_become_sections(tmp_path):
    study = tmp_path / "validity-map"
    study.mkdir()
    png = base64.b64decode(
        "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mP8z8BQDwAEhQGAhKmMIQAAAABJRU5ErkJggg==")
    (study / "map.png").write_bytes(png)
    (study / "summary.json").write_text(json.dumps({"cells": 4}))
    (study / "summary.md").write_text("Where the 1-DOF model holds.")
    paths = write_report(tmp_path / "out", scenarios=["open-center"], study_dirs=[study],
                         runs=RunCache(), engines=())
    html = paths["html"].read_text()
    assert "Study: validity-map" in html and "Where the 1-DOF model holds." in html
    assert 'src="../validity-map/map.png"' in html  # linked where it is, from the page
    assert (tmp_path / "out" / "../validity-map/map.png").read_bytes() == png
    assert "](../validity-map/map.png)" in paths["md"].read_text()
    data = json.loads(paths["json"].read_text())
    assert data["studies"][0]["data"]["summary.json"] == {"cells": 4}


def test_json_has_no_nan(report):
    paths, _ = report
    text = paths["json"].read_text()
    assert "NaN" not in text and "Infinity" not in text
    json.loads(text)
    assert math.isfinite(json.loads(text)["runs"]["wall_s"]["total"])


def test_each_engine_draws_its_rungs_in_its_own_three_shades():
    from treeimpact.compare.report.figures import rung_style
    from treeimpact.compare.runs.backends import BACKENDS, ENGINES

    class Rung:
        def __init__(self, backend, kind):
            self.backend, self.kind = backend, kind

    colours = {(e, k): rung_style(Rung(e, k))["color"] for e in ENGINES
               for k in ("engine", "chain", "pendulum")}
    assert len(set(colours.values())) == 3 * len(ENGINES)  # no two rungs share a colour
    assert all(colours[(e, "engine")] == BACKENDS[e].shades[0] for e in ENGINES)
    # an engine's own elastic rod (MuJoCo's flex) has a fourth shade of its own
    from treeimpact.compare.runs.rungs import offers_rod

    rods = {e: rung_style(Rung(e, "rod")) for e in ENGINES if offers_rod(e)}
    assert rods and not {r["color"] for r in rods.values()} & set(colours.values())


def test_the_answer_leads_with_whole_event_metrics_and_whether_the_fit_explains(report,
                                                                               run_cache):
    """The answer is the continuum (beam rung) against rung 1, the ladder's own numbers; it
    needs no engine (the fixture's engine does not exist); the engines' chains agree with it."""
    from treeimpact.compare.report.answer import one_dof_answer
    from treeimpact.compare.report.scenario import ScenarioSection

    paths, _ = report
    data = json.loads(paths["json"].read_text())
    (fixture,) = data["answer"]["one_dof"]
    assert fixture["scenario"] == "open-center" and fixture["available"] is True
    section = ScenarioSection.from_runs(load_scenario("central-leader"), run_cache)
    (answer,) = one_dof_answer([section])
    x0 = section.ladder.rungs[0].values["x_max"]
    x_flex = section.ladder.value("beam", "x_max")
    assert answer["metrics"]["x_max"]["rel"] == pytest.approx(x_flex / x0 - 1.0, rel=1e-12)
    chains = [r for r in section.ladder.rungs if r.rung.kind == "chain" and r.ok]
    for chain in chains:  # discretisation: within the step.chain tolerance of the continuum
        assert chain.values["x_max"] == pytest.approx(x_flex, rel=0.005)
    # x_max, energy delivered, crown peak: the paper's (Newton) model; force and crown
    # acceleration, which Newton's impulses do not have: the soft SDOF with the same pad
    assert answer["good_enough"] == {"x_max": False, "energy_delivered": False,
                                     "crown_peak": False, "crown_peak_acceleration": False,
                                     "peak_force": False}
    soft = section.ladder.value("soft", "peak_force")
    assert answer["metrics"]["peak_force"]["one_dof"] == soft
    assert answer["metrics"]["energy_delivered"]["one_dof"] == \
        section.ladder.rungs[0].values["energy_delivered"]
    assert answer["explained"] is False  # the full-record fit on the continuum's record
    html = paths["html"].read_text()
    assert html.index("The answer") < html.index("Summary")
    # the pad's loss the answer quotes: the continuum's and the 1-DOF model's, eq 56
    assert answer["pad_loss"]["continuum"] == section.ladder.value("beam", "contact_dissipation")
    assert answer["pad_loss"]["one_dof"] == \
        section.ladder.rungs[0].values["contact_dissipation"]
    loss = fixture["pad_loss"]
    # one tree: each band's ends are equal, printed once (issue 41: not "17.7-17.7 J")
    quoted = re.search(r"pad loses far less energy than eq 56 says \(([0-9.]+) J on "
                       r"the continuum instead of the 1-DOF model's ([0-9.]+) J\)", html)
    assert quoted, "the answer quotes the pad's loss"
    assert [float(v) for v in quoted.groups()] == pytest.approx(
        [loss["continuum"], loss["one_dof"]], rel=0.005)  # 3 digits printed


def test_a_one_impact_record_shows_ranges_not_numbers(tmp_path):
    """central-leader with a crown of four trunk masses at e = 0.3: the pendulum rebounds
    off M_T = 557 kg and never returns, so the SDOF rungs' records do not fix M_T and e
    apart (docs/identification.md): the fit table gives ranges holding the truth, says
    "not fixed" and why, and the JSON keeps the ranges."""
    from treeimpact.analytic.model.two_body import two_body_model
    from treeimpact.compare.studies.ident_records import Case, _scenario

    scen = _scenario(Case("central-leader", 0.3, 4.0, "analytic"))
    paths = write_report(tmp_path, scenarios=[scen], runs=RunCache(),
                         engines=("no-such-engine",), segments=4)
    md = paths["md"].read_text()
    row = next(line for line in md.splitlines() if line.startswith("| analytic |")
               and "not fixed" in line)
    assert "the pendulum left after one impact" in md
    data = json.loads(paths["json"].read_text())
    fits = next(iter(data["scenarios"].values()))["record_fits"]
    analytic = next(f for f in fits if f["rung"] == "analytic")
    lo, hi = analytic["ranges"]["M_T"]
    assert lo <= two_body_model(scen).dynamic_mass <= hi, (row, lo, hi)
    assert analytic["ranges"]["restitution"][0] <= 0.3 <= analytic["ranges"]["restitution"][1]


def _parents_of_tables(html: str) -> list:
    """(tag, class) of the element each <table> of ``html`` opens in."""
    from html.parser import HTMLParser

    class Tables(HTMLParser):
        VOID = {"br", "img", "meta", "hr", "input", "link", "col", "wbr"}

        def __init__(self):
            super().__init__()
            self.stack, self.parents = [], []

        def handle_starttag(self, tag, attrs):
            if tag == "table":
                self.parents.append(self.stack[-1] if self.stack else None)
            if tag not in self.VOID:
                self.stack.append((tag, dict(attrs).get("class")))

        def handle_endtag(self, tag):
            while self.stack:
                if self.stack.pop()[0] == tag:
                    break

    parser = Tables()
    parser.feed(html)
    return parser.parents


def test_every_table_scrolls_inside_its_own_box(report):
    """A table wider than the page (the ladder, the answer) scrolls in its box, never the
    page: every <table> sits directly in a div.scroll whose overflow-x is auto."""
    paths, _ = report
    html = paths["html"].read_text()
    parents = _parents_of_tables(html)
    assert len(parents) >= 10
    assert all(p == ("div", "scroll") for p in parents), parents
    assert re.search(r"\.scroll\s*\{[^}]*overflow-x:\s*auto", html)


def test_the_run_list_is_short_rounded_and_failures_first(report):
    """Runs without a result first, with their reasons; every run in a collapsed list;
    options rounded to 3 significant digits with their units, reasons to 4."""
    from treeimpact.compare.report.runlog import run_rows
    from treeimpact.compare.runs.cache import OK, SKIPPED, Run

    rows = run_rows([Run("tree", "soft", {"contact_duration": 0.00030583481301971617,
                                          "restitution": 0.1}, OK, wall_s=0.1),
                     Run("tree", "analytic", {}, OK, wall_s=0.01),
                     Run("tree", "no-such-engine", {"segments": 12}, SKIPPED,
                         reason="identification failed: a1 = -1.4782888969718704 m/s")])
    assert [r["backend"] for r in rows] == ["no-such-engine", "analytic", "soft"]
    assert rows[0]["reason"] == "identification failed: a1 = -1.478 m/s"
    assert rows[2]["options"] == "contact_duration=3.06e-4 s, restitution=0.1"
    assert rows[1]["options"] == "defaults"
    paths, cache = report
    html = paths["html"].read_text()
    runs = html[html.index('id="runs"'):]
    assert '<details class="runs">' in runs and "<details class=\"runs\" open" not in runs
    failed = runs[runs.index("Runs without a result"):runs.index('<details class="runs">')]
    assert failed.count("<tr") == 1 + sum(not r.ok for r in cache)  # header + each failure
    listed = runs[runs.index('<details class="runs">'):]
    first_ok = listed.index('<tr class="">')
    assert listed.rfind('<tr class="skip">') < first_ok  # the failures first


def test_not_compared_is_said_once_per_reason_in_plain_words(report):
    """'Not compared' groups the tolerance file's undefined entries once per reason and
    names each comparison in words, never by its key (convention, engines.pendulum)."""
    from treeimpact.compare.report.scenario import not_compared_lines
    from treeimpact.compare.runs.rungs import RungKind

    lines = not_compared_lines([
        {"kind": "convention", "metrics": ["T0", "V"], "reason": "moving-together point"},
        {"kind": "engines.pendulum", "metrics": ["T0", "V"], "reason": "moving-together point"},
        {"kind": "beam", "metrics": ["theta_b"], "reason": "late re-contacts"}])
    assert len(lines) == 2 and lines[0]["metrics"] == ["T0", "V"]
    assert lines[0]["steps"] == ("restitution convention (c_c for e on the clamp's mass); "
                                 "the engines against each other with the full pendulum")
    assert lines[0]["reason"] == "Moving-together point"
    paths, _ = report
    html = paths["html"].read_text()
    part = html[html.index("<h3>Not compared</h3>"):]
    part = part[:part.index("</ul>")]
    items = re.findall(r"<li><b>[^<]*</b>, at ([^<]*?): ([^<]*)</li>", part)
    assert items and len(items) == part.count("<li>")
    keys = {k.value for k in RungKind} | {f"engines.{k.value}" for k in RungKind}
    for steps, reason in items:
        assert not set(re.split(r"; ", steps)) & keys, steps
        assert "engines." not in steps and "_" not in steps.replace("c_c", "")
    assert len(set(items)) == len(items)  # each comparison list and reason said once


def test_a_fit_value_the_record_does_not_fix_is_shown_as_such(report):
    """open-center's soft record: the fit explains it, but its e (3e-9, at the bound) has a
    95 % interval spanning all of [0, 1]: the page says 'not fixed by the record', not a
    number; fixed values show their interval where it is not negligible."""
    from treeimpact.compare.report.scenario import fit_cells

    cells = fit_cells({"values": {"M_T": 87.0, "K_T": 1.2e6, "C_T": 1.2e4, "restitution": 3.5e-9},
                       "errors": {"M_T": 0.001, "K_T": 0.0, "C_T": 0.0},
                       "ranges": {},
                       "intervals": {"M_T": (60.0, 109.0), "K_T": (1.19999e6, 1.20001e6),
                                     "C_T": (1.1e4, 1.3e4),
                                     "restitution": (-2.4e5, 2.4e5)}},
                      {"M_T": 87.0, "K_T": 1.2e6, "C_T": 1.2e4, "restitution": 0.1})
    by = {c["metric"]: c for c in cells}
    assert by["restitution"]["fixed"] is False and by["restitution"]["value"] is None
    assert (by["restitution"]["low"], by["restitution"]["high"]) == (0.0, 1.0)
    assert by["M_T"]["fixed"] and by["M_T"]["show_interval"]
    assert not by["K_T"]["show_interval"]  # 2e-5 of the value: nothing to show
    paths, _ = report
    data = json.loads(paths["json"].read_text())
    fits = data["scenarios"]["open-center"]["record_fits"]
    soft = next(f for f in fits if f["rung"] == "soft")
    assert soft["explained"]  # the pad's 0.02 % of the peak is far below the 1 % noise
    md = paths["md"].read_text()
    for f in fits:  # intervals in the physical range; an e spanning it reads "not fixed"
        lo, hi = f["intervals"]["restitution"]
        assert 0.0 <= lo <= hi <= 1.0, f
        row = next(line for line in md.splitlines() if line.startswith(f"| {f['rung']} |"))
        assert ("not fixed by the record" in row) == (lo <= 0.0 and hi >= 1.0), row
    html = paths["html"].read_text()
    assert "| truth |" in md and "<td class=\"l\">truth</td>" in html.replace("<b>", "")


def test_force_and_displacement_figures_tell_the_rungs_apart(ladder_of):
    """The force: one panel per rung over one time span, linear axes, the Newton impulses
    inside their axes; the displacement: one difference panel per rung, the 1-DOF trunks
    on one y scale and the flexible trunks on another."""
    from treeimpact.compare.report import figures
    from treeimpact.compare.runs.rungs import RungKind

    ladder = ladder_of("central-leader")
    ok = [r for r in ladder.rungs if r.ok]
    fig = figures.force_figure(ladder)
    axes = fig.axes
    assert len(axes) == len(ok)  # the Newton impulses and one panel per soft-contact rung
    assert {ax.get_yscale() for ax in axes} == {"linear"}
    assert len({ax.get_xlim() for ax in axes}) == 1  # one time span
    newton = axes[0]
    top = newton.get_ylim()[1]
    assert all(max(line.get_ydata(), default=0) < top for line in newton.get_lines())
    fig = figures.displacement_figure(ladder)
    panels = [ax for ax in fig.axes if ax.axison and ax.get_title().split(":")[0] in
              {r.rung.id for r in ok}]
    assert len(panels) == len([r for r in ok if r.rung.kind != RungKind.NEWTON])
    sdof = {ax.get_ylim() for ax in panels if ax.get_title().split(":")[0] in
            {r.rung.id for r in ok if r.rung.kind in (RungKind.CONTACT, RungKind.ENGINE)}}
    flexible = {ax.get_ylim() for ax in panels} - sdof
    assert len(sdof) == 1 and len(flexible) == 1
    (s_lo, s_hi), (f_lo, f_hi) = sdof.pop(), flexible.pop()
    assert s_hi - s_lo < 0.2 * (f_hi - f_lo)  # the 1-DOF trunks' differences stay visible


def _cells(row_html: str) -> list[str]:
    """The text of each cell of one html table row (tags stripped)."""
    return [re.sub(r"<[^>]+>", "", c).strip()
            for c in re.findall(r"<t[dh][^>]*>(.*?)</t[dh]>", row_html, re.S)]


def _number(text: str) -> float:
    """A page's number as a float: '+0.61 %' -> 0.0061, '1.57e-5', '5070'; n/a -> NaN."""
    text = text.strip().strip("`")
    if text == "n/a":
        return math.nan
    if text.endswith("%"):
        return float(text[:-1].strip()) / 100
    return float(text)


def _close(shown: float, value: float, *, pct: bool = False) -> bool:
    """``shown`` is ``value`` as the page rounds it: percentages to 0.01 % (5e-5 of a
    fraction), other numbers to 3 significant digits (or whole seconds from 100)."""
    if pct:
        return abs(shown - value) <= 5.01e-5
    return abs(shown - value) <= max(5.01e-3 * abs(value), 0.501 if abs(value) >= 100 else 0)


def _tables(text: str, fmt: str) -> list[list[list[str]]]:
    """Every table of an html or markdown text as rows of cell texts (header row first)."""
    if fmt == "html":
        return [[_cells(r) for r in re.findall(r"<tr>(.*?)</tr>", t, re.S)]
                for t in re.findall(r"<table>(.*?)</table>", text, re.S)]
    tables, cur = [], []
    for line in text.splitlines() + [""]:
        if line.startswith("|"):
            if not re.fullmatch(r"\|(\s*-+:?\s*\|)+", line.replace("---:", "---")):
                cur.append([c.strip() for c in line.strip().strip("|").split("|")])
        elif cur:
            tables.append(cur)
            cur = []
    return tables


@pytest.mark.parametrize("fmt", ["html", "md"])
def test_trunk_section_shows_the_numbers_of_trunks_json(fmt):
    """The trunk section's numbers are its package data's (data/trunks.json), read back from the
    rendered page as numbers: per tree the cheapest run within the target on x_max (the
    sentence and the table), and every (trunk, N) of one tree at the default step."""
    from treeimpact.compare.report.trunks import TRUNKS_JSON, TrunksSection

    data = json.loads(TRUNKS_JSON.read_text())
    tree = "central-leader"
    text = TrunksSection(tree=tree).render(fmt)
    cheap, per_n = _tables(text, fmt)
    # the user's table: one row per tree and model, the file's cheapest within the target
    want = [(name, c) for name, sc in data["scenarios"].items()
            for c in sorted(sc["cheapest"], key=lambda c: c["wall_per_simulated_s"])]
    assert len(cheap) - 1 == len(want)
    for cells, (name, c) in zip(cheap[1:], want):
        rows = {(r["model"], r["segments"]): r for r in data["scenarios"][name]["rows"]}
        assert cells[0] == name and cells[1].strip("`") == f"--trunk {c['model']}"
        assert _number(cells[2]) == c["segments"]
        assert _close(_number(cells[3]), c["dt"])
        assert _close(_number(cells[4]), c["dt"] / rows[(c["model"], c["segments"])][
            "default_dt"])
        assert _close(_number(cells[5]), c["x_max_error"], pct=True)
        assert abs(c["x_max_error"]) <= data["target"]
        assert _close(_number(cells[6]), c["energy_delivered_error"], pct=True)
        assert _close(_number(cells[7]), c["wall_per_simulated_s"])
    # the sentences: per tree the cheapest of all, its flags and cost
    plain = re.sub(r"<[^>]+>|`|\*\*", "", text)  # tags and markdown marks off
    said = re.findall(r"(\S+): use --trunk (\w+) --segments (\d+) --dt (\S+) \(.*?\),\s+"
                      r"costing (\S+) s per simulated second \(x_max ([^,]+), energy "
                      r"delivered ([^)]+)\)", plain)
    assert len(said) == len(data["scenarios"])
    for (name, model, n, dt, cost, xm, ed), (want_name, sc) in zip(
            said, data["scenarios"].items()):
        best = min(sc["cheapest"], key=lambda c: c["wall_per_simulated_s"])
        assert name == want_name and model == best["model"]
        assert int(n) == best["segments"] and _close(float(dt), best["dt"])
        assert _close(float(cost), best["wall_per_simulated_s"])
        assert _close(_number(xm), best["x_max_error"], pct=True)
        assert _close(_number(ed), best["energy_delivered_error"], pct=True)
    # every (trunk, N) of the tree at the runner's default step
    rows = data["scenarios"][tree]["rows"]
    assert len(per_n) - 1 == len(rows)
    for cells, r in zip(per_n[1:], rows):
        run = r["runs"][0]
        assert cells[0] == r["model"] and _number(cells[1]) == r["segments"]
        for i, v in ((2, r["static_stiffness_error"]), (3, r["omega_errors"][0]),
                     (4, r["omega_errors"][1]), (5, run["x_max_error"]),
                     (6, run["energy_delivered_error"])):
            assert _close(_number(cells[i]), v, pct=True), (r["model"], r["segments"], i)
        for i, v in ((7, r["default_dt"]), (8, r["trunk_stable_dt"]), (9, r["runner_limit"]),
                     (10, run["wall_per_simulated_s"])):
            assert _close(_number(cells[i]), v), (r["model"], r["segments"], i)


def test_trunk_section_says_where_its_numbers_come_from(tmp_path, report):
    """The section names the file and the machine it was measured on, or says the machine
    was not recorded; the full report carries it as a section and in report.json."""
    from treeimpact.compare.report.trunks import TRUNKS_JSON, TrunksSection

    data = json.loads(TRUNKS_JSON.read_text())
    unrecorded = {**data, "machine": None, "measured": None}
    (tmp_path / "a.json").write_text(json.dumps(unrecorded))
    html = TrunksSection(tmp_path / "a.json").render("html")
    assert "compare/report/data/trunks.json" in html and "machine not recorded" in html
    recorded = {**data, "machine": "x86_64, 2 cores, Python 3.11.7", "measured": "2026-01-02",
                "load_average": 0.5, "git_commit": "0123456789abcdef"}
    recorded["scenarios"] = {n: {**s, "record": {"machine": recorded["machine"]}}
                             for n, s in data["scenarios"].items()}
    (tmp_path / "b.json").write_text(json.dumps(recorded))
    md = TrunksSection(tmp_path / "b.json").render("md")
    assert "measured 2026-01-02 on x86_64, 2 cores" in md and "`0123456789`" in md
    assert "not recorded" not in md
    missing = TrunksSection(tmp_path / "none.json")
    assert not missing.available and "is not in this checkout" in missing.render("html")
    paths, _ = report
    assert 'id="trunks"' in paths["html"].read_text()
    shown = json.loads(paths["json"].read_text())["trunks"]
    assert shown["source"] == "compare/report/data/trunks.json"
    assert [t["name"] for t in shown["trees"]] == list(data["scenarios"])


def test_the_pooled_record_fits_are_each_rungs_own(report):
    """The report fits every rung's record in a process pool (compare.report.build_sections):
    each fit lands on its own rung, in the ladder's order, and equals the fit made in this
    process (the same record, noise seed and optimiser: equal to rounding of the JSON)."""
    from treeimpact.compare.studies.ident_fits import fit_one, fit_tasks
    from treeimpact.compare.tree.ladder import build_ladder

    paths, cache = report
    fits = json.loads(paths["json"].read_text())["scenarios"]["open-center"]["record_fits"]
    tasks = fit_tasks(build_ladder("open-center", cache=cache, segments=4,
                                   engines=("no-such-engine",)))
    assert [f["rung"] for f in fits] == [t[0] for t in tasks]
    here = fit_one(tasks[-1])  # one fit (0.5-1 s): the last, where an order slip shows
    for k, v in here["values"].items():
        assert fits[-1]["values"][k] == pytest.approx(v, rel=1e-9), k


def test_the_answer_answers_both_halves_first(report):
    """The first screen: a sentence per half, the 1-DOF table, then the small-e table and
    figure, before the summary; report.json's answer.small_e.<tree>.<name> holds each
    approximation's crossing, its error at the tree's e and its curve."""
    from treeimpact.compare.studies.small_e import APPROXIMATIONS, E_GRID

    paths, _ = report
    data = json.loads(paths["json"].read_text())
    answer = data["answer"]
    assert set(answer["in_short"]) == {"one_dof", "small_e"}
    tree = answer["small_e"]["open-center"]
    assert set(tree) == set(APPROXIMATIONS)
    for a in tree.values():
        assert {"holds_up_to_e", "error_at_e", "e_grid", "errors"} <= set(a)
        assert a["e_grid"] == list(E_GRID) and len(a["errors"]) == len(E_GRID)
        assert 0.0 <= a["holds_up_to_e"] <= E_GRID[-1]
    assert answer["small_e_figure"] == "figures/small-e.png"
    html = paths["html"].read_text()
    small = next(i["text"] for i in answer["first_screen"] if i["key"] == "small_e")
    order = [html.index(s) for s in (small[:40], 'id="answer-one-dof"',
                                     'id="answer-small-e"', 'src="figures/small-e.png"',
                                     'id="summary"')]
    assert order == sorted(order)
    md = paths["md"].read_text()
    assert "Does \"e is small\" hold?" in md and "](figures/small-e.png)" in md


def test_answer_cells_sort_by_their_own_number(report):
    """Issue 34: an answer cell holds a percentage, two values and a band; the sorter reads
    its data-sort (the gap), not every digit of its text as one number."""
    paths, _ = report
    html = paths["html"].read_text()
    data = json.loads(paths["json"].read_text())
    (row,) = data["answer"]["one_dof"]
    cells = re.findall(r'<td class="[^"]*" data-sort="([^"]+)"><b>([^<]+)</b>', html)
    assert len(cells) == len(row["metrics"])
    for (sort, shown), m in zip(cells, row["metrics"].values()):
        assert float(sort) == pytest.approx(m["rel"], rel=1e-12)
        assert float(shown.replace("%", "")) == pytest.approx(100 * m["rel"], abs=0.5)
    assert "td.dataset.sort" in html  # the sorter reads it


def test_the_answer_matrix_is_the_report_s_own_numbers_and_leads_the_answer(report):
    """Each drawn cell of the answer's matrix (compare.report.answer_matrix) against the
    report.json number it reads, judged by the 5 % rule; a cell without a number is n/a
    with its reason; the same figure in both pages, after the numbered sentences."""
    from treeimpact.compare.report.answer_matrix import State, cell_text

    paths, _ = report
    data = json.loads(paths["json"].read_text())
    matrix, tol = data["summary"]["answer_matrix"], data["answer"]["tolerance"]
    rows = {a["scenario"]: a for a in data["answer"]["one_dof"]}
    small_e = data["answer"]["small_e"]
    metric = {"x_max": "x_max", "energy_delivered": "energy_delivered",
              "crown_acceleration": "crown_peak_acceleration"}
    approx = {"energy_delivered": "eq58_energy_transferred", "eq57_loss": "eq57_energy_loss",
              "M_T": "identification_M_T", "K_T": "identification_K_T"}
    seen_na = 0
    for c in matrix["cells"]:
        row, tree = rows[c["tree"]], c["tree"]
        if c["assumption"] == "1-DOF trunk":
            if c["quantity"] in metric:
                want = row["metrics"][metric[c["quantity"]]]["rel"]
            elif c["quantity"] == "eq57_loss":
                loss = row["pad_loss"]
                want = (loss["continuum"] - loss["one_dof"]) / abs(loss["one_dof"])
            else:
                fit = next(f for f in data["scenarios"][tree]["record_fits"]
                           if f["rung"] == "beam")
                want = None if c["quantity"] in fit.get("ranges", {}) else \
                    fit["errors"][c["quantity"]]
        else:
            name = approx.get(c["quantity"])
            want = small_e[tree][name]["error_at_e"] if name else None
        if want is None:
            seen_na += 1
            assert c["state"] == State.NOT_AVAILABLE and c["value"] is None
            assert matrix["notes"][c["note"]] and c["reason"]
            continue
        assert c["value"] == pytest.approx(want, rel=1e-12)
        assert c["state"] == ("holds" if abs(want) <= tol else "off")
        assert c["text"] == cell_text(want, tol)
    assert seen_na >= 2  # x_max and the crown have no small-e formula
    md, html = paths["md"].read_text(), paths["html"].read_text()
    assert matrix["figure"] == "figures/answer-matrix.png"
    assert (paths["html"].parent / matrix["figure"]).read_bytes()[:4] == b"\x89PNG"
    for page in (md, html):
        at = page.index(matrix["figure"])
        assert page.index("The answer") < at < page.index("Where each tree's M_T comes from")


def test_a_tree_without_a_1_dof_answer_is_said_so_not_a_crash(tmp_path):
    """open-center stopped at 30 ms, inside its moving-together phase: the paper's model and
    the soft SDOF refuse the run (energy_delivered needs the last separation). The report
    is still written; its first screen, answer table and JSON say there is no 1-DOF answer
    for the tree and why (the page crashed on a missing sentence before), and the small-e
    sentence gives no verdict where no e = 0 value exists (it said "off already at e = 0")."""
    import dataclasses

    scen = dataclasses.replace(load_scenario("open-center"), t_end=0.03)
    paths = write_report(tmp_path, scenarios=[scen], runs=RunCache(),
                         engines=("no-such-engine",), segments=4)
    data = json.loads(paths["json"].read_text())
    (row,) = data["answer"]["one_dof"]
    assert row["available"] is False and row["why"].startswith("analytic: --t-end = 0.03 s")
    assert "No answer for open-center (analytic: --t-end" in data["answer"]["in_short"]["one_dof"]
    assert "| open-center | no answer: analytic: --t-end" in paths["md"].read_text()
    assert "no answer: analytic: --t-end" in paths["html"].read_text()
    # the small-e half: nothing at e = 0 is no verdict, not "off already at e = 0"
    small = data["answer"]["in_short"]["small_e"]
    assert "Off already" not in small and "at no e" not in small, small
    assert "No verdict on eq 57 energy loss" in small and "No answer for identified M_T" in small


def test_the_report_command_exits_4_when_a_tree_has_no_1_dof_answer(tmp_path, monkeypatch,
                                                                    capsys):
    """The pages are written and listed on stdout; stderr says which tree has no 1-DOF
    answer and why, and the exit code is 4 (ran, could not do what was asked)."""
    import treeimpact.compare.report as report_module
    from treeimpact.compare.interface.cli import main

    def written(out, **_):
        page = tmp_path / "report.json"
        page.write_text(json.dumps({"answer": {"one_dof": [
            {"scenario": "open-center", "available": False, "why": "analytic: too short"},
            {"scenario": "central-leader", "available": True}]}}))
        return {"json": page}

    monkeypatch.setattr(report_module, "write_report", written)
    assert main(["report", "--out", str(tmp_path), "--scenario", "open-center"]) == 4
    out, err = capsys.readouterr()
    assert out.strip() == f"json: {tmp_path / 'report.json'}"
    assert err.strip().endswith("without a 1-DOF answer for open-center (analytic: too short)")
    assert "central-leader" not in err
