"""``treeimpact contact``: the printed settings, pasted into a plain MJCF or URDF two-body
collision written here (not the command's own models), reproduce the target in each engine."""

from __future__ import annotations

import json
import math
import os
import tempfile

import pytest

from treeimpact.analytic.errors import ParameterError
from treeimpact.compare.cli import main
from treeimpact.compare.commands.contact import contact_settings, target_law

mujoco = pytest.importorskip("mujoco")

#: (mass, other mass, e, duration s, dt s): a pendulum on a clamp, on a trunk, a ball on a
#: fixed wall; 50-100 steps per collision
CASES = [(132.4, 4.0, 0.5, 2e-3, 4e-5), (132.4, 110.0, 0.1, 5e-4, 1e-5),
         (1.0, math.inf, 0.8, 1e-3, 1e-5)]
IDS = ["e0.5-2ms", "e0.1-0.5ms", "e0.8-wall"]


@pytest.fixture(scope="module", params=CASES, ids=IDS)
def case(request):
    m1, m2, e, T, dt = request.param
    out = json.loads(json.dumps(contact_settings(mass=m1, other_mass=m2, restitution=e,
                                                 duration=T, dt=dt), default=float))
    return request.param, out


def _body(name, mass, x, geom):
    if math.isinf(mass):
        return (f'<geom name="{geom}" type="sphere" size="0.1" pos="{x} 0 0" contype="0" '
                'conaffinity="0"/>')
    return (f'<body name="{name}" pos="{x} 0 0"><freejoint/><inertial pos="0 0 0" '
            f'mass="{mass!r}" diaginertia="1 1 1"/><geom name="{geom}" type="sphere" '
            'size="0.1" contype="0" conaffinity="0"/></body>')


def _mujoco_collision(snippet: str, m1: float, m2: float):
    """The printed snippet verbatim in a model of two spheres (gravity on: both fall alike);
    (e, steps with a pushing force) of a collision at 1 m/s starting touching."""
    xml = (f"<mujoco>{snippet}<worldbody>{_body('a', m1, -0.1 + 1e-12, 'A')}"
           f"{_body('b', m2, 0.1, 'B')}</worldbody></mujoco>")
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    d.qvel[0] = 1.0
    pushing = 0
    for _ in range(100_000):
        mujoco.mj_step(m, d)
        if d.nefc and d.efc_force[0] > 0:
            pushing += 1
        elif pushing:
            vb = d.qvel[6] if m.nv > 6 else 0.0
            if vb - d.qvel[0] > 0:
                return vb - d.qvel[0], pushing
    raise AssertionError("no rebound")


def test_the_direct_solref_reproduces_the_target_in_mujoco(case):
    (m1, m2, e, T, dt), out = case
    got, steps = _mujoco_collision(out["mujoco"]["mjcf"], m1, m2)
    # the correction makes the Euler replay exact; MuJoCo's force differs from the replay's
    # by d (A - A_hat) = 0 here, the snippet's 10 digits and round-off: measured <= 6e-7
    assert got == pytest.approx(e, abs=1e-5)
    # a step-counted duration: the release falls inside a step (within 1.5 steps of it)
    assert abs(steps * dt - T) <= 1.5 * dt


def test_the_time_constant_solref_reproduces_the_target_in_mujoco(case):
    (m1, m2, e, T, dt), out = case
    got, steps = _mujoco_collision(out["mujoco"]["mjcf_timeconst"], m1, m2)
    assert got == pytest.approx(e, abs=1e-5)  # as above: measured <= 6e-7
    assert abs(steps * dt - T) <= 1.5 * dt  # as above


def test_the_naive_solref_misses_where_the_corrected_one_does_not(case):
    """The correction is what makes the difference (measured naive errors 4e-3 to 3e-2)."""
    (m1, m2, e, T, dt), out = case
    mj = out["mujoco"]
    naive = mj["mjcf"].replace(" ".join(f"{v:.10g}" for v in mj["solref"]),
                               " ".join(f"{v:.10g}" for v in mj["naive"]["solref"]))
    assert naive != mj["mjcf"]
    got, _ = _mujoco_collision(naive, m1, m2)
    # the command's own run, from unrounded numbers (the snippet has 10 digits): 2e-7 measured
    assert got == pytest.approx(mj["naive"]["restitution"], abs=1e-5)
    assert abs(got - e) > 1e-3


URDF = """<robot name="{name}"><link name="body"><inertial><origin xyz="0 0 0" rpy="0 0 0"/>
<mass value="{mass!r}"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
<collision><origin xyz="0 0 0" rpy="0 0 0"/><geometry><sphere radius="0.1"/></geometry>
</collision></link></robot>"""


def _bullet_collision(out, m1, m2, stiffness, damping):
    from treeimpact.bullet_models._world import client

    bl = out["bullet"]
    p, cid = client()
    p.resetSimulation(physicsClientId=cid)
    p.setGravity(0, 0, 0, physicsClientId=cid)
    p.setPhysicsEngineParameter(physicsClientId=cid, **bl["world"])
    bodies = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, mass, x in (("a", m1, -0.1), ("b", m2, 0.1)):
            path = os.path.join(tmp, f"{name}.urdf")
            with open(path, "w") as fh:
                fh.write(URDF.format(name=name, mass=1.0 if math.isinf(mass) else mass))
            body = p.loadURDF(path, basePosition=[x, 0, 0], useFixedBase=math.isinf(mass),
                              flags=p.URDF_USE_INERTIA_FROM_FILE, physicsClientId=cid)
            p.changeDynamics(body, -1, contactStiffness=stiffness, contactDamping=damping,
                             physicsClientId=cid, **bl["link"])
            bodies.append(body)
    a, b = bodies
    p.resetBaseVelocity(a, [1.0, 0, 0], [0, 0, 0], physicsClientId=cid)
    pushing = 0
    for _ in range(100_000):
        p.stepSimulation(physicsClientId=cid)
        if sum(c[9] for c in p.getContactPoints(a, b, physicsClientId=cid)) > 0:
            pushing += 1
        elif pushing:
            rel = (p.getBaseVelocity(b, physicsClientId=cid)[0][0]
                   - p.getBaseVelocity(a, physicsClientId=cid)[0][0])
            if rel > 0:
                return rel, pushing
    raise AssertionError("no rebound")


def test_the_bullet_settings_reproduce_the_target(case):
    (m1, m2, e, T, dt), out = case
    bl = out["bullet"]
    got, steps = _bullet_collision(out, m1, m2, bl["contactStiffness"], bl["contactDamping"])
    # the replay is Bullet's own update (docs/contact-law.md): measured to 1e-14
    assert got == pytest.approx(e, abs=1e-9)
    assert abs(steps * dt - T) <= 1.5 * dt  # a step-counted duration, as for MuJoCo


def test_the_naive_bullet_settings_miss(case):
    (m1, m2, e, T, dt), out = case
    nv = out["bullet"]["naive"]
    got, _ = _bullet_collision(out, m1, m2, nv["contactStiffness"], nv["contactDamping"])
    assert got == pytest.approx(nv["restitution"], abs=1e-12)  # the command's own run
    assert abs(got - e) > 1e-3  # measured 3e-3 to 4e-2


def test_stiffness_and_damping_give_the_law_that_gives_them_back():
    law = target_law(3.0, restitution=0.4, duration=1e-3)
    back = target_law(3.0, stiffness=law["stiffness"], damping=law["damping"])
    assert back["restitution"] == pytest.approx(0.4, rel=1e-12)  # round-off of the inversion
    assert back["duration"] == pytest.approx(1e-3, rel=1e-12)
    # undamped limit: the duration is half a period, pi sqrt(mu / k) (closed form)
    tiny = target_law(3.0, stiffness=1e6, damping=1e-9)
    assert tiny["duration"] == pytest.approx(math.pi * math.sqrt(3.0 / 1e6), rel=1e-9)
    assert tiny["restitution"] == pytest.approx(1.0, abs=1e-9)


def test_json_is_all_stdout_and_has_the_keys(capsys):
    assert main(["contact", "--mass", "132.4", "--other-mass", "4", "--restitution", "0.5",
                 "--duration", "2e-3", "--dt", "4e-5", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert len(data["mujoco"]["solref"]) == 2 and len(data["mujoco"]["solimp"]) == 5
    assert {"contactStiffness", "contactDamping", "world", "link"} <= set(data["bullet"])


def test_text_output_shows_achieved_against_target(capsys):
    assert main(["contact", "--effective-mass", "3.88", "--stiffness", "7e6", "--damping",
                 "2700", "--dt", "4e-5"]) == 0
    text = capsys.readouterr().out
    for what in ("solref (direct", "solref (timeconst", "solimp", "<pair", "contactStiffness=",
                 "MuJoCo naive solref", "Bullet naive"):
        assert what in text, what


@pytest.mark.parametrize("argv, message", [
    (["--mass", "1", "--restitution", "1.5", "--duration", "1e-3", "--dt", "1e-5"],
     "--restitution = 1.5 is out of range: allowed (0, 1)"),
    (["--mass", "-1", "--restitution", "0.5", "--duration", "1e-3", "--dt", "1e-5"],
     "--mass = -1.0 kg is out of range: allowed (0, 1e+09] kg"),
    (["--mass", "1", "--restitution", "0.5", "--duration", "1e-3"], "--dt: required"),
    (["--mass", "1", "--restitution", "0.5", "--stiffness", "1e5", "--dt", "1e-5"],
     "--stiffness/--damping: give them instead of --restitution"),
    (["--mass", "1", "--restitution", "0.5", "--duration", "1e-3", "--dt", "1e-3"],
     "--dt = 0.001 s is too large for stability: allowed"),
    (["--mass", "1", "--restitution", "0.95", "--duration", "1e-3", "--dt", "1e-4"],
     "--dt = 0.0001 s is too large for Bullet's soft contact at e = 0.95: allowed (0, "),
    (["--mass", "1", "--effective-mass", "1", "--restitution", "0.5", "--duration", "1e-3",
      "--dt", "1e-5"], "--effective-mass: give it instead of --mass/--other-mass"),
])
def test_bad_input_is_one_line_naming_the_flag(argv, message, capsys):
    assert main(["contact", *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1, err
