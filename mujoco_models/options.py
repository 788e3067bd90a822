"""The MuJoCo backend's options (:class:`treeimpact.analytic.model.options.Option` each):
the engines' shared ones and MuJoCo's integrator. Importing this loads no MuJoCo, so the
command line and the sweeps read it cheaply."""

from treeimpact.analytic.engine.interface import ENGINE_OPTIONS
from treeimpact.analytic.model.options import Option

#: Values of the ``integrator`` option (MuJoCo's names, ``mjtIntegrator``).
INTEGRATORS = ("Euler", "implicit", "implicitfast", "RK4")

OPTIONS = {**ENGINE_OPTIONS,
           "integrator": Option(INTEGRATORS, "MuJoCo's integrator (default Euler)")}
