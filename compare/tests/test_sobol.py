"""Variance-based sensitivity (compare.studies.sobol): SALib's Sobol indices through the
project's wrapper on a function whose indices are known, the settled/unsettled rule, the
N/2 convergence check, what to measure first, and one tree's design run on the sweeps."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from treeimpact.compare.studies.sobol import (
    analyse_sobol,
    measure_first,
    output_entry,
    settled_prefix,
    sobol_design,
    sobol_indices,
    verdict,
    verdict_text,
)
from treeimpact.compare.studies.study_inputs import INPUTS

ISHIGAMI = {"num_vars": 3, "names": ["x1", "x2", "x3"], "bounds": [[-math.pi, math.pi]] * 3}


def _ishigami_truth(a=7.0, b=0.1) -> dict:
    """The Ishigami function's S1 and ST, analytically (Ishigami & Homma 1990; Saltelli et
    al. 2008, sec. 4.7): V1 = (1 + b pi^4 / 5)^2 / 2, V2 = a^2 / 8, V3 = 0,
    V13 = b^2 pi^8 (1/18 - 1/50), V = V1 + V2 + V13."""
    v1 = 0.5 * (1.0 + b * math.pi ** 4 / 5.0) ** 2
    v2 = a * a / 8.0
    v13 = b * b * math.pi ** 8 * (1.0 / 18.0 - 1.0 / 50.0)
    v = v1 + v2 + v13
    return {"x1": {"S1": v1 / v, "ST": (v1 + v13) / v}, "x2": {"S1": v2 / v, "ST": v2 / v},
            "x3": {"S1": 0.0, "ST": v13 / v}}


def _ishigami(X):
    from SALib.test_functions import Ishigami

    return Ishigami.evaluate(X)


def test_ishigami_indices_lie_within_their_intervals_and_their_order_settles():
    """N = 2048 (14336 evaluations): every S1 and ST of the wrapper within its own
    S1_conf / ST_conf of the analytic value, and the rule says the order x1, x2, x3 is
    settled (their ST intervals separate, the same order at N/2)."""
    n = 2048
    y = _ishigami(sobol_design(n, spec=ISHIGAMI))
    entry = output_entry(ISHIGAMI["names"], y, n, ISHIGAMI)
    truth = _ishigami_truth()
    for name, t in truth.items():
        got = entry["indices"][name]
        for k in ("S1", "ST"):
            assert abs(got[k] - t[k]) <= got[f"{k}_conf"], (name, k, got[k], t[k])
    assert entry["status"] == "settled" and entry["settled"] == ["x1", "x2", "x3"]
    assert verdict_text(entry) == "decided by x1, then x2, then x3"


def test_the_half_design_is_the_first_half_of_the_design():
    """The N/2 check reads the first n/2 blocks of the design of n: they are the design of
    n/2 itself (the same scrambled Sobol points), so its indices are those of N/2."""
    full, half = sobol_design(64, spec=ISHIGAMI), sobol_design(32, spec=ISHIGAMI)
    assert np.array_equal(full[: len(half)], half)
    y = _ishigami(full)
    entry = output_entry(ISHIGAMI["names"], y, 64, ISHIGAMI)
    direct = sobol_indices(ISHIGAMI["names"], _ishigami(half), ISHIGAMI)
    for name in ISHIGAMI["names"]:
        got = entry["indices"][name]
        assert got["ST_half"] == direct[name]["ST"]
        assert got["ST_change"] == pytest.approx(got["ST"] - direct[name]["ST"], abs=1e-15)


def test_ishigami_at_a_small_n_is_said_unsettled():
    """N = 64: the x1 and x2 ST intervals overlap, so the rule names them both, unsettled."""
    n = 64
    entry = output_entry(ISHIGAMI["names"], _ishigami(sobol_design(n, spec=ISHIGAMI)), n,
                         ISHIGAMI)
    assert entry["status"] == "unsettled"
    assert set(entry["tied"]) >= {"x1", "x2"}
    assert verdict_text(entry).startswith("unsettled: ")


def _idx(**kw):
    """Constructed indices: name=(ST, ST_conf)."""
    return {k: {"ST": st, "ST_conf": c, "S1": st, "S1_conf": c} for k, (st, c) in kw.items()}


def test_the_rule_on_constructed_numbers():
    """settled_prefix counts leading inputs whose interval clears every lower one's and that
    keep their rank at N/2; verdict words the rest."""
    clear = _idx(a=(0.6, 0.05), b=(0.3, 0.05), c=(0.1, 0.05))
    assert settled_prefix(clear, clear) == 3
    assert verdict(clear, clear)["settled"] == ["a", "b", "c"]
    # b and c overlap (0.25 <= 0.25 + ... reaches): only a settles
    second = _idx(a=(0.6, 0.05), b=(0.3, 0.05), c=(0.22, 0.05))
    assert settled_prefix(second, second) == 1
    assert verdict_text(verdict(second, second)) == "decided by a"
    # a's interval reaches b's: unsettled, both named; c's upper end 0.15 < a's lower 0.4
    tied = _idx(a=(0.5, 0.1), b=(0.42, 0.05), c=(0.1, 0.05))
    v = verdict(tied, tied)
    assert v["status"] == "unsettled" and v["tied"] == ["a", "b"]
    assert verdict_text(v) == "unsettled: a or b (ST intervals overlap)"
    # separated at N but N/2 ranks b first: not settled
    swapped = _idx(a=(0.3, 0.02), b=(0.5, 0.02), c=(0.1, 0.02))
    v = verdict(clear, swapped)
    assert v["status"] == "unsettled" and v["tied"] == ["a"]
    assert verdict_text(v) == "unsettled: a ranks first at N but not at N/2"
    # no N/2 check (below 4 base samples): never settled
    assert verdict(clear, None)["status"] == "unsettled"
    assert verdict(None, None)["status"] == "nothing"
    assert verdict_text(verdict(None, None)) == "no input moves it"


def test_an_interval_the_bootstrap_could_not_give_settles_nothing():
    """A NaN ST_conf (a bootstrap resample with no spread) is an unknown interval: it ties
    with the leader instead of letting it clear; the page prints n/a for it."""
    from treeimpact.compare.report.base import share

    idx = _idx(a=(0.6, 0.05), b=(0.3, math.nan), c=(0.1, 0.05))
    v = verdict(idx, idx)
    assert v["status"] == "unsettled" and v["tied"] == ["a", "b"]
    assert share(math.nan) == "n/a" and share(None) == "n/a" and share(0.054, True) == "+0.05"


def test_a_flat_output_has_no_variance_to_share():
    names = ["x1", "x2", "x3"]
    assert sobol_indices(names, np.ones(5 * 8), ISHIGAMI) is None
    assert output_entry(names, np.ones(8 * 5), 8, ISHIGAMI)["status"] == "nothing"


def _entry(order, st, status="settled", settled=(), tied=()):
    return {"indices": {n: {"ST": s, "ST_conf": 0.01} for n, s in zip(order, st)},
            "order": list(order), "status": status, "settled": list(settled),
            "tied": list(tied)}


def test_what_to_measure_first_ranks_inputs_by_their_largest_share():
    """Rows ranked by the largest ST over the gaps, each with its measurement (INPUTS) and
    per gap its rank; per headline gap the settled leader's measurement, or the tied set's."""
    outputs = {
        "gap.x_max": _entry(["root_share", "e_over_g", "log10_pad_duration", "density"],
                            [0.5, 0.45, 0.1, 0.01], "unsettled",
                            tied=["root_share", "e_over_g"]),
        "gap.energy_delivered": _entry(["log10_pad_duration", "root_share", "density",
                                        "e_over_g"], [0.9, 0.2, 0.0, 0.0],
                                       settled=["log10_pad_duration"]),
    }
    got = measure_first(outputs)
    assert [r["input"] for r in got["rows"]] == ["log10_pad_duration", "root_share",
                                                "e_over_g", "density"]
    row = got["rows"][1]
    assert row["measurement"] == INPUTS["root_share"][4]
    assert row["gaps"]["gap.x_max"]["rank"] == 1 and row["gaps"]["gap.energy_delivered"][
        "rank"] == 2
    first = got["first"]
    assert first["gap.energy_delivered"] == {
        "status": "settled", "inputs": ["log10_pad_duration"],
        "measurements": [INPUTS["log10_pad_duration"][4]]}
    assert first["gap.x_max"]["status"] == "unsettled"
    assert first["gap.x_max"]["inputs"] == ["root_share", "e_over_g"]


def test_analyse_sobol_reads_a_table_of_the_design():
    """A synthetic table on the design of 16 over the six inputs: the x_max gap set by the
    root's share and (a tenth as much) e, the energy gap by the pad alone: the root's share
    leads x_max, the pad is the energy gap's settled leader and the first measurement."""
    n = 16
    X = sobol_design(n)
    rows = []
    for x in X:
        p = dict(zip(INPUTS, x))
        rows.append({"status": "ok", **{f"input.{k}": v for k, v in p.items()},
                     "gap.x_max": p["root_share"] + 0.1 * p["restitution"],
                     "gap.energy_delivered": p["log10_pad_duration"]})
    out = analyse_sobol(pd.DataFrame(rows), n)
    assert out["failed"] == 0 and out["evaluations"] == n * (len(INPUTS) + 2)
    assert set(out["outputs"]) == {"gap.x_max", "gap.energy_delivered"}
    assert out["outputs"]["gap.x_max"]["order"][0] == "root_share"
    energy = out["outputs"]["gap.energy_delivered"]
    assert energy["status"] == "settled" and energy["settled"][0] == "log10_pad_duration"
    assert out["measure_first"]["first"]["gap.energy_delivered"]["measurements"] == [
        INPUTS["log10_pad_duration"][4]]
    assert out["measure_first"]["rows"][0]["input"] in ("root_share", "log10_pad_duration")


def test_a_missing_point_is_counted_and_its_block_dropped():
    """A design of 4 whose first point has no row: counted, named (index 0, status
    missing), and the indices rest on the 3 complete blocks (issue 50 item 4)."""
    n = 4
    X = sobol_design(n)
    rows = [{"status": "ok", **{f"input.{k}": v for k, v in zip(INPUTS, x)},
             "gap.x_max": 1.0} for x in X[1:]]
    out = analyse_sobol(pd.DataFrame(rows), n)
    assert out["failed"] == 1 and out["blocks_used"] == 3
    assert out["failed_points"][0]["index"] == 0
    assert out["failed_points"][0]["status"] == "missing"
    assert out["outputs"]["gap.x_max"]["basis"] == {
        "blocks": 3, "of": 4, "points": 3 * (len(INPUTS) + 2), "non_finite": 0}
    assert out["outputs"]["gap.x_max"]["status"] == "nothing"  # a constant gap


def test_one_trees_design_runs_on_the_sweeps_with_its_measured_inputs_held(tmp_path):
    """A user's tree whose file says the clamp mass and e were measured: the Sobol sweep
    varies the four others (N = 4: 24 evaluations, in this process), every gap finite, and
    the ranking names only free inputs."""
    from treeimpact.analytic.model.scenario import load_scenario
    from treeimpact.analytic.model.scenario_toml import scenario_toml
    from treeimpact.compare.studies.sobol import sobol_sweep
    from treeimpact.compare.studies.study_inputs import free_inputs, ranges_of
    from treeimpact.compare.studies.sweep.run import run_sweeps

    text = scenario_toml(load_scenario("open-center")).replace(
        "[calibration]",
        '[calibration]\nmeasured = ["trunk.clamp_mass", "contact.restitution"]')
    path = tmp_path / "mine.toml"
    path.write_text(text)
    scen = load_scenario(path)
    names = free_inputs(scen)
    assert names == ("e_over_g", "log10_pad_duration", "root_share", "density")
    (res,) = run_sweeps([sobol_sweep(scen, tmp_path / "sweep", 4)], workers=0,
                        progress=False)
    assert len(res.table) == 4 * (len(names) + 2) and set(res.table["status"]) == {"ok"}
    out = analyse_sobol(res.table, 4, names=names, ranges=ranges_of(scen))
    assert out["failed"] == 0 and len(out["outputs"]) == 5
    assert {r["input"] for r in out["measure_first"]["rows"]} == set(names)
    assert all(math.isfinite(o["low"]) for o in out["outputs"].values())


def _study_row(outputs):
    """An answer row carrying a tree's Sobol analysis of ``outputs``, as with_sobol makes."""
    from treeimpact.compare.report.measure import with_sobol

    class Study:
        study = {"validity": [], "sensitivity": {"sobol": 64, "trees": {"t": {"sobol": {
            "n": 64, "evaluations": 512, "conf_level": 0.95,
            "outputs": outputs, "measure_first": measure_first(outputs)}}}}}

    row = {"scenario": "t"}
    with_sobol([row], [Study()])
    return row


def test_the_first_screen_sentence_is_generated_by_the_rule():
    """Settled: the leader's measurement with its ST; unsettled: every tied input's
    measurement; each verdict worded in the row's outputs."""
    from treeimpact.compare.report.measure import in_short_text

    outputs = {
        "gap.x_max": _entry(["root_share", "e_over_g", "log10_pad_duration"],
                            [0.5, 0.45, 0.1], "unsettled", tied=["root_share", "e_over_g"]),
        "gap.energy_delivered": _entry(["log10_pad_duration", "root_share", "e_over_g"],
                                       [0.9, 0.2, 0.0], settled=["log10_pad_duration"]),
    }
    row = _study_row(outputs)
    said = row["measure_first"]["said"]
    assert said == ("x_max: unsettled between root compliance (ST 0.50 +- 0.01) and E / G "
                    "(shear) (ST 0.45 +- 0.01); the energy delivered: pad contact duration (ST 0.90 "
                    "+- 0.01), by " + INPUTS["log10_pad_duration"][4] + ".")
    assert row["sobol"]["outputs"]["gap.energy_delivered"]["text"] == \
        "decided by pad contact duration"
    assert row["measure_first"]["sentence"] == f"t: {said}"
    short = in_short_text([row])
    assert "N = 64, 512 evaluations per tree" in short and short.endswith(said)
    assert in_short_text([{"scenario": "u", "measure_first": {}}]) is None
    # a user's tree with two inputs held has fewer evaluations: each tree's count said
    # (issue 41: the page said 210 where its answer table's tree had 150)
    held = {**row, "scenario": "mine", "sobol": {**row["sobol"], "evaluations": 384}}
    both = in_short_text([row, held])
    assert "evaluations t 512, mine 384" in both and "per tree" not in both


def test_n_is_a_power_of_two_and_the_docs_say_each_presets():
    """A Sobol sequence is balanced only at powers of two: any other N is refused in one
    line; every preset's N is one, and docs/sensitivity.md says the default's and the
    full preset's."""
    from pathlib import Path

    from treeimpact.analytic.errors import ParameterError
    from treeimpact.compare.report.validity.study import PRESETS

    with pytest.raises(ParameterError, match="power of two"):
        sobol_design(48)
    text = (Path(__file__).resolve().parents[2] / "docs" / "sensitivity.md").read_text()
    for name in ("default", "full"):
        n = PRESETS[name].sobol
        assert n > 0 and n & (n - 1) == 0, name
        assert f"N = {n}" in text, name
    assert PRESETS["full"].sobol >= 4096  # issue 40: the full preset's N >= 4096
