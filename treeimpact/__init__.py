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

The public names are :mod:`treeimpact.api`'s, a plain module of re-exports; everything
else (``treeimpact.analytic``, ``treeimpact.compare``, the engine packages) is the
implementation. The names load on first use, so ``import treeimpact`` stays fast.
"""

from importlib import import_module

#: The package's folders (``from treeimpact import mujoco_models`` imports the folder, never
#: the API).
_FOLDERS = frozenset({"analytic", "compare", "mujoco_models", "bullet_models"})


def __getattr__(name: str):
    """A public name (and ``__all__``) from :mod:`treeimpact.api`, loaded on first use."""
    if name.startswith("__") and name != "__all__" or name in _FOLDERS:
        raise AttributeError(f"module 'treeimpact' has no attribute {name!r}")
    api = import_module("treeimpact.api")
    if name != "__all__" and name not in api.__all__:
        raise AttributeError(f"module 'treeimpact' has no attribute {name!r}")
    value = getattr(api, name)
    globals()[name] = value  # later reads skip this hook
    return value


def __dir__():
    return sorted(set(globals()) | set(import_module("treeimpact.api").__all__))
