"""The MuJoCo runner: roll compiled setups out with ``mujoco.rollout`` and turn the records
into results; the engine interface's names in one place.

The model and its setup: :mod:`._setup`; the stepping: :mod:`._rollout`; record ->
metrics: :mod:`._record`; the trunk's modes: :mod:`._modes`; MuJoCo's warnings:
:mod:`._warnings`. Design notes and measured figures: docs/engines.md.
"""

from __future__ import annotations

import os

from treeimpact.analytic.errors import SimulationDiverged
from treeimpact.analytic.model.parameters import Scenario
from treeimpact.analytic.results import SimulationResult

from ._matrices import engine_trunk_matrices, flex_trunk_matrices, highest_frequency
from ._modes import flex_modes, modes
from ._record import _result
from ._rollout import _plan, _run_group, _signature
from ._setup import Setup, build_model, make_setup
from ._warnings import collected_warnings, mujoco_warnings, tell
from .options import OPTIONS

#: The engine interface (treeimpact.analytic.engine.interface.Engine) and what the tests,
#: benchmarks and the regenerator read from the runner.
__all__ = ["OPTIONS", "Setup", "build_model", "engine_trunk_matrices", "flex_modes",
           "flex_trunk_matrices", "highest_frequency", "make_setup", "modes", "run",
           "run_setups", "simulate", "simulate_batch"]


def simulate(scenario: Scenario, *, trunk="chain", segments=None, pendulum="linear",
             dt=None, trunk_damping_model=None, integrator="Euler", calibration=None
             ) -> SimulationResult:
    """Run one scenario in MuJoCo (rules: docs/engines.md); backend "mujoco".

    Args:
        scenario: the tree, pendulum and contact (its e, pad and t_end: a run option that
            overrides one is applied to it before, analytic.model.options.scenario_as_run).
        trunk: "chain" (hinged rigid segments, default), "sdof" (eq 11 on a slide joint),
            "flex" (MuJoCo's 1-D elastic rod) or "cable" (refused: gone in MuJoCo 4.0).
        segments: the chain's or the rod's segments (None: the fewest within 0.5 % of the
            beam, :func:`analytic.continuum.chain.default_segments`).
        pendulum: "linear" (eq 13, starting at the touch at u_1) or "full" (released from
            theta_r, swinging to the trunk).
        dt: the time step, s (None: :mod:`analytic.contact.timestep`'s rule).
        trunk_damping_model: "distributed" (None, the default: eq 9's C along the trunk) or
            "joint" (in the chain's hinges); refused with ``trunk = "sdof"``.
        integrator: MuJoCo's ``Euler`` (default), ``implicit``, ``implicitfast`` or
            ``RK4``.
        calibration: "pad" (None, the default) the SDOF rung's (k_c, c_c); "effective" c_c
            recalibrated so that e holds on the trunk's effective mass at the clamp; refused
            with ``trunk = "sdof"`` (where both are the same).

    Returns:
        The SimulationResult: metrics, model, record (SI).

    Raises:
        ParameterError: a bad option or a step the engine cannot take (one line).
        SimulationDiverged: the run diverged (with MuJoCo's warning, if it gave one).
    """
    out = simulate_batch([scenario], trunk=trunk, segments=segments, pendulum=pendulum,
                         dt=dt, trunk_damping_model=trunk_damping_model,
                         integrator=integrator,
                         calibration=calibration, max_workers=1)[0]
    if isinstance(out, SimulationDiverged):
        raise out
    return out


def run(setup: Setup) -> SimulationResult:
    """Roll out one compiled setup (the engine interface's ``run``)."""
    out = run_setups([setup], max_workers=1)[0]
    if isinstance(out, SimulationDiverged):
        raise out
    return out


@mujoco_warnings
def run_setups(setups: list[Setup], *, max_workers=None) -> list:
    """Roll out compiled setups; a SimulationResult or SimulationDiverged per setup, in order."""
    nthread = max_workers or os.cpu_count() or 1
    plans = [_plan(s) for s in setups]
    groups: dict = {}
    for i, p in enumerate(plans):
        groups.setdefault(_signature(p.setup.mjmodel), []).append(i)
    out = [None] * len(plans)
    with collected_warnings() as seen:
        for idx in groups.values():
            for i, (s0, st, sd, h, cost) in zip(idx, _run_group([plans[i] for i in idx],
                                                                 nthread)):
                try:
                    out[i] = _result(setups[i], s0, st, sd, cost, h)
                except SimulationDiverged as exc:
                    out[i] = exc
    return _with_warnings(out, seen)


def _with_warnings(out: list, seen: list) -> list:
    """``out`` with MuJoCo's first warning in each diverged run's message (one line, not a
    line of its own before it); told on stderr when a run ended well."""
    if not seen:
        return out
    diverged = [isinstance(r, SimulationDiverged) for r in out]
    out = [SimulationDiverged(f"{r} (MuJoCo warned: {seen[0]})") if bad else r
           for r, bad in zip(out, diverged)]
    if not all(diverged):
        for text in seen:
            tell(text)
    return out


def simulate_batch(scenarios, *, max_workers=None, **options) -> list:
    """Simulate many scenarios with the same options through multi-threaded ``mujoco.rollout``.

    Models of one size signature (same trunk kind and segments) step together in one rollout
    call over ``max_workers`` threads (default: all CPUs). Returns, in order, a
    SimulationResult or the SimulationDiverged of each scenario; bad options raise
    ParameterError before anything is stepped.
    """
    setups = [make_setup(s, **options) for s in scenarios]
    return run_setups(setups, max_workers=max_workers)
