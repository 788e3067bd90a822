"""The MuJoCo backend's options (:class:`treeimpact.analytic.model.options.Option` each):
the engines' shared ones, MuJoCo's own trunk models and its integrator. Importing this
loads no MuJoCo, so the command line and the sweeps read it cheaply."""

from treeimpact.analytic.engine.interface import ENGINE_OPTIONS, TRUNKS as ENGINE_TRUNKS
from treeimpact.analytic.model.options import Option

#: Values of MuJoCo's ``trunk`` option: the shared ones, its 1-D elastic ``flex`` and
#: ``cable`` (refused with a one-line reason: MuJoCo 4.0 removed the cable plugin).
TRUNKS = (*ENGINE_TRUNKS, "flex", "cable")

#: Values of the ``integrator`` option (MuJoCo's names, ``mjtIntegrator``).
INTEGRATORS = ("Euler", "implicit", "implicitfast", "RK4")

OPTIONS = {**ENGINE_OPTIONS,
           "trunk": Option(TRUNKS, "trunk model: the paper's SDOF (slide joint), the hinged "
                                   "chain, or MuJoCo's elastic rod (flex; cable: refused, "
                                   "removed in MuJoCo 4.0)"),
           "integrator": Option(INTEGRATORS, "MuJoCo's integrator (default Euler)")}
