"""The design study (compare.studies.design, design_words, compare.report.validity.design_study):
its cells against the rungs run directly on a tree rebuilt by hand, the words-from-map rule
on constructed maps, the 5 % line where the cells change side, bad ranges refused in one
line (exit 2), the page section and the registration."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from treeimpact.analytic.errors import ParameterError
from treeimpact.compare.studies import design as D
from treeimpact.compare.studies import design_words as W


# --------------------------------------------------------------------------- cells


def _by_hand(scen, a_over_l: float, mass_ratio: float):
    """The tree at (a/l, m/M_T) built without compare.studies.sweep.apply: the clamp at a/l of l,
    then the impactor's mass m/M_T times eq 7's M_T of that clamped trunk."""
    from treeimpact.analytic.model.reduction import reduce_trunk

    trunk = dataclasses.replace(scen.trunk, clamp_height=a_over_l * scen.trunk.length)
    m = mass_ratio * reduce_trunk(trunk).dynamic_mass
    return dataclasses.replace(scen, trunk=trunk,
                               impactor=dataclasses.replace(scen.impactor, mass=m))


def test_cells_agree_with_the_rungs_run_directly(tmp_path):
    from treeimpact.analytic.contact.soft import simulate_soft
    from treeimpact.analytic.continuum.beam_impact import simulate_beam
    from treeimpact.analytic.impact.simulate import simulate
    from treeimpact.compare.runs.cache import resolve_scenario
    from treeimpact.compare.studies.sweep.run import run_sweeps

    scen = resolve_scenario("central-leader")
    spec = D.design_spec(scen, ["a_over_l=0.15,0.5", "mass_ratio=0.3,3"], tmp_path / "m")
    table = run_sweeps([spec], workers=0, progress=False)[0].table
    assert len(table) == 4 and set(table["status"]) == {"ok"}
    for _, row in table.iterrows():
        s = _by_hand(scen, float(row["a_over_l"]), float(row["mass_ratio"]))
        newton, beam = simulate(s, samples=2).metrics, simulate_beam(s).metrics
        soft = simulate_soft(s).metrics
        for q, ref in (("x_max", newton), ("energy_delivered", newton),
                       ("crown_peak_acceleration", soft)):
            want = (beam[q] - ref[q]) / abs(ref[q])
            assert row[f"design.{q}"] == pytest.approx(want, rel=1e-9, abs=1e-12), q
        # eq 57 against the exact loss, from the formula, not from small_e
        model = simulate(s, samples=2).solution.model
        eq57 = model.reduced_mass * model.impact_speed ** 2 / 2.0
        loss = newton["contact_dissipation"]
        assert row["design.eq57_energy_loss"] == pytest.approx((eq57 - loss) / loss, rel=1e-9)


def test_the_cells_move_with_the_inputs_applied():
    """A cell that ignored its point would repeat the tree's own numbers."""
    from treeimpact.analytic.impact.simulate import simulate
    from treeimpact.compare.runs.cache import resolve_scenario

    scen = resolve_scenario("central-leader")
    low, high = _by_hand(scen, 0.15, 0.3), _by_hand(scen, 0.5, 3.0)
    a = D.design_cell(simulate(low), low)
    b = D.design_cell(simulate(high), high)
    assert abs(a["design.x_max"] - b["design.x_max"]) > 0.01


def test_operating_point_is_the_trees_own():
    from treeimpact.compare.runs.cache import resolve_scenario

    scen = resolve_scenario("central-leader")
    here = D.operating_point(scen)
    assert here["a_over_l"] == pytest.approx(scen.trunk.clamp_height / scen.trunk.length)
    assert here["contact_duration"] == pytest.approx(scen.contact.duration)
    assert here["restitution"] == scen.contact.restitution


# --------------------------------------------------------------------------- the rule


def test_the_5_percent_line_lies_where_the_cells_change_side():
    x = np.linspace(0.1, 0.6, 11)
    gap = 0.5 * (0.4 - x)  # |gap| = 5 % at x = 0.3 and x = 0.5, exactly
    found = W.crossings(x, gap, 0.05)
    assert found == pytest.approx([0.3, 0.5], abs=1e-12)
    # a curved gap: each crossing between the two cells on opposite sides
    curved = (x - 0.33) ** 2 * 3.0
    for c in W.crossings(x, curved, 0.05):
        i = np.searchsorted(x, c)
        assert (abs(curved[i - 1]) <= 0.05) != (abs(curved[i]) <= 0.05)
        assert x[i - 1] <= c <= x[i]


def test_within_intervals_and_their_words():
    x = np.linspace(0.1, 0.6, 11)
    assert W.within_intervals(x, 0.5 * (0.4 - x), 0.05) == [
        pytest.approx((0.3, 0.5), abs=1e-12)]
    assert W.within_intervals(x, np.full(11, 0.01), 0.05) == [(0.1, 0.6)]
    assert W.within_intervals(x, np.full(11, 0.5), 0.05) == []
    assert W.intervals_text("a_over_l", [], 0.1, 0.6) == \
        "at no clamp height a/l from 0.1 to 0.6"
    assert W.intervals_text("a_over_l", [(0.1, 0.6)], 0.1, 0.6).startswith("over the whole")
    assert W.intervals_text("contact_duration", [(0.006, 0.05)], 2e-4, 5e-2) == \
        "for contact duration from 6 ms to 50 ms"


def test_the_sentence_is_read_off_a_constructed_map():
    x = np.linspace(0.1, 0.6, 11)  # a/l
    y = np.array(D.INPUTS["mass_ratio"].values(5))  # m/M_T 0.2, 0.447, 1, 2.236, 5
    # linear in a/l and in log10 m/M_T, so the line between rows is exact
    z = np.array([[0.5 * (0.45 - xi) + 0.1 * math.log10(r) for xi in x] for r in y])
    here = {"a_over_l": 0.3, "mass_ratio": 1.0, "contact_duration": 5e-4, "restitution": 0.1}
    # on a row: |0.5 (0.45 - a/l)| <= 0.05 for a/l in [0.35, 0.55]
    text = W.sentence_along(x, y, z, ("a_over_l", "mass_ratio"), here, "x_max", 0.05)
    assert text == "At mass ratio m/M_T = 1, x_max is within 5 % for clamp height a/l " \
                   "from 0.35 to 0.55."
    # between rows (m/M_T = 1.495, halfway on log10 between 1 and 2.236): the shift is
    # 0.1 log10(1.495) = 0.01747, so a/l in [0.385, 0.585]
    between = dict(here, mass_ratio=10 ** (0.5 * math.log10(y[3])))
    found, _ = W.along(x, y, z, ("a_over_l", "mass_ratio"), between, 0.05)
    shift = 0.1 * math.log10(between["mass_ratio"])
    assert found == [pytest.approx((0.45 - 0.1 + 2 * shift, 0.45 + 0.1 + 2 * shift),
                                   abs=1e-12)]
    # a log input's interval comes back in its units: |gap| <= 5 % within a quarter decade
    # of 2 ms, the ends interpolated on log10 of the duration
    d = np.array(D.INPUTS["contact_duration"].values(7))
    zd = np.array([[0.2 * (math.log10(2e-3) - math.log10(v)) for v in d]] * 2)
    found, _ = W.along(d, np.array([0.1, 0.6]), zd, ("contact_duration", "a_over_l"),
                       here, 0.05)
    ends = (10 ** (math.log10(2e-3) - 0.25), 10 ** (math.log10(2e-3) + 0.25))
    assert found == [pytest.approx(ends, rel=1e-9)]
    assert W.grade(0.04) == "within 5 %" and W.grade(-0.19) == "within 20 %"
    assert W.grade(0.34) == "off by +34 %"
    s = W.sentence_at_point(here, {"x_max": 0.04, "energy_delivered": 0.6}, ("x_max",
                                                                            "energy_delivered"))
    assert s == ("Clamping at a/l = 0.3 with m/M_T = 1, a 0.5 ms pad and e = 0.1, the 1-DOF "
                 "model is within 5 % on x_max and off by +60 % on energy delivered.")


# --------------------------------------------------------------------------- bad input


def test_a_bad_range_is_refused_in_one_line(tmp_path, capsys):
    from treeimpact.compare.interface.cli import main

    rc = main(["sweep", "--preset", "design", "--grid", "a_over_l=0.01:0.6:5",
               "--workers", "0", "--out", str(tmp_path / "d")])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and "\n" not in err and "Traceback" not in err
    assert "--grid 'a_over_l=0.01:0.6:5'" in err and "0.05-1" in err
    assert not (tmp_path / "d" / "a_over_l-mass_ratio").exists()
    import treeimpact

    with pytest.raises(ParameterError, match=r"^ranges: mass_ratio from 0 to 5 1; allowed "
                                             r"0.05 <= low < high <= 20 1$"):
        treeimpact.design_map(tmp_path / "e", ranges={"mass_ratio": (0.0, 5.0)})
    with pytest.raises(ParameterError, match="count = 1"):
        treeimpact.design_map(tmp_path / "e", count=1)


# --------------------------------------------------------------------------- the study


def test_the_study_writes_its_maps_words_and_section(tmp_path):
    from treeimpact.compare.report.studies import StudySection
    from treeimpact.compare.report.validity.design_study import run_design_study
    from treeimpact.compare.report.validity.study import get_preset

    assert get_preset("design").run is run_design_study  # registered beside it
    paths = run_design_study(tmp_path / "design", "central-leader", count=4, workers=0,
                             progress=False)
    import json

    data = json.loads(paths["json"].read_text())
    assert [p["pair"] for p in data["pairs"]] == [list(p) for p in D.PAIRS]
    assert len(data["pairs"][0]["x"]) == 4 and len(data["family"]) == len(D.DIAMETER_FACTORS)
    sec = StudySection(tmp_path / "design", page_dir=tmp_path)
    html = sec.render("html")
    assert data["at_point"] in html.replace("&#39;", "'")
    for p in data["pairs"]:
        assert p["figure"] in html
        for s in p["sentences"]:
            assert s["text"].split(",")[0] in html
    assert sec.to_json()["data"]["design.json"]["tree"] == "central-leader"
    _the_answer_reads_the_study(sec, data)


def _the_answer_reads_the_study(sec, data: dict) -> None:
    """report.json's answer.design.<tree> and the first screen's item carry the study's own
    sentences and numbers (compare/report/design_answer.py), not a recomputation."""
    from treeimpact.compare.report.design_answer import FIRST_PAIR, design_answer, in_short_text

    answer = design_answer([sec])["central-leader"]
    assert answer["at_point"] == data["at_point"] and answer["gaps_at_point"] == data["cell"]
    assert [s["text"] for s in answer["sentences"]] == [
        s["text"] for p in data["pairs"] for s in p["sentences"]]
    pair = data["pairs"][[tuple(p["pair"]) for p in data["pairs"]].index(FIRST_PAIR)]
    assert answer["maps"]["-".join(FIRST_PAIR)]["maps"] == pair["maps"]
    nearest = [s for s in pair["sentences"] if s["rule"] == "nearest"]
    short = in_short_text({"central-leader": answer})
    assert short.startswith("For a designer (central-leader): " + data["at_point"])
    assert all(s["text"] in short for s in nearest)
    assert design_answer([object()]) == {} and in_short_text({}) == ""


def test_the_nearest_cell_within_every_target():
    x = np.linspace(0.1, 0.6, 11)  # a/l
    y = np.array(D.INPUTS["mass_ratio"].values(5))  # 0.2, 0.447, 1, 2.236, 5
    xs, ys = np.meshgrid(x, y)
    maps = {"x_max": np.where(xs >= 0.45, 0.01, 0.3),  # within 5 % from a/l = 0.45
            "energy_delivered": np.where(ys >= 2.0, 0.1, 0.5)}  # within 20 % from 2.236
    here = {"a_over_l": 0.3, "mass_ratio": 1.0}
    target = {"x_max": 0.05, "energy_delivered": 0.20}
    pair = ("a_over_l", "mass_ratio")
    # the closest corner of the region [0.45, 0.6] x [2.236, 5] to (0.3, 1)
    assert W.nearest_within(x, y, maps, target, pair, here) == pytest.approx((0.45, 2.236))
    assert W.sentence_nearest(x, y, maps, target, pair, here) == (
        "The nearest choice on the clamp height a/l x mass ratio m/M_T map at which the "
        "1-DOF model is within 5 % on x_max and within 20 % on energy delivered: clamp height "
        "a/l = 0.45 with mass ratio m/M_T = 2.24.")
    maps["x_max"] = np.full_like(xs, np.nan)  # no number is no cell within
    assert W.nearest_within(x, y, maps, target, pair, here) is None
    assert W.sentence_nearest(x, y, maps, target, pair, here).startswith("No cell of the")


# --------------------------------------------------------------------------- engines


def test_spot_points_are_the_corners_and_the_cells_at_the_5_percent_line():
    from treeimpact.compare.studies.design_engines import spot_points

    x = np.linspace(0.1, 0.6, 6)  # a/l
    y = np.array(D.INPUTS["contact_duration"].values(7))  # 0.2-50 ms, log
    # |gap| <= 5 % within half a decade of 2 ms (0.632-6.32 ms), whatever a/l
    z = np.array([[0.1 * (math.log10(2e-3) - math.log10(v)) for _ in x] for v in y])
    pair = ("a_over_l", "contact_duration")
    here = {"a_over_l": 0.33, "contact_duration": 5e-4}
    pts = spot_points(x, y, z, pair, here, 0.05)
    assert pts[:4] == [{"a_over_l": 0.1, "contact_duration": 2e-4},
                       {"a_over_l": 0.1, "contact_duration": 5e-2},
                       {"a_over_l": 0.6, "contact_duration": 2e-4},
                       {"a_over_l": 0.6, "contact_duration": 5e-2}]
    # the crossings 0.632 ms and 6.32 ms lie nearest the cells 0.502 ms and 7.94 ms (on
    # log10), in the a/l column nearest the tree's 0.33
    assert [p["a_over_l"] for p in pts[4:]] == pytest.approx([0.3, 0.3])
    assert [p["contact_duration"] for p in pts[4:]] == [float(y[1]), float(y[4])]
    assert (y[1], y[4]) == pytest.approx((5.02e-4, 7.94e-3), rel=1e-3)


def test_spot_sentence_names_every_disagreement():
    from treeimpact.compare.studies.design_engines import spot_sentence

    ok = {"rel": 0.001, "tolerance": 0.005, "within": True}
    bad = {"rel": 0.52, "tolerance": 0.01, "within": False}
    checks = [{"point": {"a_over_l": 0.6, "contact_duration": 0.05},
               "rungs": {"Bullet chain": {"x_max": ok, "energy_delivered": bad,
                                          "crown_peak_acceleration": ok},
                         "MuJoCo chain": {"error": "skipped: not installed"}}}]
    assert spot_sentence(checks, ("a_over_l", "contact_duration")) == (
        "The engines' flexible trunks agree with the continuum within their stated "
        "tolerances in 2 of 3 comparisons at 1 cells: they disagree on Bullet chain "
        "energy_delivered +52.0 % (tolerance 1.0 %) at clamp height a/l = 0.6, contact "
        "duration = 50 ms; MuJoCo chain at clamp height a/l = 0.6, contact duration = 50 ms: "
        "no run (skipped: not installed).")


def test_the_engines_agree_with_the_continuum_at_the_trees_own_cell():
    """The shipped tree's own cell, where tolerances.toml's chain and rod tolerances were
    measured: every engine within them (the map's other cells may not be: reported)."""
    from treeimpact.compare.runs.cache import resolve_scenario
    from treeimpact.compare.studies.design_engines import spot_check

    scen = resolve_scenario("central-leader")
    here = D.operating_point(scen)
    check = spot_check((scen, {"a_over_l": here["a_over_l"],
                               "contact_duration": here["contact_duration"]}))
    for label, got in check["rungs"].items():
        assert "error" not in got, (label, got)
        for m in ("x_max", "energy_delivered", "crown_peak_acceleration"):
            assert got[m]["within"], (label, m, got[m])


def test_a_long_damped_pad_is_read_after_it_lets_go():
    """The design map's corner a/l = 0.6 with a 50 ms pad (e = 0.1: a heavily damped pad):
    Bullet's chain delivered +52 % of the continuum's energy, its x_max and crown within
    0.2 %. Not Bullet's physics: the loss was read at the first sample below the contact's
    force threshold, where Bullet's pad still pushed 0.003 N and its record held the
    compression the dashpot balances (26 mm, 36 J) as energy the bodies could get back;
    read where the force is 0, every engine trunk is within its tolerances there."""
    from treeimpact.compare.runs.cache import resolve_scenario
    from treeimpact.compare.studies.design_engines import spot_check

    check = spot_check((resolve_scenario("central-leader"),
                        {"a_over_l": 0.6, "contact_duration": 0.05}))
    for label, got in check["rungs"].items():
        assert "error" not in got, (label, got)
        for m in ("x_max", "energy_delivered", "crown_peak_acceleration"):
            assert got[m]["within"], (label, m, got[m])
