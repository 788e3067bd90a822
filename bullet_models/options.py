"""The PyBullet backend's options (:class:`treeimpact.analytic.model.options.Option` each):
the engines' shared ones and Bullet's contact mode. Importing this loads no PyBullet, so
the command line and the sweeps read it cheaply."""

from treeimpact.analytic.engine.interface import ENGINE_OPTIONS
from treeimpact.analytic.model.options import Option

#: Values of the ``contact`` option: the pad as Bullet's spring-damper, or its impulses.
CONTACTS = ("soft", "newton")

OPTIONS = {**ENGINE_OPTIONS,
           "contact": Option(CONTACTS, "Bullet's contact: the pad as a spring-damper (soft) "
                                       "or its restitution impulses (newton)")}
