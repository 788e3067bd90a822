"""``treeimpact contact``: MuJoCo and Bullet contact settings you can paste, for a target
restitution and touch duration (or the pad's stiffness and damping) at a time step, checked
by simulating the two-body collision in each engine (compare.runs.contact_settings). SI units;
design notes: docs/contact-settings.md.
"""

from __future__ import annotations

import math

from treeimpact.analytic.errors import NotAchieved, ParameterError
from treeimpact.analytic.results import json_text
from treeimpact.compare.runs.contact_settings import HOLD_TOLERANCE

from ...runs.backends import ENGINE_REGISTRY
from ...runs.backends import engines as registered_engines
from ...runs.exits import ExitCode
from ._common import add_parameter_flag, number

NAME = "contact"
#: Removed spellings -> their names now (compare.runs.names).
RENAMED = {"duration": "touch_duration", "stiffness": "contact_stiffness",
           "damping": "contact_damping"}
#: --engine's words -> the engines they ask for: each registered engine that gives contact
#: settings (compare.runs.backends.ENGINE_REGISTRY), and "both" for all of them.
ENGINE_CHOICES = {**{e: (e,) for e in registered_engines(contact=True)},
                  "both": registered_engines(contact=True)}


def add_arguments(sp) -> None:
    """The command's flags, added to its subparser ``sp``."""
    sp.add_argument("--mass", type=number, help="mass of body 1, kg")
    sp.add_argument("--other-mass", type=number, dest="other_mass",
                    help="mass of body 2, kg (default inf: body 2 fixed)")
    sp.add_argument("--effective-mass", type=number, dest="effective_mass",
                    help="the reduced mass m1 m2 / (m1 + m2), kg, instead of --mass")
    add_parameter_flag(sp, "restitution", note="the target of one collision, in (0, 1)")
    sp.add_argument("--touch-duration", type=number, dest="touch_duration",
                    help="target touch duration, s: first touch to release (not the undamped "
                         "pi sqrt(mu / k_c), which is --contact-duration elsewhere)")
    add_parameter_flag(sp, "contact_stiffness", note="with --contact-damping, instead of "
                                                     "--restitution and --touch-duration")
    add_parameter_flag(sp, "contact_damping")
    sp.add_argument("--dt", type=number, help="the engines' time step, s (MuJoCo's default "
                                              "is 0.002)")
    sp.add_argument("--engine", choices=tuple(ENGINE_CHOICES), default="both",
                    help="the engine(s) to give settings for (default both); an engine that "
                         "cannot hold --dt is named with the step it needs")
    sp.add_argument("--json", action="store_true", help="machine-readable output")


def run(args) -> int:
    """Print the settings and the simulated collisions for the parsed command line ``args``
    (the API's :func:`~treeimpact.compare.interface.api.contact_settings`, as text or
    ``--json``); exit code 0 when at least one engine holds the step and each
    engine that gives settings holds the target within 10 %; NotAchieved (exit 4, after
    the output) naming what was achieved and what would hold it when one does not;
    ParameterError (exit 2) with each engine's reason when no engine holds the step."""
    # lazy: +290 ms at import otherwise (the API's modules, numpy), which --help does not need
    from treeimpact.compare.interface.api import contact_settings

    engines = ENGINE_CHOICES[args.engine]
    res = contact_settings(mass=args.mass, other_mass=args.other_mass,
                           effective_mass=args.effective_mass, restitution=args.restitution,
                           touch_duration=args.touch_duration,
                           contact_stiffness=args.contact_stiffness,
                           contact_damping=args.contact_damping, dt=args.dt, engines=engines)
    if all("error" in res[e] for e in engines):
        raise ParameterError("; ".join(res[e]["error"] for e in engines))
    if args.json:
        print(json_text(res, indent=2))
    else:
        print_settings(res, engines)
    missed = [not_held_text(res, e) for e in engines if res[e].get("holds_target") is False]
    if missed:
        raise NotAchieved("; ".join(missed))
    return ExitCode.OK


def not_held_text(res: dict, engine: str) -> str:
    """One line: what ``engine``'s setting achieved against the target of ``res`` (what
    :func:`contact_settings` returns) and what would hold the target (its ``what_holds``)."""
    law, dt, r = res["target"], res["inputs"]["dt"], res[engine]
    got = ENGINE_REGISTRY[engine].contact_side().achieved(r)
    e, t = got["restitution"], got["touch_duration"]
    text = (f"{ENGINE_REGISTRY[engine].label}'s setting gives e {e:.4g} and a touch duration of "
            f"{1e3 * t:.4g} ms ({t / law['touch_duration'] - 1:+.2%}) for the e "
            f"{law['restitution']:g}, {1e3 * law['touch_duration']:g} ms asked at --dt "
            f"{dt:g} s, beyond {HOLD_TOLERANCE:.0%}")
    holds = r["what_holds"]
    ways = []
    if holds["smallest_touch_duration"] is not None:
        ways.append(f"the shortest touch duration this --dt holds within "
                    f"{HOLD_TOLERANCE:.0%} is {1e3 * holds['smallest_touch_duration']:.4g} ms "
                    "(same e)")
    if holds["largest_dt"] is not None:
        ways.append(f"the {1e3 * law['touch_duration']:g} ms touch needs --dt <= "
                    f"{holds['largest_dt']:.3g} s")
    return text + (": " + ", or ".join(ways) if ways else "")


def _row(name, achieved, law) -> str:
    e, t = achieved["restitution"], achieved["touch_duration"]
    if not math.isfinite(e):
        return f"  {name:<32}{'diverged: the step is too large for this setting':<66}"
    e_text = f"{e:.6f} ({e - law['restitution']:+.1e})"
    t_text = (f"{1e3 * t:.4f} ms ({t / law['touch_duration'] - 1:+.2%}, "
              f"{achieved['steps']} steps)")
    return (f"  {name:<32}{e_text:<21}{t_text:<34}"
            f"{1e3 * achieved['peak_penetration']:>8.4g} mm")


def _moved(c: dict) -> str:
    e, t = c["restitution"], c["touch_duration"]
    if not math.isfinite(e):
        return f"{'diverged':<22}"
    if e > 1.0:
        return f"{f'e {e:.3g} > 1: unstable':<22}"
    return f"{f'{e:.4f}, {1e3 * t:.4g} ms':<22}"


def _header(res: dict) -> None:
    law, inp = res["target"], res["inputs"]
    other = "fixed" if math.isinf(inp["other_mass"]) else f"{inp['other_mass']:g} kg"
    print(f"Contact of {inp['mass']:g} kg with {other} (reduced mass "
          f"{inp['effective_mass']:.6g} kg) at dt = {inp['dt']:.6g} s")
    print(f"  target: e {law['restitution']:.6g}, touch duration "
          f"{1e3 * law['touch_duration']:.6g} ms (first touch to release); the pad k_c "
          f"{law['contact_stiffness']:.6g} N/m, c_c {law['contact_damping']:.6g} N s/m, zeta "
          f"{law['damping_ratio']:.4g} (contact duration pi sqrt(mu / k_c) "
          f"{1e3 * law['contact_duration']:.6g} ms)")
    print()


def _collision_rows(res: dict, engines) -> list:
    """(label, achieved at dt, at dt/2, at 2 dt) of every setting printed."""
    return [row for e in engines if "error" not in res[e]
            for row in ENGINE_REGISTRY[e].contact_side().rows(res[e])]


def print_settings(res: dict, engines) -> None:
    """The command's text output of ``res`` (what :func:`contact_settings` returns) for the
    ``engines`` named: the target, each engine's settings (or why it cannot hold the step),
    then each setting's simulated collision at dt and kept at dt/2 and 2 dt."""
    _header(res)
    for engine in engines:
        if "error" in res[engine]:
            print(f"{res[engine]['error']}\n")
        else:
            ENGINE_REGISTRY[engine].contact_side().describe(res[engine])
    law = res["target"]
    speed = res["inputs"]["approach_speed"]
    print(f"Simulated two-body collision at {speed:g} m/s, achieved against the target (naive: "
          "the continuous law, no time-step correction; penetration: the largest overlap, "
          "linear in the approach speed); each setting kept as printed at half and twice the "
          "step:")
    print(f"  {'setting':<32}{'e (error)':<21}{'touch duration (error, steps)':<34}"
          f"{'penetration':>11}  {'at dt/2: e, duration':<22}  at 2 dt: e, duration")
    for label, at, half, double in _collision_rows(res, engines):
        line = _row(label, at, law)
        print(f"{line}  {_moved(half)}  {_moved(double)}".rstrip())
    _print_phases(res, engines)


def _print_phases(res: dict, engines) -> None:
    """How e and the touch duration move with where in a step the first touch falls."""
    rows = []
    for e in engines:
        side = ENGINE_REGISTRY[e].contact_side()
        if side.phases is not None and "error" not in res[e]:
            rows += side.phases(res[e])
    if not rows:
        return
    print(f"Where in a step the first touch falls ({rows[0][1]['phases']} fractions of a "
          "step, the setting as printed; the duration from the first touch):")
    for label, spread in rows:
        (e0, e1), (t0, t1) = spread["restitution"], spread["touch_duration"]
        if not math.isfinite(e0):
            print(f"  {label:<32}diverged at some fraction of the step")
            continue
        print(f"  {label:<32}e {e0:.4f} to {e1:.4f}, touch duration {1e3 * t0:.4g} to "
              f"{1e3 * t1:.4g} ms")
