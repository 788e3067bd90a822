"""treeimpact.bullet_models: PyBullet models of the paper's trunk, pendulum and contact.

Public API (SI units)::

    from treeimpact.bullet_models import simulate, simulate_batch, modes
    result = simulate(load_scenario("open-center"), trunk="sdof", contact="soft")

Rules: :mod:`bullet_models._setup` (options, time step, Newton-contact settings),
:mod:`bullet_models._runner` (the runs; :mod:`bullet_models._record` the record and its
energy ledger),
:mod:`bullet_models._contact` (Bullet's ERP/CFM and the time-step correction),
:mod:`bullet_models._urdf` (the models; ``python -m treeimpact.bullet_models.regenerate`` writes
them to ``bullet_models/models``).
"""

from importlib import import_module

from .declaration import DECLARATION

#: The engine interface (treeimpact.analytic.engine.interface.Engine), loaded on first use:
#: its declaration and options are read without importing the engine.
_RUNNER = ("make_setup", "modes", "run", "simulate", "simulate_batch")
#: Bullet's contact for a target law at a time step (contactStiffness/contactDamping, the
#: largest step it holds) and the two-body collision, with the world's and the links' flags,
#: that measures what a setting achieves: what ``treeimpact contact`` reads
#: (compare.runs.contact_engines). Loaded on first use: name -> its module.
_CONTACT = {"bullet_contact": "_contact", "largest_time_step": "_contact",
            "per_body": "_contact", "LINK_FLAGS": "_world", "WORLD_FLAGS": "_world",
            "two_body_collision": "_world"}

__all__ = ["DECLARATION", "OPTIONS", *_RUNNER, *_CONTACT]


def __getattr__(name: str):
    if name == "OPTIONS":
        # lazy face: +100 ms at import otherwise (numpy, the engines' shared options): the
        # registry reads DECLARATION alone
        from .options import OPTIONS

        return OPTIONS
    if name in _RUNNER:
        # lazy face: +326 ms at import otherwise (pybullet and the runner)
        from . import _runner

        return getattr(_runner, name)
    if name in _CONTACT:
        return getattr(import_module(f"{__name__}.{_CONTACT[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
