"""Each engine's contact settings for a target law (compare.runs.contact_settings.target_law) at a
time step, and the two-body collision each setting gives in that engine: at the step, and
with the setting kept as printed at half and twice the step (how sensitive it is to a
change of step). An engine that cannot hold the step answers ``{"error", "largest_dt"}``.
SI units; docs/contact-settings.md."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from treeimpact import bullet_models as bc
from treeimpact import mujoco_models as mc
from treeimpact.analytic.errors import ParameterError

from . import contact_text

SPEED = 1.0  # m/s: approach speed of the simulated collision (the law is linear: any speed)

#: The steps each setting is also run at, as multiples of the step it was made for.
STEP_FACTORS = {"at_half_dt": 0.5, "at_double_dt": 2.0}
#: Where in a step the first touch falls, for the spread printed beside each engine's
#: setting: the fractions 0, 1/8, ..., 7/8 of a step (:func:`phase_spread`).
PHASES = 8
#: The MJCF snippet's geom names: placeholders for the user's two colliding geoms.
GEOM_PLACEHOLDERS = ("GEOM_OF_BODY_1", "GEOM_OF_BODY_2")


def _fmt(v: float) -> str:
    return f"{v:.10g}"


def mjcf_snippet(dt, solref, solimp, refsafe_off=False) -> str:
    """The <option> and the <contact><pair> to paste, with the time step ``dt`` (s), the
    pair's ``solref`` and ``solimp``, and ``<flag refsafe="disable"/>`` when
    ``refsafe_off``: the pair's geoms are placeholders (:data:`GEOM_PLACEHOLDERS`) for the
    names of the user's two colliding geoms; give both contype = conaffinity = 0 so that
    the pair is their only contact."""
    opt = f'<option timestep="{_fmt(dt)}" integrator="Euler">'
    opt += '\n  <flag refsafe="disable"/>\n</option>' if refsafe_off else ""
    opt = opt if refsafe_off else opt[:-1] + "/>"
    g1, g2 = GEOM_PLACEHOLDERS
    return (f"{opt}\n<contact>\n  <!-- {g1}, {g2}: replace by the names of your two geoms "
            "(body 1: --mass, body 2: --other-mass) -->\n"
            f"  <pair geom1=\"{g1}\" geom2=\"{g2}\" condim=\"1\" margin=\"0\" "
            f"solref=\"{' '.join(_fmt(v) for v in solref)}\" "
            f"solimp=\"{' '.join(_fmt(v) for v in solimp)}\"/>\n</contact>")


def phase_spread(collide, dt: float, speed: float = SPEED) -> dict:
    """The range of e and touch duration (s) over where in a step the first touch falls:
    ``collide(overlap)`` (a FreeCollision started with the bodies ``overlap`` m into each
    other, approaching at ``speed`` m/s) at overlaps of j / :data:`PHASES` of a step's travel
    speed dt (``dt`` s), the same state a body reaches that first touched j / PHASES of a step
    before the step's end; the duration counted from that first touch (the run's own plus
    overlap / speed). Returns ``{"restitution": [min, max], "touch_duration": [min, max],
    "phases": PHASES}`` (NaN where a run left the finite)."""
    es, ts = [], []
    for j in range(PHASES):
        overlap = max(1e-12, j / PHASES * speed * dt)  # 1e-12: touching, as the runs start
        c = collide(overlap)
        es.append(c.restitution)
        ts.append(c.touch_duration + overlap / speed)
    finite = all(math.isfinite(v) for v in es + ts)
    return {"restitution": [float(min(es)), float(max(es))] if finite else [math.nan] * 2,
            "touch_duration": [float(min(ts)), float(max(ts))] if finite else [math.nan] * 2,
            "phases": PHASES}


def _cannot(engine: str, dt: float, largest: float, why: str) -> dict:
    return {"error": f"{engine} cannot hold --dt = {dt:.6g} s for this contact: it needs "
                     f"dt <= {largest:.3g} s ({why})", "largest_dt": largest}


def mujoco_settings(law: dict, mu: float, m1: float, m2: float, dt: float) -> dict:
    """MuJoCo's solref/solimp (direct and time-constant) for ``law`` (of
    :func:`compare.runs.contact_settings.target_law`)
    on the reduced mass ``mu`` (kg) at ``dt`` (s), the MJCF to paste, and the collision of
    each in MuJoCo between bodies of ``m1`` and ``m2`` kg (inf: fixed) (at dt, dt/2 and
    2 dt), beside the naive (uncorrected) solref's, and the direct solref's
    ``phase_spread`` (:func:`phase_spread`); or ``{"error", "largest_dt"}`` beyond Euler's
    omega dt < 2."""
    k, c, e = law["contact_stiffness"], law["contact_damping"], law["restitution"]
    top = 2.0 / math.sqrt(k / mu)
    if dt >= top:
        return _cannot("MuJoCo", dt, top * (1 - 1e-9), "its Euler step diverges at omega dt "
                       f">= 2, omega = sqrt(k_c / mu) = {math.sqrt(k / mu):.4g} rad/s")
    try:
        eng = mc.engine_law(k, e, mu, dt)
    except ParameterError as exc:
        return {"error": f"MuJoCo: {exc}", "largest_dt": None}
    S = mc.effective_denominator(1.0 / mu, 1.0 / mu)  # free bodies: diagApprox is 1 / mu
    solimp = [mc.IMPEDANCE, mc.IMPEDANCE, *mc.SOLIMP_TAIL]
    solref = list(mc.solref_for_law(eng.stiffness, eng.damping, S))
    tc = list(mc.time_constant_solref(eng.stiffness, eng.damping, S))
    d_tc = mc.time_constant_impedance(eng.stiffness, S)
    solimp_tc = [d_tc, d_tc, *mc.SOLIMP_TAIL]
    refsafe = tc[0] >= 2.0 * dt  # else MuJoCo raises timeconst to 2 dt unless disabled
    naive = list(mc.solref_for_law(k, c, S))
    rows = {"solref": (solref, solimp, True), "solref_timeconst": (tc, solimp_tc, refsafe),
            "naive": (naive, solimp, True)}

    def run(name, step):
        ref, imp, safe = rows[name]
        return mc.two_body_collision(mc.two_body_mjcf(m1, m2, step, ref, imp, refsafe=safe),
                                     SPEED).to_json()

    xml = mc.two_body_mjcf(m1, m2, dt, solref, solimp)
    out = {"solref": solref, "solref_timeconst": tc, "solimp": solimp,
           "solimp_timeconst": solimp_tc, "engine_contact_stiffness": eng.stiffness,
           "engine_contact_damping": eng.damping, "refsafe_disable_needed": not refsafe,
           "geoms": list(GEOM_PLACEHOLDERS),
           "mjcf": mjcf_snippet(dt, solref, solimp),
           "mjcf_timeconst": mjcf_snippet(dt, tc, solimp_tc, refsafe_off=not refsafe),
           "achieved": {"solref": run("solref", dt),
                        "solref_timeconst": run("solref_timeconst", dt)},
           "naive": {"solref": naive, **run("naive", dt)},
           "phase_spread": phase_spread(
               lambda overlap: mc.two_body_collision(xml, SPEED, overlap=overlap), dt)}
    for key, f in STEP_FACTORS.items():
        out[key] = {name: run(name, f * dt) for name in rows}
    return out


def bullet_settings(law: dict, mu: float, m1: float, m2: float, dt: float) -> dict:
    """Bullet's contactStiffness/contactDamping per link for ``law`` on the reduced mass
    ``mu`` (kg) at ``dt`` (s) with the world and link flags exact restitution needs, and the
    collision in Bullet between bodies of ``m1`` and ``m2`` kg (at dt, dt/2 and 2 dt)
    beside the naive settings'; or ``{"error", "largest_dt"}`` when its implicit step
    alone damps more than e allows."""
    k, c = law["contact_stiffness"], law["contact_damping"]
    limit = bc.largest_time_step(k, c, mu)
    if dt > limit:
        return _cannot("Bullet", dt, limit, f"its implicit step alone damps more than e = "
                       f"{law['restitution']:.4g} allows")
    try:
        b = bc.bullet_contact(k, c, mu, dt)
    except ParameterError as exc:
        return {"error": f"Bullet: {exc}", "largest_dt": limit}
    ks, ds = b.per_body
    nk, nd = bc.per_body(k, c)
    rows = {"settings": (ks, ds), "naive": (nk, nd)}

    def run(name, step):
        return bc.two_body_collision(m1, m2, step, *rows[name], SPEED).to_json()

    out = {"contactStiffness": ks, "contactDamping": ds,
           "engine_contact_stiffness": b.stiffness, "engine_contact_damping": b.damping,
           "erp": b.erp, "cfm": b.cfm,
           "world": {"fixedTimeStep": dt, **bc.WORLD_FLAGS}, "link": dict(bc.LINK_FLAGS),
           "start": "touching (distance 0) or apart by whole steps: a contact that starts "
                    "inside a step is off by O(dt)",
           "achieved": run("settings", dt),
           "naive": {"contactStiffness": nk, "contactDamping": nd, **run("naive", dt)}}
    for key, f in STEP_FACTORS.items():
        out[key] = {name: run(name, f * dt) for name in rows}
    return out


def mujoco_collision(law: dict, mu: float, m1: float, m2: float, dt: float):
    """The collision (FreeCollision) MuJoCo's corrected setting for ``law`` gives at ``dt``
    (s) between bodies of ``m1`` and ``m2`` kg (reduced mass ``mu``), as ``achieved`` of
    :func:`mujoco_settings` (direct solref); None where MuJoCo cannot hold the step."""
    k, e = law["contact_stiffness"], law["restitution"]
    if dt >= 2.0 / math.sqrt(k / mu):
        return None
    eng = mc.engine_law(k, e, mu, dt)
    S = mc.effective_denominator(1.0 / mu, 1.0 / mu)
    solref = mc.solref_for_law(eng.stiffness, eng.damping, S)
    solimp = [mc.IMPEDANCE, mc.IMPEDANCE, *mc.SOLIMP_TAIL]
    return mc.two_body_collision(mc.two_body_mjcf(m1, m2, dt, solref, solimp), SPEED)


def bullet_collision(law: dict, mu: float, m1: float, m2: float, dt: float):
    """The collision (FreeCollision) Bullet's setting for ``law`` gives at ``dt`` (s)
    between bodies of ``m1`` and ``m2`` kg (reduced mass ``mu``), as ``achieved`` of
    :func:`bullet_settings`; None where Bullet cannot hold the step."""
    k, c = law["contact_stiffness"], law["contact_damping"]
    if dt > bc.largest_time_step(k, c, mu):
        return None
    ks, ds = bc.bullet_contact(k, c, mu, dt).per_body
    return bc.two_body_collision(m1, m2, dt, ks, ds, SPEED)


@dataclass(frozen=True)
class ContactSide:
    """What ``treeimpact contact`` asks of one engine (its registration's ``contact``):
    ``settings(law, mu, m1, m2, dt)``, its settings and collisions as a dict (or
    ``{"error", "largest_dt"}``); ``collision(law, mu, m1, m2, dt)``, the corrected
    setting's FreeCollision or None (what the search for a target that holds runs);
    ``achieved_key``: where in ``settings``' ``achieved`` the corrected setting's collision
    is (None: ``achieved`` itself); ``describe(settings)`` prints the settings to paste;
    ``rows(settings)``, the collision table's (label, at dt, at dt/2, at 2 dt);
    ``phases(settings)``, the (label, phase spread) rows (None: no such rows)."""

    settings: Callable
    collision: Callable
    achieved_key: str | None
    describe: Callable
    rows: Callable
    phases: Callable | None = None

    def achieved(self, res: dict) -> dict:
        """The corrected setting's collision (JSON) in ``res``, what :attr:`settings` gave."""
        return res["achieved"] if self.achieved_key is None else \
            res["achieved"][self.achieved_key]

    def collision_at(self, law: dict, mu: float, m1: float, m2: float, dt: float):
        """:attr:`collision` for ``law`` on the reduced mass ``mu`` (kg) of bodies of ``m1``
        and ``m2`` kg at ``dt`` (s); None also where the engine refuses the setting."""
        try:
            return self.collision(law, mu, m1, m2, dt)
        except ParameterError:
            return None


MUJOCO = ContactSide(mujoco_settings, mujoco_collision, "solref", contact_text.print_mujoco,
                     contact_text.mujoco_rows, contact_text.mujoco_phases)
BULLET = ContactSide(bullet_settings, bullet_collision, None, contact_text.print_bullet,
                     contact_text.bullet_rows)
