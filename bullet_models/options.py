"""The PyBullet backend's options (:class:`treeimpact.analytic.model.options.Option` each):
the engines' shared ones and Bullet's contact mode. Importing this loads no PyBullet, so
the command line and the sweeps read it cheaply."""

from dataclasses import replace

from treeimpact.analytic.engine.interface import ENGINE_OPTIONS
from treeimpact.analytic.model.options import Option

#: Values of the ``contact`` option: the pad as Bullet's spring-damper, or its impulses.
CONTACTS = ("soft", "newton")

#: Hinges of one PyBullet multibody whose states it returns: 3.2.7 fails getJointState(s)
#: from 128 (its shared-memory MAX_DEGREE_OF_FREEDOM; measured: 127 runs, 128 fails).
MAX_SEGMENTS = 127
#: How the one-line errors name the engine and its limit.
ENGINE_NAME = "PyBullet (its joint-state limit)"

OPTIONS = {**ENGINE_OPTIONS,
           "segments": replace(ENGINE_OPTIONS["segments"], high=MAX_SEGMENTS),
           "contact": Option(CONTACTS, "Bullet's contact: the pad as a spring-damper (soft) "
                                       "or its restitution impulses (newton)")}
