"""treeimpact: the paper's one-degree-of-freedom model of a pendulum striking a fruit-tree
trunk, checked one assumption at a time against a continuum beam, MuJoCo and PyBullet.

The public API (SI units; docs/api.md)::

    import treeimpact as ti
    scenario = ti.load_scenario("open-center")        # or a TOML path, or ti.Scenario(...)
    run = ti.simulate(scenario, backend="beam")        # analytic, soft, beam, mujoco, bullet
    run.metrics.x_max                                  # m, largest trunk displacement
    record = ti.record_from_simulation(run, noise=0.01)  # as a field test records it
    fit = ti.identify(record, scenario)                # M_T, K_T, C_T, e, E with intervals
    ladder = ti.ladder(scenario)                       # one assumption per rung, judged
    ti.report("reports")                               # report.html, .md, .json

Everything else (``treeimpact.analytic``, ``treeimpact.compare``, the engine packages) is
the implementation. Names load on first use, so ``import treeimpact`` stays fast.
"""

from importlib import import_module

#: Public name -> the module that defines it.
_EXPORTS = {
    # scenarios: load, build, write
    "Scenario": "treeimpact.analytic.model.parameters",
    "Trunk": "treeimpact.analytic.model.parameters",
    "Pendulum": "treeimpact.analytic.model.parameters",
    "Billet": "treeimpact.analytic.model.parameters",
    "Contact": "treeimpact.analytic.model.parameters",
    "load_scenario": "treeimpact.analytic.model.scenario",
    "shipped_scenarios": "treeimpact.analytic.model.scenario",
    "scenario_toml": "treeimpact.analytic.model.scenario_toml",
    "MeasuredTree": "treeimpact.analytic.model.calibration",
    "tree_scenario": "treeimpact.compare.interface.api",
    "calibrate_trunk": "treeimpact.analytic.model.calibration",
    # runs, ladders, sweeps, identification, the report
    "simulate": "treeimpact.compare.interface.api",
    "modes": "treeimpact.compare.interface.api",
    "backends": "treeimpact.compare.interface.api",
    "ladder": "treeimpact.compare.interface.api",
    "sweep": "treeimpact.compare.interface.api",
    "design_map": "treeimpact.compare.interface.api",
    "read_record": "treeimpact.compare.interface.api",
    "record_from_simulation": "treeimpact.compare.interface.api",
    "identify": "treeimpact.compare.interface.api",
    "report": "treeimpact.compare.interface.api",
    # results (typed, SI) and errors
    "Simulation": "treeimpact.compare.interface.api_results",
    "Metrics": "treeimpact.compare.interface.api_results",
    "Model": "treeimpact.compare.interface.api_results",
    "Modes": "treeimpact.compare.interface.api_results",
    "TrunkModes": "treeimpact.compare.interface.api_results",
    "Identification": "treeimpact.compare.interface.api_results",
    "Estimate": "treeimpact.compare.interface.api_results",
    "Diagnosis": "treeimpact.compare.interface.api_results",
    "DiagnosisKind": "treeimpact.compare.interface.api_results",
    "Conclusion": "treeimpact.compare.interface.api_results",
    "Record": "treeimpact.analytic.identify.pendulum_record",
    "METRIC_UNITS": "treeimpact.analytic.metrics",
    "ParameterError": "treeimpact.analytic.errors",
    "SimulationDiverged": "treeimpact.analytic.errors",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name not in _EXPORTS:
        raise AttributeError(f"module 'treeimpact' has no attribute {name!r}")
    value = getattr(import_module(_EXPORTS[name]), name)
    globals()[name] = value  # later reads skip this hook
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
