"""treeimpact.mujoco_models: MuJoCo models of the paper's trunk, pendulum and soft contact.

Public API (SI units)::

    from treeimpact.mujoco_models import simulate, simulate_batch, modes, build_model
    result = simulate(load_scenario("open-center"), trunk="sdof")

Rules: :mod:`mujoco_models._builder` (the MJCF, built with ``mujoco.MjSpec``),
:mod:`mujoco_models._contact` (MuJoCo's solref/solimp as a spring-dashpot and the
restitution mapping for its Euler step, also exact for ``implicit``/``implicitfast``; RK4
gets the continuous law), :mod:`mujoco_models._setup` (integrator option, time step, the
compiled model), :mod:`mujoco_models._runner` (the runs: :mod:`._rollout` steps,
:mod:`._record` makes the record and its energy ledger), :mod:`mujoco_models._modes`,
:mod:`mujoco_models._warnings` (MuJoCo's warnings on stderr while the engine works).
``python -m treeimpact.mujoco_models.regenerate`` writes the models of the shipped scenarios
to ``mujoco_models/models``.
"""

from .declaration import DECLARATION

#: The engine interface (treeimpact.analytic.engine.interface.Engine), loaded on first use:
#: its declaration and options are read without importing the engine.
_RUNNER = ("build_model", "make_setup", "modes", "run", "simulate", "simulate_batch")
#: MuJoCo's contact for a target law at a time step (solref/solimp, the engine law its
#: Euler step needs) and the two-body collision that measures what a setting achieves:
#: what ``treeimpact contact`` reads (compare.runs.contact_engines). Loaded on first use.
_CONTACT = ("IMPEDANCE", "SOLIMP_TAIL", "effective_denominator", "engine_law",
            "solref_for_law", "time_constant_impedance", "time_constant_solref",
            "two_body_collision", "two_body_mjcf")

__all__ = ["DECLARATION", "OPTIONS", *_RUNNER, *_CONTACT]


def __getattr__(name: str):
    if name == "OPTIONS":
        # lazy face: +100 ms at import otherwise (numpy, the engines' shared options): the
        # registry reads DECLARATION alone
        from .options import OPTIONS

        return OPTIONS
    if name in _RUNNER or name in _CONTACT:
        # lazy face: +478 ms at import otherwise (MuJoCo and the runner); from the first
        # use on, MuJoCo's warnings go to stderr
        from . import _runner

        if name in _RUNNER:
            return getattr(_runner, name)
        # lazy face: +377 ms at import otherwise (the contact law's MuJoCo side)
        from . import _contact

        return getattr(_contact, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
