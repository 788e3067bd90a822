"""treeimpact.analytic: the paper's one-degree-of-freedom trunk impact model, exactly.

Public API (SI units throughout)::

    from analytic import load_scenario, simulate
    result = simulate(load_scenario("open-center"))
    result.metrics["V"]        # common velocity, m/s (eq 34)
"""

from .model import TwoBodyModel, two_body_model
from .parameters import (Billet, Contact, ParameterError, Pendulum, Scenario, Trunk)
from .reduction import TreeSDOF, reduce_trunk, static_mode_shape
from .scenario import load_scenario, scenario_from_dict, shipped_scenarios

__all__ = [
    "Billet", "Contact", "ParameterError", "Pendulum", "Scenario", "Trunk", "TreeSDOF",
    "TwoBodyModel", "load_scenario", "reduce_trunk", "scenario_from_dict",
    "shipped_scenarios", "static_mode_shape", "two_body_model",
]

from .simulate import impact_metrics, simulate, simulate_model  # noqa: E402
from .solver import ImpactSolution, solve_impacts  # noqa: E402

__all__ += ["ImpactSolution", "impact_metrics", "simulate", "simulate_model", "solve_impacts"]
