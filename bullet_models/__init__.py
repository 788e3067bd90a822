"""treeimpact.bullet_models: PyBullet models of the paper's trunk, pendulum and contact.

Public API (SI units)::

    from bullet_models import simulate, simulate_batch, modes
    result = simulate(load_scenario("open-center"), trunk="sdof", contact="soft")

Rules: :mod:`bullet_models._runner` (runner, time step, Newton-contact settings),
:mod:`bullet_models._contact` (Bullet's ERP/CFM and the time-step correction),
:mod:`bullet_models._urdf` (the models; ``python -m treeimpact.bullet_models.regenerate`` writes
them to ``bullet_models/models``).
"""

from ._runner import OPTIONS, make_setup, modes, run, simulate, simulate_batch

__all__ = ["OPTIONS", "make_setup", "modes", "run", "simulate", "simulate_batch"]
