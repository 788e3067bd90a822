"""The text ``treeimpact contact`` prints for each engine's settings (compare.runs.contact_engines'
ContactSide): the settings to paste and the rows of the collision and phase tables. SI
inputs, times printed in ms; design notes: docs/contact-settings.md."""

from __future__ import annotations


def _fmt(v: float) -> str:
    return f"{v:.10g}"


def print_mujoco(mj: dict) -> None:
    """Print MuJoCo's settings ``mj`` (compare.runs.contact_engines.mujoco_settings): solref in
    both forms, solimp and the MJCF snippet."""
    print("MuJoCo (Euler; the pair's force is (k' delta + b' delta') / S, S = 1 / reduced mass)")
    print(f"  solref (direct: -k' -b')      {' '.join(_fmt(v) for v in mj['solref'])}")
    print(f"  solref (timeconst dampratio)  {' '.join(_fmt(v) for v in mj['solref_timeconst'])}"
          + ("   needs <flag refsafe=\"disable\"/>" if mj["refsafe_disable_needed"] else ""))
    print(f"  solimp                        {' '.join(_fmt(v) for v in mj['solimp'])}")
    if mj["solimp_timeconst"] != mj["solimp"]:
        print(f"  solimp (with timeconst)       "
              f"{' '.join(_fmt(v) for v in mj['solimp_timeconst'])}"
              "   (MuJoCo caps 1/(d timeconst dampratio)^2 at 1e15)")
    print(f"  MJCF ({' and '.join(mj['geoms'])} are placeholders: your two geoms' names):")
    for line in mj["mjcf"].splitlines():
        print(f"    {line}")
    print()


def print_bullet(bl: dict) -> None:
    """Print Bullet's settings ``bl`` (compare.runs.contact_engines.bullet_settings): the
    changeDynamics and setPhysicsEngineParameter calls and how to start the bodies."""
    print("Bullet (each of the two links; they combine to k in series, c in sum)")
    print(f"  changeDynamics(contactStiffness={_fmt(bl['contactStiffness'])}, "
          f"contactDamping={_fmt(bl['contactDamping'])}, "
          + ", ".join(f"{k}={v:g}" for k, v in bl["link"].items()) + ")")
    print("  setPhysicsEngineParameter(" + ", ".join(f"{k}={v:g}" for k, v in
                                                  bl["world"].items()) + ")")
    print(f"  start the bodies {bl['start']}")
    print()


def mujoco_rows(mj: dict) -> list:
    """(label, achieved at dt, at dt/2, at 2 dt) of MuJoCo's three settings in ``mj``."""
    rows = [(label, mj["achieved"][key], mj["at_half_dt"][key], mj["at_double_dt"][key])
            for label, key in (("MuJoCo solref (direct)", "solref"),
                               ("MuJoCo solref (timeconst)", "solref_timeconst"))]
    rows.append(("MuJoCo naive solref", mj["naive"], mj["at_half_dt"]["naive"],
                 mj["at_double_dt"]["naive"]))
    return rows


def bullet_rows(bl: dict) -> list:
    """(label, achieved at dt, at dt/2, at 2 dt) of Bullet's two settings in ``bl``."""
    return [("Bullet contactStiffness/Damping", bl["achieved"], bl["at_half_dt"]["settings"],
             bl["at_double_dt"]["settings"]),
            ("Bullet naive", bl["naive"], bl["at_half_dt"]["naive"],
             bl["at_double_dt"]["naive"])]


def mujoco_phases(mj: dict) -> list:
    """(label, phase spread) of MuJoCo's direct solref in ``mj``."""
    return [("MuJoCo solref (direct)", mj["phase_spread"])]
