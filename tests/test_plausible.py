"""Plausible slips (issue 50 item 7): an input inside its allowed range but outside what
fruit trees and harvesters show is run and warned about, one line naming the field, the
range and its source, and the unit slip that would bring it inside; declared once, with the
parameter (analytic/model/registry.py ``plausible``)."""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

import treeimpact as ti
from treeimpact.analytic.errors import ImplausibleInput
from treeimpact.analytic.model import registry
from treeimpact.analytic.model.plausible import implausible, implausible_values
from treeimpact.analytic.model.scenario import load_scenario, shipped_scenarios

SCENARIOS = Path(ti.__file__).resolve().parents[1] / "analytic" / "model" / "scenarios"
TREE = dict(clamp_height=0.315, diameter=0.126, impactor_mass=132.4, equivalent_length=1.51,
            release_angle_deg=36.39, youngs_modulus=9e9, dynamic_mass=110.0,
            equivalent_stiffness=1.5e6, damping_rate=29.835)


def _caught(build):
    """The ImplausibleInput messages ``build()`` warns, and its result."""
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        out = build()
    return [str(w.message) for w in seen if issubclass(w.category, ImplausibleInput)], out


def _edited(tmp_path, old: str, new: str) -> Path:
    """central-leader's file with the line starting ``old`` set to ``new``."""
    text = (SCENARIOS / "central-leader.toml").read_text()
    line = re.search(rf"^{re.escape(old)}.*$", text, flags=re.M).group(0)
    path = tmp_path / "slip.toml"
    path.write_text(text.replace(line, new))
    return path


def test_every_plausible_range_lies_inside_the_allowed_one():
    """A plausible range narrows the allowed one (a warning, never a second refusal)."""
    declared = [p for p in registry.PARAMETERS if p.plausible is not None]
    assert {p.name for p in declared} >= {"release_angle_deg", "diameter", "impactor_mass"}
    for p in declared:
        assert p.low <= p.plausible.low < p.plausible.high <= p.high, p.name
        assert p.path is not None and p.plausible.source, p.name


@pytest.mark.parametrize("name", shipped_scenarios())
def test_the_shipped_trees_warn_nothing(name):
    """The paper's trees and the realistic crown are what trees and harvesters show."""
    found, _ = _caught(lambda: load_scenario(name))
    assert found == []


def test_a_release_angle_in_radians_is_run_and_warned_with_its_degrees(tmp_path):
    """0.635 typed as degrees: 0.635 rad is 36.38 deg (central-leader's 36.39 deg), inside
    2-90 deg, so the warning names the slip; the scenario is built as given."""
    path = _edited(tmp_path, "release_angle_deg", "release_angle_deg = 0.635")
    found, scen = _caught(lambda: load_scenario(path))
    assert scen.impactor.release_angle_deg == 0.635  # run as given, not corrected
    assert len(found) == 1 and "\n" not in found[0]
    assert found[0].startswith("impactor.release_angle_deg = 0.635 deg")
    assert "2-90 deg" in found[0] and "radians" in found[0]
    assert f"{math.degrees(0.635):.4g} deg" in found[0]  # 36.38, the closed form


def test_a_diameter_in_centimetres_names_the_slip_and_a_huge_one_only_the_range():
    """2.5 (cm typed as m) reads 0.025 m, inside 0.02-0.5 m: the slip is named; 1.2 m is
    inside no slip's reading (12 mm and 1.2 mm are below 2 cm): the range only."""
    (cm,) = implausible_values({"trunk.diameter": 2.5})
    assert "centimetres? 2.5 centimetres is 0.025 m" in cm.text
    (big,) = implausible_values({"trunk.diameter": 1.2})
    assert big.slip == "" and "0.02-0.5 m" in big.text
    assert implausible_values({"trunk.diameter": 0.5, "trunk.length": None}) == ()  # ends in


def test_a_billet_and_a_stiffness_given_pad_are_read_only_where_they_have_the_field():
    """A billet has no release angle and a pendulum's impact speed is derived (its angle
    warns, not a second line for the speed it implies)."""
    scen = load_scenario("central-leader")
    slow = scen.__class__(**{**scen.__dict__, "impactor": ti.Pendulum(
        mass=132.4, equivalent_length=1.51, release_angle_deg=0.635)})
    assert [i.path for i in implausible(slow)] == ["impactor.release_angle_deg"]


def test_tree_scenario_warns_what_it_was_given():
    """ti.tree_scenario (the ``scenario`` command's builder) warns at its boundary."""
    found, scen = _caught(lambda: ti.tree_scenario("t", **{**TREE, "release_angle_deg": 1.5}))
    assert scen.impactor.release_angle_deg == 1.5
    assert [f.split(" = ")[0] for f in found] == ["impactor.release_angle_deg"]
    assert f"{math.degrees(1.5):.4g} deg" in found[0]  # 1.5 rad = 85.94 deg: the slip


def test_the_cli_runs_the_slip_and_warns_in_one_line_each(tmp_path):
    """``simulate`` of a file with the angle in radians: exit 0, numbers on stdout, and on
    stderr one line per implausible input, in the project's words (no Python source
    location, no category name)."""
    path = _edited(tmp_path, "release_angle_deg", "release_angle_deg = 0.635")
    proc = subprocess.run([sys.executable, "-m", "treeimpact.compare.interface.cli", "simulate",
                           str(path), "--json"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["metrics"]["x_max"] > 0
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("treeimpact: warning: impactor.release_angle_deg = 0.635 deg")
    assert lines[0].endswith("; run as given")
    assert "ImplausibleInput" not in lines[0] and ".py:" not in lines[0]


def test_a_refusal_keeps_its_one_line_and_carries_the_slip_that_may_explain_it(tmp_path):
    """The same file on the soft rung with a 1 us pad (beyond the run's budget): exit 2,
    one stderr line, the refusal first and the implausible input as its note (not 'run as
    given': it was not run)."""
    path = _edited(tmp_path, "release_angle_deg", "release_angle_deg = 0.635")
    proc = subprocess.run([sys.executable, "-m", "treeimpact.compare.interface.cli", "simulate",
                           str(path), "--backend", "soft", "--contact-duration", "1e-6"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1 and proc.stderr.startswith("treeimpact: error: ")
    assert "(note: impactor.release_angle_deg = 0.635 deg" in proc.stderr
    assert "run as given" not in proc.stderr
