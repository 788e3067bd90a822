"""Every refusal names the field or flag as typed and the value that would work, in one
stderr line with exit 2, checked on the command line in a subprocess (issue 54): a derived
field's range named by the flag that set it, every bad flag of a run named, a budget's
refusal naming the contact duration that fits, a record's absurd values refused before
any arithmetic (no numpy warning), and a run too short for its event exit 2 on every
backend and option."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.calibration import MeasuredTree, calibrate_trunk
from treeimpact.analytic.model.parameters import LIMITS, Trunk

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "analytic" / "model" / "scenarios"
#: The issue's tree (central-leader's test), as the scenario command's flags.
TREE = ["--clamp-height", "0.315", "--diameter", "0.126", "--impactor-mass", "132.4",
        "--equivalent-length", "1.51", "--release-angle-deg", "36.39", "--youngs-modulus",
        "9e9"]
TEST = ["--impactor-mass", "132.4", "--equivalent-length", "1.51", "--release-angle-deg",
        "36.39", "--clamp-height", "0.315", "--diameter", "0.126"]


def cli(*argv, env=None) -> tuple[int, str, str]:
    """(exit code, stdout, stderr) of ``treeimpact argv`` in its own process."""
    proc = subprocess.run([sys.executable, "-m", "treeimpact.compare.interface.cli", *argv],
                          capture_output=True, text=True, cwd=ROOT,
                          env={**os.environ, **(env or {})}, check=False)
    return proc.returncode, proc.stdout, proc.stderr


def refused(*argv, env=None) -> str:
    """The one stderr line of a command refused as bad input (exit 2, no traceback)."""
    code, _, err = cli(*argv, env=env)
    assert code == 2, (argv, code, err)
    assert err.count("\n") == 1 and err.startswith("treeimpact: error: "), err
    return err


# -- a record's absurd values: refused at read time, naming the column and row -----------

def _record(path: Path, rows) -> str:
    """A record file of ``rows`` (t, x) or (t, x, y), SI."""
    head = "t [s],x [m]" + (",y [m]" if len(rows[0]) == 3 else "")
    path.write_text(head + "\n" + "".join(",".join(map(repr, r)) + "\n" for r in rows))
    return str(path)


@pytest.mark.parametrize(("column", "rows", "words"), [
    ("x", [(i / 5000, (-1) ** i * 1.7e308) for i in range(600)],
     "x = 1.7e+308 m at row 2 is out of range: allowed |x| <= 1e+09 m"),
    ("x", [(i / 5000, 1.7e308 if i > 300 else 0.0) for i in range(600)],
     "x = 1.7e+308 m at row 303"),
    ("y", [(i / 5000, 1e-3 * (i > 300), 1.7e308 if i == 400 else 1e-3 * (i < 300))
           for i in range(600)], "y = 1.7e+308 m at row 402"),
    ("t", [(i * 1e300, 1e-3 * (i > 300)) for i in range(600)],
     "t = 1e+300 s at row 3 is out of range: allowed |t| <= 1e+12 s"),
])
def test_a_record_of_huge_values_is_one_line_naming_the_column(column, rows, words, tmp_path):
    """+-1.7e308 printed three numpy overflow RuntimeWarnings before the refusal; now the
    record is refused before any arithmetic: one line, the column, the row, the range."""
    err = refused("identify", _record(tmp_path / "r.csv", rows), *TEST)
    assert words in err and "Warning" not in err, err


def test_a_record_just_inside_the_range_is_read_without_warnings(tmp_path):
    """x up to 9e8 m is read (and judged implausible in any unit: exit 4), no warning."""
    path = _record(tmp_path / "r.csv", [(i / 5000, (-1) ** i * 9e8) for i in range(600)])
    code, _, err = cli("identify", path, *TEST)
    assert code == 4 and err.count("\n") == 1 and "Warning" not in err, err


# -- a derived field's range, named by the flag that set it --------------------------------

def _allowed(err: str, flag: str, unit: str) -> tuple[float, float]:
    m = re.search(rf"{re.escape(flag)} = \S+ {re.escape(unit)}: .*; allowed \[(\S+), (\S+)\] "
                  rf"{re.escape(unit)}", err)
    assert m, err
    return float(m.group(1)), float(m.group(2))


def test_scenario_names_dynamic_mass_and_its_range_not_the_crown_mass():
    """--dynamic-mass 1e6 said "trunk.crown_mass = 92742 kg is out of range"; now it names
    --dynamic-mass and its range, whose ends calibrate to a crown mass of 0 and of the
    largest trunk.crown_mass (the Trunk's own range check, the independent judge)."""
    err = refused("scenario", "t", *TREE, "--dynamic-mass", "1e6", "--damping-rate", "5",
                  "--equivalent-stiffness", "1.5e6")
    assert "crown_mass" not in err
    low, high = _allowed(err, "--dynamic-mass", "kg")
    chosen = Trunk(length=1.0, clamp_height=0.315, diameter=0.126, density=950.0,
                   youngs_modulus=9e9, clamp_mass=4.0)
    crown_max = LIMITS["trunk.crown_mass"][1]
    for m_t, crown in ((low * (1 + 1e-5), 0.0), (high * (1 - 1e-5), crown_max)):
        trunk = calibrate_trunk(chosen, MeasuredTree(m_t, 1.5e6, 5.0), impactor_mass=132.4)
        # 1e-4 of the range: the ends are printed to 6 digits (1e-6) and stepped 1e-5 in
        assert abs(trunk.crown_mass - crown) <= 1e-4 * crown_max
    for m_t in (low * (1 - 1e-5), high * (1 + 1e-5)):
        with pytest.raises(ParameterError, match=r"^dynamic_mass = "):
            calibrate_trunk(chosen, MeasuredTree(m_t, 1.5e6, 5.0), impactor_mass=132.4)


@pytest.mark.parametrize(("flags", "flag", "unit", "field"), [
    (["--equivalent-stiffness", "1", "--damping-rate", "5"], "--equivalent-stiffness", "N/m",
     "base_stiffness"),
    (["--equivalent-stiffness", "1.5e6", "--damping-rate", "1e6"], "--damping-rate", "1/s",
     "damping"),
])
def test_scenario_names_the_flag_of_every_derived_field(flags, flag, unit, field):
    """K_T = 1 named trunk.base_stiffness, b = 1e6 trunk.damping; now the flag typed and
    the range that calibrates within the field's (checked by calibrating at its end)."""
    err = refused("scenario", "t", *TREE, "--dynamic-mass", "110", *flags)
    assert f"trunk.{field}" not in err
    _, high = _allowed(err, flag, unit)
    chosen = Trunk(length=1.0, clamp_height=0.315, diameter=0.126, density=950.0,
                   youngs_modulus=9e9, clamp_mass=4.0)
    if field == "damping":  # b at its end: C = 2 b (M_T + m) / J at the field's largest
        trunk = calibrate_trunk(chosen, MeasuredTree(110.0, 1.5e6, high * (1 - 1e-5)),
                                impactor_mass=132.4)
        assert trunk.damping <= LIMITS["trunk.damping"][1]
        with pytest.raises(ParameterError, match=r"^damping_rate = "):
            calibrate_trunk(chosen, MeasuredTree(110.0, 1.5e6, high * (1 + 1e-5)),
                            impactor_mass=132.4)
    else:  # K_T at the low end: the root spring at the field's smallest
        low, _ = _allowed(err, flag, unit)
        trunk = calibrate_trunk(chosen, MeasuredTree(110.0, low * (1 + 1e-5), 5.0),
                                impactor_mass=132.4)
        assert trunk.base_stiffness >= LIMITS["trunk.base_stiffness"][0]
        with pytest.raises(ParameterError, match=r"^equivalent_stiffness = "):
            calibrate_trunk(chosen, MeasuredTree(110.0, low * (1 - 1e-5), 5.0),
                            impactor_mass=132.4)


# -- every bad flag of a run named ----------------------------------------------------------

def test_every_refused_option_of_a_run_is_named_with_its_range():
    """--trunk flex --segments 1001 on Bullet named --trunk only."""
    err = refused("simulate", "central-leader", "--backend", "bullet", "--trunk", "flex",
                  "--segments", "1001")
    assert "--trunk = 'flex': allowed sdof, chain" in err
    assert "--segments = 1001 is out of range: allowed [2, 127]" in err


# -- the budget names the contact duration that fits ----------------------------------------

def test_the_soft_contact_s_budget_names_contact_duration_and_the_shortest_that_fits(tmp_path):
    """contact.duration = 1e-6 said "beyond its budget: 1.7e+07 steps" alone."""
    text = (SCENARIOS / "central-leader.toml").read_text()
    path = tmp_path / "short-pad.toml"
    path.write_text(re.sub(r"(?m)^duration = .*$", "duration = 1e-6", text))
    err = refused("simulate", str(path), "--backend", "soft")
    assert "contact.duration = 1e-06 s: the run is beyond its budget" in err
    assert re.search(r"allowed contact\.duration >= \S+ s at this t_end", err), err


@pytest.mark.parametrize("backend", [["soft"], ["beam"], ["beam", "--calibration", "effective"]])
def test_the_duration_the_budget_names_fits_it_and_a_shorter_one_does_not(backend):
    """Under a budget of 1e5 steps (cheap runs): the duration named runs, 2 % less (below
    its 3-digit rounding up, at most 1 %) is refused again; on the beam too, whose
    effective convention recalibrates c_c and so the collision's time."""
    env = {"TREEIMPACT_MAX_STEPS": "1e5"}
    run = ["simulate", "central-leader", "--backend", *backend, "--contact-duration"]
    err = refused(*run, "1e-5", env=env)
    shortest = float(re.search(r"allowed --contact-duration >= (\S+) s", err).group(1))
    code, _, err = cli(*run, repr(shortest), env=env)
    assert code == 0, err
    err = refused(*run, repr(0.98 * shortest), env=env)
    assert "beyond its budget" in err


# -- a run too short for its event: exit 2 on every backend and option ----------------------

@pytest.mark.parametrize("options", [
    ["--backend", "analytic"], ["--backend", "soft"], ["--backend", "beam"],
    ["--backend", "mujoco", "--trunk", "sdof"], ["--backend", "mujoco", "--trunk", "chain"],
    ["--backend", "mujoco", "--trunk", "sdof", "--pendulum", "full"],
    ["--backend", "mujoco", "--trunk", "chain", "--pendulum", "full"],
    ["--backend", "bullet", "--trunk", "sdof"], ["--backend", "bullet", "--trunk", "chain"],
    ["--backend", "bullet", "--trunk", "chain", "--pendulum", "full"],
], ids=lambda o: "-".join(o[1::2]))
def test_a_run_too_short_for_its_event_is_bad_input_naming_t_end(options):
    """MuJoCo's full pendulum at --t-end 1e-4 exited 3 "simulation diverged" (its t_xmax
    after t_end, inside what it simulated past it) where the linear one exited 2; the beam
    named the scenario's t_end (0.1 s), not the one typed."""
    err = refused("simulate", "central-leader", *options, "--t-end", "1e-4")
    assert "--t-end = 0.0001 s is too short for this run" in err and "a longer --t-end" in err


def test_a_damping_rate_from_the_regression_names_a1_and_a2():
    """b = -a2/a1 beyond its range named --damping-rate, which was not typed; now the
    regression's flags lead the line, with b's range."""
    err = refused("scenario", "t", *TREE, "--dynamic-mass", "110", "--a1", "100",
                  "--a2=-1e6", "--equivalent-stiffness", "1.5e6")
    assert err.startswith("treeimpact: error: --a1 = 100 m/s, --a2 = -1e+06 m/s^2 give b")
    assert "--damping-rate" not in err and re.search(r"allowed \[0, \S+\] 1/s", err), err
