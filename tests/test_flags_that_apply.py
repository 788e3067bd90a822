"""Issue 41 items 4 and 7: a flag the run ignores is refused like ``--segments`` with the SDOF
trunk (exit 2, one line naming the flag as typed and why it does not apply); a too-short
t_end is exit 2 with one worded line on every trunk of every backend; a result outside the
model's validity is its own run status, never "diverged"."""

from __future__ import annotations

import pytest

from treeimpact.compare.interface.cli import main
from treeimpact.analytic.model.options import scenario_as_run


def one_line(capsys, argv, code) -> str:
    """Run the CLI in-process: exit ``code``, one stderr line, no traceback; the line."""
    rc = main(argv)
    err = capsys.readouterr().err
    assert rc == code, err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


@pytest.mark.parametrize("backend", ["mujoco", "bullet"])
@pytest.mark.parametrize("flag, value, why", [
    ("--trunk-damping-model", "joint", "damping is C_T at the clamp"),
    ("--trunk-damping-model", "distributed", "damping is C_T at the clamp"),
    ("--calibration", "effective", "'pad' and 'effective' set the same pad"),
])
def test_a_chain_flag_with_the_sdof_trunk_is_refused(capsys, backend, flag, value, why):
    """Was accepted and echoed though the run is the same without it."""
    err = one_line(capsys, ["simulate", "central-leader", "--backend", backend, "--trunk",
                            "sdof", flag, value], 2)
    assert f"{flag} = {value!r}: only for a --trunk with segments, not --trunk sdof" in err
    assert why in err


def test_the_chain_flags_still_apply_to_the_chain():
    """The refusal is the SDOF trunk's only: the chain's joint damping changes its run."""
    from treeimpact.analytic.model.scenario import load_scenario
    from treeimpact.mujoco_models import simulate

    s = load_scenario("central-leader")
    base = simulate(scenario_as_run(s, {"t_end": 0.03}), trunk="chain", segments=4)
    joint = simulate(scenario_as_run(s, {"t_end": 0.03}),
                     trunk="chain", segments=4, trunk_damping_model="joint")
    assert joint.metrics["x_max"] != base.metrics["x_max"]


@pytest.mark.parametrize("argv", [
    ["--backend", "mujoco", "--trunk", "chain"],
    ["--backend", "mujoco", "--trunk", "flex"],
    ["--backend", "mujoco", "--trunk", "sdof"],
    ["--backend", "bullet", "--trunk", "sdof"],
    ["--backend", "soft"],
    ["--backend", "analytic"],
])
def test_a_too_short_t_end_is_bad_input_in_the_same_words(capsys, argv):
    """MuJoCo's SDOF trunk said "diverged" (exit 3: its peak one step and a part past
    t_end), the flex rod exit 2; the soft rung named the scenario's t_end, not the one
    typed."""
    err = one_line(capsys, ["simulate", "central-leader", *argv, "--t-end", "0.0002"], 2)
    assert err.startswith("treeimpact: error: --t-end = 0.0002 s is too short for this run ")
    assert err.rstrip().endswith(": a longer --t-end")


def test_outside_validity_is_its_own_run_status():
    """runs.attempt recorded an OutsideValidity as DIVERGED ("diverged: ..."); a real
    divergence stays DIVERGED."""
    from treeimpact.analytic.errors import OutsideValidity, SimulationDiverged
    from treeimpact.analytic.model.scenario import load_scenario
    from treeimpact.compare.runs.cache import DIVERGED, OUTSIDE, attempt

    class Raising:
        name = "raising"

        def __init__(self, exc):
            self.exc = exc

        def simulate(self, scenario, **options):
            raise self.exc

    s = load_scenario("open-center")
    out = attempt(Raising(OutsideValidity("x_max = 2 m beyond the clamp height")), s, {})
    assert out.status == OUTSIDE and out.status == "outside validity"
    assert out.reason == "outside the model's validity: x_max = 2 m beyond the clamp height"
    gone = attempt(Raising(SimulationDiverged("energy grew")), s, {})
    assert gone.status == DIVERGED and gone.reason == "diverged: energy grew"
