"""``treeimpact contact``: MuJoCo and Bullet contact settings you can paste, for a target
restitution and contact duration (or a stiffness and damping) at a time step, checked by
simulating the two-body collision in each engine. SI units; design notes:
docs/contact-settings.md.
"""

from __future__ import annotations

import json
import math

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.parameters import check_range

from ._common import number

NAME = "contact"
HELP = ("MuJoCo's solref/solimp and Bullet's contactStiffness/Damping for a target e and "
        "contact duration, checked in both engines")

#: Fewest steps of the target collision the command accepts (0.5e5 steps per collision at
#: most keep the two simulations under a second).
MAX_STEPS_PER_COLLISION = 50_000
SPEED = 1.0  # m/s: approach speed of the simulated collision (the law is linear: any speed)


def add_arguments(sp) -> None:
    """The command's flags."""
    sp.add_argument("--mass", type=number, help="mass of body 1, kg")
    sp.add_argument("--other-mass", type=number, dest="other_mass",
                    help="mass of body 2, kg (default inf: body 2 fixed)")
    sp.add_argument("--effective-mass", type=number, dest="effective_mass",
                    help="the reduced mass m1 m2 / (m1 + m2), kg, instead of --mass")
    sp.add_argument("--restitution", type=number, help="target e of one collision (0, 1)")
    sp.add_argument("--duration", type=number,
                    help="target contact duration, s: first touch to release")
    sp.add_argument("--stiffness", type=number, help="contact stiffness k, N/m (with "
                    "--damping, instead of --restitution and --duration)")
    sp.add_argument("--damping", type=number, help="contact damping c, N s/m")
    sp.add_argument("--dt", type=number, help="the engines' time step, s")
    sp.add_argument("--json", action="store_true", help="machine-readable output")


def _masses(mass, other_mass, effective_mass) -> tuple[float, float]:
    """(m1, m2) in kg; m2 = inf: a fixed body. ``--effective-mass`` mu is m1 = mu, m2 fixed."""
    if effective_mass is not None:
        if mass is not None or other_mass is not None:
            raise ParameterError("--effective-mass: give it instead of --mass/--other-mass")
        return check_range("--effective-mass", effective_mass, low=0.0, low_open=True,
                           high=1e9, unit="kg"), math.inf
    if mass is None:
        raise ParameterError("--mass: required (or --effective-mass), allowed (0, 1e+09] kg")
    m1 = check_range("--mass", mass, low=0.0, low_open=True, high=1e9, unit="kg")
    if other_mass is None or other_mass == math.inf:
        return m1, math.inf
    return m1, check_range("--other-mass", other_mass, low=0.0, low_open=True, high=1e9,
                           unit="kg")


def target_law(mu: float, *, restitution=None, duration=None, stiffness=None, damping=None
               ) -> dict:
    """The continuous spring-dashpot F = max(0, k delta + c delta') on the reduced mass mu
    (kg): from (e, duration) or (k, c); its e, duration (first touch to release, s),
    k (N/m), c (N s/m), zeta and the undamped time pi sqrt(mu / k) (s)."""
    from treeimpact.analytic.contact.law import (
        damping_ratio_for_restitution,
        release_time,
        restitution_for_damping_ratio,
    )

    if restitution is not None or duration is not None:
        if stiffness is not None or damping is not None:
            raise ParameterError("--stiffness/--damping: give them instead of --restitution "
                                 "and --duration, not with them")
        if restitution is None or duration is None:
            raise ParameterError("--restitution and --duration: give both (or --stiffness "
                                 "and --damping)")
        # e = 1: no damping, which Bullet's implicit contact cannot give (it always damps)
        check_range("--restitution", restitution, low=0.0, high=1.0, low_open=True,
                    high_open=True)
        check_range("--duration", duration, low=0.0, high=10.0, low_open=True, unit="s")
        zeta = damping_ratio_for_restitution(restitution)
        omega = release_time(zeta) / duration
        k = mu * omega * omega
        c = 2.0 * zeta * math.sqrt(k * mu)
    else:
        if stiffness is None or damping is None:
            raise ParameterError("--restitution and --duration, or --stiffness and --damping: "
                                 "required")
        check_range("--stiffness", stiffness, low=0.0, high=1e15, low_open=True, unit="N/m")
        check_range("--damping", damping, low=0.0, high=1e12, low_open=True, unit="N s/m")
        k, c = float(stiffness), float(damping)
        zeta = c / (2.0 * math.sqrt(k * mu))
        omega = math.sqrt(k / mu)
        restitution = restitution_for_damping_ratio(zeta)
        duration = release_time(zeta) / omega
    return {"restitution": float(restitution), "duration": float(duration), "stiffness": k,
            "damping": c, "damping_ratio": zeta,
            "undamped_duration": math.pi * math.sqrt(mu / k)}


def _check_dt(dt, law: dict, mu: float) -> float:
    if dt is None:
        raise ParameterError("--dt: required, the engines' time step in s")
    top = 2.0 / math.sqrt(law["stiffness"] / mu)  # Euler's stability: omega dt < 2
    low = law["duration"] / MAX_STEPS_PER_COLLISION
    if isinstance(dt, (int, float)) and dt >= top:
        raise ParameterError(f"--dt = {dt!r} s is too large for stability: allowed "
                             f"[{low:.3g}, {top:.3g}) s (omega dt < 2)")
    return check_range("--dt", dt, low=low, high=top, high_open=True, unit="s")


def mujoco_settings(law: dict, mu: float, m1: float, m2: float, dt: float) -> dict:
    from treeimpact.mujoco_models import _contact as mc

    k, c, e = law["stiffness"], law["damping"], law["restitution"]
    eng = mc.engine_law(k, e, mu, dt)
    # two free bodies (or one against a fixed one): MuJoCo's diagApprox is the exact 1/mu
    S = mc.effective_denominator(1.0 / mu, 1.0 / mu)
    solimp = [mc.IMPEDANCE, mc.IMPEDANCE, *mc.SOLIMP_TAIL]
    solref = list(mc.solref_for_law(eng.stiffness, eng.damping, S))
    tc = list(mc.time_constant_solref(eng.stiffness, eng.damping, S))
    d_tc = mc.time_constant_impedance(eng.stiffness, S)
    solimp_tc = [d_tc, d_tc, *mc.SOLIMP_TAIL]
    refsafe = tc[0] >= 2.0 * dt  # else MuJoCo raises timeconst to 2 dt unless disabled
    naive = list(mc.solref_for_law(k, c, S))

    def run(ref, safe=True, imp=solimp):
        e_, t_, n_ = mc.two_body_collision(mc.two_body_mjcf(m1, m2, dt, ref, imp,
                                                            refsafe=safe), SPEED)
        return {"restitution": float(e_), "duration": float(t_), "steps": int(n_)}

    return {"solref": solref, "solref_timeconst": tc, "solimp": solimp,
            "solimp_timeconst": solimp_tc,
            "stiffness": eng.stiffness, "damping": eng.damping,
            "refsafe_disable_needed": not refsafe,
            "mjcf": _mjcf_snippet(dt, solref, solimp),
            "mjcf_timeconst": _mjcf_snippet(dt, tc, solimp_tc, refsafe_off=not refsafe),
            "achieved": {"solref": run(solref),
                         "solref_timeconst": run(tc, refsafe, solimp_tc)},
            "naive": {"solref": naive, **run(naive)}}


def _fmt(v: float) -> str:
    return f"{v:.10g}"


def _mjcf_snippet(dt, solref, solimp, refsafe_off=False) -> str:
    """The <option> and the <pair> of geoms A and B (contype = conaffinity = 0 on both, so
    that the pair is their only contact)."""
    opt = f'<option timestep="{_fmt(dt)}" integrator="Euler">'
    opt += '\n  <flag refsafe="disable"/>\n</option>' if refsafe_off else ""
    opt = opt if refsafe_off else opt[:-1] + "/>"
    return (f"{opt}\n<contact>\n  <pair geom1=\"A\" geom2=\"B\" condim=\"1\" margin=\"0\" "
            f"solref=\"{' '.join(_fmt(v) for v in solref)}\" "
            f"solimp=\"{' '.join(_fmt(v) for v in solimp)}\"/>\n</contact>")


def bullet_settings(law: dict, mu: float, m1: float, m2: float, dt: float) -> dict:
    from treeimpact.bullet_models import _contact as bc
    from treeimpact.bullet_models._world import (
        LINK_FLAGS,
        WORLD_FLAGS,
        two_body_collision,
    )

    k, c = law["stiffness"], law["damping"]
    limit = bc.largest_time_step(k, c, mu)
    if dt > limit:
        raise ParameterError(f"--dt = {dt!r} s is too large for Bullet's soft contact at e = "
                             f"{law['restitution']:.4g}: allowed (0, {limit:.3g}] s (its "
                             "implicit step alone would damp more than e allows)")
    b = bc.bullet_contact(k, c, mu, dt)
    ks, ds = b.per_body
    nk, nd = bc.per_body(k, c)

    def run(kk, dd):
        e_, t_, n_ = two_body_collision(m1, m2, dt, kk, dd, SPEED)
        return {"restitution": float(e_), "duration": float(t_), "steps": int(n_)}

    return {"contactStiffness": ks, "contactDamping": ds,
            "stiffness": b.stiffness, "damping": b.damping, "erp": b.erp, "cfm": b.cfm,
            "world": {"fixedTimeStep": dt, **WORLD_FLAGS}, "link": dict(LINK_FLAGS),
            "start": "touching (distance 0) or apart by whole steps: a contact that starts "
                     "inside a step is off by O(dt)",
            "achieved": run(ks, ds),
            "naive": {"contactStiffness": nk, "contactDamping": nd, **run(nk, nd)}}


def contact_settings(*, mass=None, other_mass=None, effective_mass=None, restitution=None,
                     duration=None, stiffness=None, damping=None, dt=None) -> dict:
    """Everything ``treeimpact contact`` prints (the JSON), for these flags' values."""
    m1, m2 = _masses(mass, other_mass, effective_mass)
    mu = m1 if math.isinf(m2) else m1 * m2 / (m1 + m2)
    law = target_law(mu, restitution=restitution, duration=duration, stiffness=stiffness,
                     damping=damping)
    dt = _check_dt(dt, law, mu)
    from treeimpact.compare.backends import quiet_stdout

    with quiet_stdout():  # PyBullet prints on import; --json keeps stdout for JSON
        out = {"inputs": {"mass": m1, "other_mass": m2, "effective_mass": mu, "dt": dt},
               "target": law,
               "mujoco": mujoco_settings(law, mu, m1, m2, dt),
               "bullet": bullet_settings(law, mu, m1, m2, dt)}
    return out


def run(args) -> int:
    """Print the settings and the simulated collisions (text or ``--json``); exit code 0."""
    res = contact_settings(mass=args.mass, other_mass=args.other_mass,
                           effective_mass=args.effective_mass, restitution=args.restitution,
                           duration=args.duration, stiffness=args.stiffness,
                           damping=args.damping, dt=args.dt)
    if args.json:
        from treeimpact.analytic.results import to_jsonable

        print(json.dumps(to_jsonable(res), indent=2))
        return 0
    _print(res)
    return 0


def _row(name, achieved, law) -> str:
    e, t = achieved["restitution"], achieved["duration"]
    return (f"  {name:<34}e {e:.6f} ({e - law['restitution']:+.2e})   duration "
            f"{1e3 * t:.4f} ms ({t / law['duration'] - 1:+.2%}, {achieved['steps']} steps)")


def _print(res: dict) -> None:
    law, inp, mj, bl = res["target"], res["inputs"], res["mujoco"], res["bullet"]
    other = "fixed" if math.isinf(inp["other_mass"]) else f"{inp['other_mass']:g} kg"
    print(f"Contact of {inp['mass']:g} kg with {other} (reduced mass {inp['effective_mass']:.6g}"
          f" kg) at dt = {inp['dt']:.6g} s")
    print(f"  target: e {law['restitution']:.6g}, duration {1e3 * law['duration']:.6g} ms "
          f"(first touch to release); the law k {law['stiffness']:.6g} N/m, c "
          f"{law['damping']:.6g} N s/m, zeta {law['damping_ratio']:.4g}")
    print()
    print("MuJoCo (Euler; the pair's force is (k' delta + b' delta') / S, S = 1 / reduced mass)")
    print(f"  solref (direct: -k' -b')      {' '.join(_fmt(v) for v in mj['solref'])}")
    print(f"  solref (timeconst dampratio)  {' '.join(_fmt(v) for v in mj['solref_timeconst'])}"
          + ("   needs <flag refsafe=\"disable\"/>" if mj["refsafe_disable_needed"] else ""))
    print(f"  solimp                        {' '.join(_fmt(v) for v in mj['solimp'])}")
    if mj["solimp_timeconst"] != mj["solimp"]:
        print(f"  solimp (with timeconst)       {' '.join(_fmt(v) for v in mj['solimp_timeconst'])}"
              "   (MuJoCo caps 1/(d timeconst dampratio)^2 at 1e15)")
    print("  MJCF:")
    for line in mj["mjcf"].splitlines():
        print(f"    {line}")
    print()
    print("Bullet (each of the two links; they combine to k in series, c in sum)")
    print(f"  changeDynamics(contactStiffness={_fmt(bl['contactStiffness'])}, "
          f"contactDamping={_fmt(bl['contactDamping'])}, "
          + ", ".join(f"{k}={v:g}" for k, v in bl["link"].items()) + ")")
    print("  setPhysicsEngineParameter(" + ", ".join(f"{k}={v:g}" for k, v in
                                                  bl["world"].items()) + ")")
    print(f"  start the bodies {bl['start']}")
    print()
    print("Simulated two-body collision, achieved against the target "
          "(naive: the continuous law, no time-step correction)")
    print(_row("MuJoCo solref (direct)", mj["achieved"]["solref"], law))
    print(_row("MuJoCo solref (timeconst)", mj["achieved"]["solref_timeconst"], law))
    print(_row("MuJoCo naive solref", mj["naive"], law))
    print(_row("Bullet contactStiffness/Damping", bl["achieved"], law))
    print(_row("Bullet naive", bl["naive"], law))
