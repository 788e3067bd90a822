"""The analytic reference backends, declared beside the package that defines them (as each
engine package declares itself: analytic.engine.declaration): their names, what each is,
where its ``simulate`` and ``modes`` live and what a run costs. Plain data, importable
without numpy, so the command line lists the backends cheaply; compare.runs.backends makes
its registry from :data:`REFERENCES` and the engines' declarations (docs/engines.md,
"Adding an engine").

Each ``simulate`` takes ``(scenario, **numerical options)`` and returns
analytic.results.SimulationResult; each ``modes`` ``(scenario, **trunk options)`` the
modes dict; each module of a ``simulate`` holds that backend's ``OPTIONS``.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class ReferenceDeclaration:
    """One analytic reference backend, as analytic declares it.

    Attributes:
        name: its backend name (``--backend``, the rung ids).
        description: one line for ``treeimpact simulate --help`` and the backends' list.
        simulate: ``module:function`` of its ``simulate``.
        modes: ``module:function`` of its ``modes``.
        run_cost: rough wall time (s) of one run of a shipped scenario on a 2-core machine
            ((None, s): its only model): what orders and groups parallel runs.
    """

    name: str
    description: str
    simulate: str
    modes: str
    run_cost: tuple = ()


#: The analytic references, in the order the backends' list shows them: the paper's exact
#: model (eqs 12-35), its 1-DOF trunk with the spring-dashpot pad, the continuum trunk.
REFERENCES = (
    ReferenceDeclaration(
        "analytic", "exact Newton-restitution solver of the paper (eqs 12-35)",
        "treeimpact.analytic.impact.simulate:simulate",
        "treeimpact.analytic.continuum.modes:modes", run_cost=((None, 0.005),)),
    ReferenceDeclaration(
        "soft", "analytic SDOF with the spring-dashpot contact",
        "treeimpact.analytic.contact.soft:simulate_soft",
        "treeimpact.analytic.continuum.modes:modes", run_cost=((None, 0.2),)),
    ReferenceDeclaration(
        "beam", "continuum Euler-Bernoulli trunk with the same pad, exact between contact "
                "switches",
        "treeimpact.analytic.continuum.beam_impact:simulate_beam",
        "treeimpact.analytic.continuum.beam_impact:modes", run_cost=((None, 0.6),)),
)
