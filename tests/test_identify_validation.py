"""The validation set of `treeimpact identify` (tests/data/identify, issues 24 and 35):
records of trees unlike the shipped ones (M_T 40, 250, 600 kg) at 500 Hz-10 kHz with 0.5-5 %
noise, with the defects real records have (drift, truncation, a spike, units, file
formats), flexible trunks, and what issue 35's fuzzer found the fit claiming too much of
(noise alone, a record ending at the impact, one from the impact to the separation, both
columns in other units), simulated by an integrator written apart from the fit's solver
(make_records.py); the verdict each must get and no confident wrong answer. A subset runs
here (one seed of each cell; the full set's figures: docs/identification.md)."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from treeimpact.analytic.identify.diagnosis import DiagnosisKind
from treeimpact.analytic.identify.intervals import DETERMINED_FACTOR, TREE
from treeimpact.analytic.identify.pendulum_record import read_record
from treeimpact.analytic.identify.record_fit import Record, fit_record
from treeimpact.compare.interface.cli import main
from treeimpact.compare.runs.exits import ExitCode

DATA = Path(__file__).resolve().parent / "data" / "identify"
sys.path.insert(0, str(DATA))
import make_records as mr  # noqa: E402 - the generator, from its folder

CASES = mr.load(DATA)
#: One seed of every cell: the clean records, each tree x rate x noise, the pendulum's
#: record, each defect, the flexible trunks, issue 35's classes (63 of the 226 records).
SUBSET = [c for c in CASES if c["seed"] in (0, 1)]
META = json.loads((DATA / "cases.json").read_text())


@pytest.fixture(scope="module")
def outcomes():
    return {c["id"]: mr.evaluate(c) for c in SUBSET}


def test_the_integrator_agrees_with_the_exact_solver():
    """The records' integrator (DOP853 through the events) against the fit's exact solver
    on the three trees: the same model two ways (measured 1.3e-12 to 2.1e-12 of the peak;
    1e-9 leaves room for the integrator's rtol of 1e-12 over the events)."""
    from treeimpact.analytic.impact.solver import solve_impacts
    from treeimpact.analytic.model.two_body import TwoBodyModel

    for tree in mr.TREES.values():
        model = TwoBodyModel(dynamic_mass=tree.M_T, equivalent_damping=tree.C_T,
                             equivalent_stiffness=tree.K_T,
                             impactor_mass=tree.m, impactor_stiffness=tree.k,
                             impact_speed=tree.u1, restitution=tree.restitution)
        s = np.linspace(0.0, tree.duration, 5001)
        exact = solve_impacts(model, tree.duration).state(s)[0]
        mine = mr.simulate(tree, tree.duration)(s)[0]
        assert np.max(np.abs(mine - exact)) < 1e-9 * np.max(np.abs(exact)), tree.name


def test_the_stored_records_are_the_generator_s():
    """A stored record is what make_records.py makes of its case (float32 when noisy: to
    its 7 digits, 1e-6 of the peak)."""
    case = next(c for c in CASES if c["id"] == "B-2000Hz-2%-s3")
    t, x, _, t_c = mr.sdof_record(mr.TREES["B"], 2000.0, 0.02, 3)
    assert t_c == case["t_contact"] and np.array_equal(t, case["t"])
    assert np.max(np.abs(x - case["x"])) < 1e-6 * np.max(np.abs(x))


def test_every_record_gets_its_verdict(outcomes):
    """explained or not, M_T fixed or not, and the diagnoses the defect calls for (a
    drift, linear or bent, outliers, a truncated record, a second mode, a one-impact
    record), no unit suspicion on records in SI."""
    wrong = {k: (r["verdict"], r["diagnoses"]) for k, r in outcomes.items()
             if not r["as_expected"]}
    assert not wrong, wrong
    assert {d for r in outcomes.values() for d in r["diagnoses"]} <= {k.value for k in
                                                                      DiagnosisKind}


def test_no_confident_wrong_answer(outcomes):
    """The issue's goal: an interval of M_T, K_T, C_T, the trunk's damping ratio or e
    missing the truth while the fit says "explained" (or a record of noise alone called
    explained) in at most 5 % of the noisy records (the 95 % intervals promise that much
    each), in none of the clean ones (measured here 2 of 54 noisy, 0 of 9 clean; the full
    set: docs/identification.md)."""
    noisy = [r for r in outcomes.values() if r["noisy"]]
    clean = [r for r in outcomes.values() if r["clean"]]
    missed = [r["id"] for r in noisy if r["confident_wrong"]]
    assert len(missed) <= 0.05 * len(noisy), missed
    assert not [r["id"] for r in clean if r["confident_wrong"]]


def test_every_interval_is_in_the_physical_range(outcomes):
    """e's in [0, 1]; M_T's, K_T's, C_T's, the damping ratios' and E's above 0, or all of
    (0, inf) for a quantity the record says nothing about (the issue saw e from -0.05 to
    1.0035 and xi from -0.22)."""
    assert not [k for k, r in outcomes.items() if not r["physical"]]


def test_a_clean_record_is_recovered_to_its_accuracy(outcomes):
    """Noise-free records (no one-impact ridge): every fixed quantity within 1e-9 (the
    records agree with the fit's solver to 2e-12 of the peak; measured 2e-12 at most)."""
    for r in outcomes.values():
        if r["clean"] and r["fixed"]:
            assert max(abs(v) for v in r["errors"].values()) < 1e-9, r


@pytest.mark.parametrize("case_id", ["A-500Hz-2%-s1", "A-500Hz-2%-s2", "A-500Hz-5%-s1",
                                     "C-2000Hz-0.5%-s1"])
def test_the_global_fit_is_as_good_as_a_fit_from_the_truth(case_id):
    """The issue's local minima (tree A at 500 Hz: e 0.94 for 0.3) and one-impact branch
    (tree C): the fit's optimum is no worse than the one reached from the truth, by less
    than chi-square 1 (a 95 % interval allows 3.84; measured within 1e-6 of 0: the same
    optimum)."""
    case = next(c for c in CASES if c["id"] == case_id)
    row = mr.evaluate(case, from_truth=True)
    assert row["excess_chi2"] < 1.0, row


def test_files_as_researchers_write_them_read_as_the_plain_record():
    """A BOM and CRLF (Excel's "CSV UTF-8"), ';' with decimal commas, tabs with the units
    in the header (ms, mm), reordered and extra columns with comment lines (um), an epoch
    clock: the same record in SI (to the 9 digits written; times from 0)."""
    plain = read_record(DATA / "files" / "plain.csv")
    for name, spec in META["files"].items():
        if spec["expect"] != "same":
            continue
        rec = read_record(DATA / "files" / name)
        assert rec.t.size == plain.t.size, name
        assert np.allclose(rec.t, plain.t, rtol=0, atol=1e-9), name  # us-exact clocks
        assert np.allclose(rec.x, plain.x, rtol=1e-8, atol=0), name  # 9 digits written
    assert "columns ignored: channel, temperature" in read_record(
        DATA / "files" / "reordered-extra-comments.csv").warnings[0]


@pytest.mark.parametrize("name", ["undeclared-ms.csv", "undeclared-mm.csv",
                                  "undeclared-cm.csv", "undeclared-um.csv"])
def test_a_unit_mistake_is_named_with_the_unit_it_looks_like(name):
    """t in ms or x in mm, cm, um read as s and m: not fitted (a record 1000 x off is no
    tree's), NOT explained, the column and the likely unit named."""
    spec = META["files"][name]
    flags = META["file_flags"]
    fit = fit_record(read_record(DATA / "files" / name), mr.pendulum_test(flags))
    assert not fit.explained and fit.diagnosis_kinds() == [DiagnosisKind.UNITS]
    assert fit.diagnoses[0].message.startswith(
        f"{spec['column']} looks like {spec['unit']}, not ")
    assert all(math.isnan(v) for v in fit.values.values())


def test_the_cli_warns_of_units_on_one_line_and_in_the_json(capsys):
    flags = META["file_flags"]
    args = ["identify", str(DATA / "files" / "undeclared-mm.csv"),
            "--impactor-mass", str(flags["mass"]),
            "--equivalent-length", str(flags["equivalent_length"]), "--release-angle-deg",
            str(flags["release_angle_deg"]), "--clamp-height", str(flags["clamp_height"]),
            "--diameter", str(flags["diameter"])]
    # not fitted: exit 4 (ran, but could not do what was asked), one line naming the flag
    assert main(args) == ExitCode.NOT_ACHIEVED
    captured = capsys.readouterr()
    assert captured.err.count("\n") == 1 and "x looks like mm" in captured.err
    assert "not achieved" in captured.err and "--length-unit mm" in captured.err
    assert "NOT explained (units)" in captured.out
    assert main(args + ["--json"]) == ExitCode.NOT_ACHIEVED
    captured = capsys.readouterr()
    data = json.loads(captured.out)
    assert captured.err.count("\n") == 1 and data["explained"] is False
    assert len(data["warnings"]) == 1 and "--length-unit mm" in data["warnings"][0]
    # the paper's procedure refuses it too (issue 41: it printed M_T = 2.5e8 kg beside the
    # fit's refusal), in every reading, for the same reason
    assert data["paper"] and all(r == {"error": f"not read: {data['warnings'][0]}"}
                                 for r in data["paper"].values()), data["paper"]
    assert main(args + ["--length-unit", "mm"]) == 0  # declared: read right, fitted
    out = capsys.readouterr().out
    assert "verdict: explained" in out


# -- issue 35: where the fit claimed more than the record holds ----------------------------

NOISE_ONLY = [c for c in CASES if c.get("noise_only")]


def test_noise_alone_is_never_explained():
    """Gaussian noise and no impact (1 mm, 600 samples at 5 kHz; the fuzzer found one in four
    "explained (noise-limited)", M_T "determined" in [0.12, 48264] kg): the fitted impact is
    tested against a record without one, with the noise estimated apart from the fit (the
    rest before the contact, or the record's second differences), and refused ("no-impact",
    or not fitted when its numbers look like another unit), none of the tree's quantities
    fixed. Every noise record of the repository (20; the full set's 100: none explained)."""
    assert len(NOISE_ONLY) >= 12
    for case in NOISE_ONLY:
        fit = fit_record(Record(case["t"], case["x"]), mr.pendulum_test(case["flags"]))
        kinds = fit.diagnosis_kinds()
        assert not fit.explained, (case["id"], str(fit.conclusion))
        assert {DiagnosisKind.NO_IMPACT, DiagnosisKind.UNITS} & set(kinds), case["id"]
        assert not any(fit.determined[k] for k in TREE), case["id"]
        assert all(math.isnan(fit.values[k]) for k in TREE), case["id"]


def test_a_record_that_ends_at_the_impact_fixes_nothing_of_the_tree():
    """A logger stopped one sample into the impact (trees A and D; the fuzzer's omega_1 =
    0.031 rad/s "determined" in [0, inf]): not explained, and nothing of the tree
    "determined": that takes a bounded interval narrower than a factor 2."""
    cases = [c for c in CASES if c.get("defect") == "ends-at-impact"]
    assert len(cases) == 8
    for case in cases:
        fit = fit_record(Record(case["t"], case["x"]), mr.pendulum_test(case["flags"]))
        assert not fit.explained, case["id"]
        assert not any(fit.determined[k] for k in TREE if k != "t0"), case["id"]
        for k in TREE:  # what is called determined is bounded and narrower than the factor
            lo, hi = fit.intervals[k]
            assert not fit.determined[k] or (0 < hi < math.inf and (
                k == "t0" or hi <= DETERMINED_FACTOR * lo)), (case["id"], k, lo, hi)


def test_the_record_from_the_impact_to_the_separation_is_explained_within_2_percent():
    """Tree D from the impact to the pendulum's separation (27 ms, shorter than a period;
    5 kHz, 1 % noise; the independent integrator): no rest and no ring-down, so the sensor's
    offset and drift are held at 0 and said so ("sensor-held"; fitted, they trade with the
    motion: "NOT explained (optimiser)", M_T -19 % in the fuzzer's hands); explained, M_T
    and K_T within 2 % in the repository's four seeds (measured 0.7-1.9 % and 0.2-0.6 %;
    the full set's: docs/identification.md), every interval holding the truth."""
    cases = [c for c in CASES if c.get("short")]
    assert len(cases) == 4
    for case in cases:
        fit = fit_record(Record(case["t"], case["x"]), mr.pendulum_test(case["flags"]))
        assert fit.explained, (case["id"], str(fit.conclusion))
        assert DiagnosisKind.SENSOR_HELD in fit.diagnosis_kinds()
        assert fit.held["x_offset"] == fit.held["x_drift"] == "held at 0"
        assert fit.intervals["x_drift"] == (0.0, 0.0) and fit.values["x_drift"] == 0.0
        truth = case["truth"]
        for k in ("M_T", "K_T"):
            assert abs(fit.values[k] / truth[k] - 1.0) < 0.02, (case["id"], k)
        for k in ("M_T", "K_T", "C_T", "trunk_damping_ratio", "restitution"):
            lo, hi = fit.intervals[k]
            assert fit.determined[k] and lo <= truth[k] <= hi, (case["id"], k, lo, hi)


def test_both_columns_in_other_units_are_named_as_such():
    """t in ms and x in mm, declared as neither (a 10.6 mm peak 23 ms after the contact at
    2 kHz reads as 10.5 m after 23 s): the fuzzer's "implausible in any unit"; now both
    named, and with both declared the record is fitted and explained."""
    spec = META["files"]["undeclared-ms-mm.csv"]
    test = mr.pendulum_test(META["tree_flags"][spec["tree"]])
    fit = fit_record(read_record(DATA / "files" / "undeclared-ms-mm.csv"), test)
    assert not fit.explained and fit.diagnosis_kinds() == [DiagnosisKind.UNITS]
    assert fit.diagnoses[0].message.startswith("t looks like ms and x like mm, not s and m: ")
    assert "--time-unit ms --length-unit mm" in fit.diagnoses[0].message
    declared = fit_record(read_record(DATA / "files" / "undeclared-ms-mm.csv", time_unit="ms",
                                      length_unit="mm"), test)
    assert declared.explained and declared.determined["M_T"]
