"""The full-record fit (analytic.identify.record_fit) and `treeimpact identify`: accuracy and
interval coverage on seeded synthetic records of the exact model (the truth known), the residual
check, bad records, the JSON layout."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.identify.diagnosis import DiagnosisKind
from treeimpact.analytic.identify.procedure import pendulum_test_of
from treeimpact.analytic.identify.record_fit import Record, fit_record
from treeimpact.analytic.impact.solver import solve_impacts
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.analytic.model.two_body import two_body_model
from treeimpact.compare.interface.cli import main

RATE = 5000.0  # Hz: the sampling rate
NOISE = 0.01  # of the peak: 1 % white noise


def synthetic(e: float, seed: int, extra=None, pendulum=False, noise=None, **changes):
    """A 0.1 s record of the central-leader model (``changes`` to its TwoBodyModel fields)
    at RATE with ``noise`` (of the peak; default NOISE), contact at 10 ms; with ``pendulum``
    also the pendulum's y (the swing u_1 sin(w_2 s) / w_2 before the contact, its own
    noise of its own peak)."""
    noise = NOISE if noise is None else noise
    s = load_scenario("central-leader")
    model = dataclasses.replace(two_body_model(s), restitution=e, **changes)
    t = np.arange(0.0, 0.1, 1.0 / RATE)
    sol = solve_impacts(model, 0.1)
    state = sol.state(np.clip(t - 0.01, 0.0, 0.1))
    clean = np.where(t > 0.01, state[0], 0.0)
    if extra is not None:
        clean = clean + extra(t)
    rng = np.random.default_rng(seed)
    noisy = clean + noise * clean.max() * rng.standard_normal(t.size)
    y = None
    if pendulum:
        w2 = math.sqrt(model.impactor_stiffness / model.impactor_mass)
        y = np.where(t > 0.01, state[2], model.impact_speed * np.sin(w2 * (t - 0.01)) / w2)
        y = y + noise * np.max(np.abs(y)) * rng.standard_normal(t.size) + 0.003  # offset
    return model, Record(t, noisy, y), pendulum_test_of(s)


@pytest.mark.parametrize("e", [0.1, 0.3])
def test_fit_recovers_the_tree_within_2_percent_and_its_intervals_cover_the_truth(e):
    """Goal of the issue: within 2 % at 5 kHz and 1 % noise for e <= 0.3, intervals covering
    the truth in at least 90 % of seeded trials (10 seeds here; 20 gave 90-100 %)."""
    covered, trials = {"M_T": 0, "K_T": 0, "C_T": 0}, 10
    for seed in range(trials):
        model, record, test = synthetic(e, seed)
        fit = fit_record(record, test)
        truth = {"M_T": model.dynamic_mass, "K_T": model.equivalent_stiffness,
                 "C_T": model.equivalent_damping}
        for k, v in truth.items():
            assert abs(fit.values[k] / v - 1.0) < 0.02, (k, seed, fit.values[k], v)
            lo, hi = fit.intervals[k]
            covered[k] += lo <= v <= hi
        assert fit.explained
        assert abs(fit.values["t0"] - 0.01) < 1.0 / RATE  # the contact, within a sample
    assert all(c >= 0.8 * trials for c in covered.values()), covered  # 10 trials: 8+ of 10


def test_a_record_the_1dof_model_cannot_explain_is_said_so():
    """A second mode (40 Hz, 8 % of the peak) on top of the 1-DOF motion."""
    model, record, test = synthetic(0.1, 0, extra=lambda t: np.where(
        t > 0.01, 8e-4 * np.sin(2 * np.pi * 40 * (t - 0.01)), 0.0))
    fit = fit_record(record, test)
    assert not fit.explained and fit.residual_rms > 0.03 * fit.peak


#: The central-leader tree with a crown four times the trunk's mass (M_T 557 kg, the
#: identification study's crown-4 cell): the pendulum (132 kg) rebounds off it and does not
#: come back within 0.1 s, so the record is V_1 psi(t) of the tree oscillator alone.
HEAVY = {"dynamic_mass": 556.8}


def test_a_one_impact_record_fixes_omega_xi_and_v1_and_gives_m_and_e_as_ranges():
    """x(t) = V_1 psi(t; omega_1, xi) after a single impact: (M_T, e) on the curve
    M_T + m = m (1 + e) u_1 / V_1 give the same record, so no fit can pick one (the study's
    crown-4, e = 0.3 cell landed at +26 % with the best residual). The fit says so from
    the data (e's profile within the 95 % threshold up to the top, its top a one-impact
    model), keeps what is fixed, and its ranges hold the truth."""
    import math

    from treeimpact.analytic.identify.fit_model import model_x, two_body_at
    from treeimpact.analytic.identify.fit_parameters import Slot
    from treeimpact.analytic.identify.one_impact import on_ridge

    model, record, test = synthetic(0.3, 0, **HEAVY)
    fit = fit_record(record, test)
    assert "does not return" in fit.note and DiagnosisKind.ONE_IMPACT in fit.diagnosis_kinds()
    assert fit.explained
    assert not any(fit.determined[k] for k in ("M_T", "K_T", "C_T", "restitution", "E"))
    assert all(math.isnan(fit.values[k]) for k in ("M_T", "K_T", "restitution"))
    omega = math.sqrt(model.equivalent_stiffness / model.dynamic_mass)
    m, u = model.impactor_mass, model.impact_speed
    v1 = m * (1.0 + model.restitution) * u / (model.dynamic_mass + m)
    for k, v in (("omega_1", omega), ("V_1", v1)):
        assert fit.determined[k] and abs(fit.values[k] / v - 1.0) < 0.01, (k, fit.values[k], v)
    for k, v in (("M_T", model.dynamic_mass), ("K_T", model.equivalent_stiffness),
                 ("restitution", 0.3)):
        lo, hi = fit.intervals[k]
        assert lo <= v <= hi, (k, lo, v, hi)
    e_low, e_high = fit.intervals["restitution"]
    # the low end: the profile's first point outside the threshold below the truth (its grid
    # spacing is 0.1; measured 0.2), where the pendulum would come back
    assert e_high == 1.0 and 0.15 < e_low < 0.3
    # the ridge is exact while the pendulum stays away: the same x from the truth's e to 1
    # (the fit's point is on the ridge)
    same = model_x(fit.point, test, record.t)
    span = float(record.t[-1] - fit.point[Slot.T0])
    for e in (0.3, 0.65, 1.0):
        moved = on_ridge(fit.point, e, test)
        assert len(solve_impacts(two_body_at(moved, test), span).impacts) == 1
        assert np.allclose(model_x(moved, test, record.t), same,
                           rtol=0.0, atol=1e-12 * np.max(np.abs(same)))
    # ... and well below the range's low end it is not: the pendulum comes back
    sol = solve_impacts(two_body_at(on_ridge(fit.point, e_low - 0.1, test), test), span)
    assert len(sol.impacts) > 1 or sol.together_starts


@pytest.mark.parametrize("seed", range(5))
def test_a_known_restitution_fixes_the_one_impact_record_within_2_percent(seed):
    """With e given (the pad's, --restitution) the same record fixes M_T, K_T, C_T; e's
    interval is its value, exactly (issue 35: 0.5 came out as [0.5000000000000001,
    0.5000000000000001], which excludes it)."""
    model, record, test = synthetic(0.3, seed, **HEAVY)
    fit = fit_record(record, test, restitution=0.3)
    assert fit.note == "" and fit.values["restitution"] == 0.3
    assert fit.intervals["restitution"] == (0.3, 0.3) and fit.held["restitution"] == "given"
    assert fit.determined["restitution"]
    for k, v in (("M_T", model.dynamic_mass), ("K_T", model.equivalent_stiffness),
                 ("C_T", model.equivalent_damping)):
        assert abs(fit.values[k] / v - 1.0) < 0.02, (k, fit.values[k], v)


def test_the_pendulum_s_record_fixes_the_one_impact_record_within_2_percent():
    """With y the pendulum's rebound v = (m - M_T e) u_1 / (M_T + m) (eq 54) is in the
    record: with V_1 it fixes M_T = m (u_1 - v) / V_1 and e apart; the fit uses it (x and y,
    each weighted by its own noise), the sensor's offset (3 mm) fitted. 10 seeds: every
    one within 2 %, 95 % intervals covering the truth in 8+ of 10 (measured 9-10)."""
    covered, trials = {"M_T": 0, "K_T": 0, "C_T": 0, "restitution": 0}, 10
    for seed in range(trials):
        model, record, test = synthetic(0.3, seed, pendulum=True, **HEAVY)
        fit = fit_record(record, test)
        assert fit.note == "" and all(fit.determined.values())
        for k, v in (("M_T", model.dynamic_mass), ("K_T", model.equivalent_stiffness),
                     ("C_T", model.equivalent_damping), ("restitution", 0.3)):
            assert abs(fit.values[k] / v - 1.0) < 0.02, (k, seed, fit.values[k], v)
            lo, hi = fit.intervals[k]
            covered[k] += lo <= v <= hi
        assert abs(fit.values["y_offset"] - 0.003) < 1e-3 and fit.explained
        assert fit.residual_rms_y < 0.02 * np.max(np.abs(record.y))
    assert all(c >= 0.8 * trials for c in covered.values()), covered


def test_identify_says_what_a_one_impact_record_does_not_fix(tmp_path, capsys):
    _, record, _ = synthetic(0.3, 0, **HEAVY)
    path = tmp_path / "rec.csv"
    np.savetxt(path, np.column_stack([record.t, record.x]), delimiter=",", header="t,x",
               comments="")
    assert main(["identify", str(path), *ARGS]) == 0
    out = capsys.readouterr().out
    assert "not fixed" in out and "--restitution" in out
    assert main(["identify", str(path), *ARGS, "--restitution", "0.3"]) == 0
    out = capsys.readouterr().out
    assert "not fixed" not in out and "given" in out
    assert main(["identify", str(path), *ARGS, "--restitution", "1.5"]) == 2
    err = capsys.readouterr().err
    assert "--restitution = 1.5" in err and "[0, 1]" in err and err.count("\n") == 1


ARGS = ["--impactor-mass", "132.4", "--equivalent-length", "1.51", "--release-angle-deg", "36.39",
        "--clamp-height", "0.315", "--diameter", "0.126"]


def test_identify_json_layout_and_plot(tmp_path, capsys):
    model, record, _ = synthetic(0.1, 1)
    path = tmp_path / "rec.csv"
    np.savetxt(path, np.column_stack([record.t, record.x]), delimiter=",", header="t,x",
               comments="")
    assert main(["identify", str(path), *ARGS, "--json", "--plot", str(tmp_path / "f.png")]) == 0
    data = json.loads(capsys.readouterr().out)
    assert set(data) == {"fit", "paper", "definitions", "residual_rms", "residual_rms_y",
                         "explained", "note", "held", "verdict", "diagnoses", "noise",
                         "noise_source", "misfit_ratio", "flagged_rows", "warnings",
                         "provenance"}
    assert data["held"] == {"x_drift2": "held at 0"}  # a bend only where the record needs it
    import hashlib

    prov = data["provenance"]  # the record by its bytes, the code, the engines' versions
    assert prov["record"]["sha1"] == hashlib.sha1(path.read_bytes()).hexdigest()
    assert prov["record"]["samples"] == record.t.size and prov["test"]["impactor_mass"] == 132.4
    assert {"code", "environment"} <= set(prov)
    # the two damping ratios, by name and formula; the paper's xi (b / omega_n) is the pair's
    assert set(data["definitions"]) == {"trunk_damping_ratio", "pair_damping_ratio"}
    fit, m, k = data["fit"], 132.4, 132.4 * 9.81 / 1.51
    M, K, C = (fit[q]["value"] for q in ("M_T", "K_T", "C_T"))
    assert fit["trunk_damping_ratio"]["value"] == pytest.approx(C / (2 * (K * M) ** 0.5),
                                                                rel=1e-9)
    assert fit["pair_damping_ratio"]["value"] == pytest.approx(
        C / (2 * ((K + k) * (M + m)) ** 0.5), rel=1e-9)
    assert "pair_damping_ratio" in data["paper"]["paper"] and "xi" not in data["paper"]["paper"]
    assert data["verdict"] == "explained" and data["diagnoses"][0]["kind"] == "noise-limited"
    assert data["warnings"] == [] and data["flagged_rows"] == []
    assert {"M_T", "K_T", "C_T", "trunk_damping_ratio", "pair_damping_ratio", "restitution", "E",
            "omega_1", "V_1"} <= set(data["fit"])
    assert set(data["fit"]["M_T"]) == {"value", "low", "high", "determined", "held"}
    assert data["fit"]["M_T"]["determined"] is True and data["note"] == ""
    assert data["fit"]["M_T"]["value"] == pytest.approx(model.dynamic_mass, rel=0.02)
    assert set(data["paper"]) == {"paper", "printed", "consistent"}
    assert data["explained"] is True
    assert (tmp_path / "f.png").read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize("text, words", [
    ("tt,x\n0,0\n", "header 'tt,x'"),
    ("t,x\n" + "".join(f"{i * 1e-3},{0.0 if i < 5 else 1e-3}\n" for i in range(10)),
     "10 samples; at least 20"),
    ("t,x\n" + "".join(f"{(i if i != 7 else 3) * 1e-3},{i * 1e-4}\n" for i in range(30)),
     "time t does not increase at row"),
    ("t,x\n" + "".join(f"{i * 1e-3},{'nan' if i == 4 else i * 1e-4}\n" for i in range(30)),
     "x is not a finite number at row 6"),
    ("t,x\n" + "".join(f"{i * 1e-3},0.002\n" for i in range(30)), "holds no impact"),
    ("t,x\n0,abc\n", "not a number"),
])
@pytest.mark.blas_free
def test_bad_records_are_one_line_and_exit_2(tmp_path, capsys, text, words):
    path = tmp_path / "rec.csv"
    path.write_text(text)
    assert main(["identify", str(path), *ARGS]) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1, err


@pytest.mark.blas_free
def test_record_checks_name_the_row():
    t = np.linspace(0.0, 0.1, 50)
    with pytest.raises(ParameterError, match="row 12"):
        Record(t, np.where(np.arange(50) == 10, np.inf, t))


def test_log_interval_of_an_undetermined_parameter_is_zero_to_infinity_without_warnings():
    """A direction the record does not determine (a singular Jacobian) has a huge standard
    deviation in logarithm: its 95 % interval is (0, inf), said so, not an overflow."""
    import math
    import warnings

    from treeimpact.analytic.identify.record_fit import log_interval

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert log_interval(2.0, 1e3) == (0.0, math.inf)
        lo, hi = log_interval(2.0, 0.1)
    assert (lo, hi) == pytest.approx((2.0 * math.exp(-0.1), 2.0 * math.exp(0.1)), rel=1e-15)
    assert all(math.isnan(v) for v in log_interval(2.0, math.nan))


def test_a_held_restitution_is_its_own_interval_and_determined_means_narrower_than_2x():
    """e held (given): its interval is its value exactly, at every e, not e's image through
    asin(sqrt(e)) and back; "determined": a bounded interval whose high end is at most twice
    its low end (intervals.DETERMINED_FACTOR), else "not fixed"."""
    from treeimpact.analytic.identify.intervals import (
        DETERMINED_FACTOR,
        determined,
        restitution_interval,
    )

    for e in (0.0, 0.1, 0.3, 0.5, 0.7, 0.95, 1.0):
        assert restitution_interval(e, 0.0) == (e, e)
    assert DETERMINED_FACTOR == 2.0
    assert determined("M_T", (50.0, 100.0)) and not determined("M_T", (50.0, 100.5))
    assert not determined("omega_1", (0.0, math.inf))  # the fuzzer's "determined" omega_1
    assert not determined("restitution", (0.0, 0.2)) and determined("restitution", (0.2, 0.3))
    assert determined("t0", (0.01, 0.02)) and not determined("t0", (-math.inf, 0.02))


@pytest.mark.parametrize("text, flags, words", [
    ("t [min],x\n0,0\n", [], "unit 'min'; allowed s, ms, us"),
    ("t [s],x\n" + "".join(f"{i * 1e-3},{i * 1e-4}\n" for i in range(30)),
     ["--time-unit", "ms"], "is in s, but --time-unit says ms"),
    ("0,0\n" + "".join(f"{i * 1e-3},{i * 1e-4}\n" for i in range(30)), [],
     "line 1 is numbers, not a header"),
    ("# a comment\nt;x\n" + "".join(f"{i * 1e-3};{i * 1e-4}\n".replace(".", ",")
                                    for i in range(10)) + "0,011;\n", [],
     "row 13 has no value in column 'x'"),
    ("t,x,t\n0,0,0\n", [], "has 2 column(s) t"),
])
@pytest.mark.blas_free
def test_bad_headers_and_cells_are_one_line_and_exit_2(tmp_path, capsys, text, flags, words):
    """Units and headers: an unknown unit, a flag that contradicts the header, no header, a
    missing cell (its row as in the file, after a comment line), a column twice."""
    path = tmp_path / "rec.csv"
    path.write_text(text)
    assert main(["identify", str(path), *ARGS, *flags]) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1, err


def test_simulate_writes_a_record_identify_reads(tmp_path, capsys):
    """`simulate --record`: the trunk's x at the rate asked, from 20 ms before the impact,
    with the noise asked (of the peak); --json keeps stdout JSON; a rate or noise out of
    range is one line naming the flag and its range."""
    from treeimpact.analytic.identify.pendulum_record import read_record

    path = tmp_path / "rec.csv"
    assert main(["simulate", "central-leader", "--record", str(path), "--rate", "2000",
                 "--noise", "0.02", "--seed", "3", "--json"]) == 0
    json.loads(capsys.readouterr().out)  # stdout holds only the JSON
    rec = read_record(path)
    assert np.allclose(np.diff(rec.t), 5e-4) and rec.x.size == 240  # 0.12 s at 2 kHz
    before = rec.x[rec.t < 0.019]  # rest: the noise alone (2 % of the peak, 38 samples)
    assert 0.01 < np.std(before) / np.max(np.abs(rec.x)) < 0.03
    for flag, value, words in (("--rate", "10", "--rate = 10.0 Hz is out of range: allowed "
                                "[50, 1e+06] Hz"), ("--noise", "2", "--noise = 2.0 is out of "
                                                    "range: allowed [0, 0.5]")):
        assert main(["simulate", "central-leader", "--record", str(path), flag, value]) == 2
        err = capsys.readouterr().err
        assert words in err and err.count("\n") == 1, err
