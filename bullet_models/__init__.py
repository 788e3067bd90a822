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

from .options import OPTIONS

#: The engine interface (treeimpact.analytic.engine.interface.Engine), loaded on first use:
#: the options above are read without importing the engine.
_RUNNER = ("make_setup", "modes", "run", "simulate", "simulate_batch")

__all__ = ["OPTIONS", *_RUNNER]


def __getattr__(name: str):
    if name in _RUNNER:
        from . import _runner

        return getattr(_runner, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
