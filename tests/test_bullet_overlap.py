"""Issue 41 item 7: Bullet's ``two_body_collision`` ignored its ``overlap`` argument (every
collision started touching). Started ``overlap`` m into each other, the spheres now collide
as the continuous pad law's closed form says they do from that state."""

from __future__ import annotations

import math

import pytest

pytest.importorskip("pybullet")

from scipy.optimize import brentq  # noqa: E402

from treeimpact.bullet_models._contact import law_for_restitution  # noqa: E402
from treeimpact.bullet_models import bullet_contact, two_body_collision  # noqa: E402

M1, M2, SPEED, E, T_C = 132.4, 110.0, 1.0, 0.3, 5e-4  # kg, kg, m/s, 1, s
MU = M1 * M2 / (M1 + M2)
K = MU * (math.pi / T_C) ** 2  # N/m: the undamped collision lasts T_C
C = law_for_restitution(E, K, MU)  # N s/m
DT = T_C / 500


def closed_form_restitution(overlap: float) -> float:
    """e of the linear law mu d'' = -(k d + c d') from d(0) = ``overlap``, d'(0) = SPEED:
    the separation speed where the law's force k d + c d' first returns to zero, over
    SPEED (the underdamped solution in closed form, its zero by Brent)."""
    zeta = C / (2.0 * math.sqrt(K * MU))
    wn = math.sqrt(K / MU)
    wd = wn * math.sqrt(1.0 - zeta ** 2)
    a, b = overlap, (SPEED + zeta * wn * overlap) / wd

    def d(t):
        return math.exp(-zeta * wn * t) * (a * math.cos(wd * t) + b * math.sin(wd * t))

    def v(t):
        s, co = math.sin(wd * t), math.cos(wd * t)
        return math.exp(-zeta * wn * t) * (-zeta * wn * (a * co + b * s)
                                           + wd * (-a * s + b * co))

    t_release = brentq(lambda t: K * d(t) + C * v(t), 1e-3 / wn, math.pi / wd)
    return -v(t_release) / SPEED


def test_the_closed_form_is_the_law_restitution_from_touching():
    assert closed_form_restitution(0.0) == pytest.approx(E, abs=1e-9)


@pytest.mark.parametrize("steps", [20, 40])
def test_an_overlap_changes_bullets_collision_as_the_law_says(steps):
    """An overlap of ``steps`` steps' travel (a state with stored elastic energy): Bullet's e
    moves from its touching value by what the closed form says, within the discrete step's
    O(dt) error."""
    ks, ds = bullet_contact(K, C, MU, DT).per_body
    overlap = steps * SPEED * DT
    touching = two_body_collision(M1, M2, DT, ks, ds, SPEED).restitution
    inside = two_body_collision(M1, M2, DT, ks, ds, SPEED, overlap=overlap).restitution
    want = closed_form_restitution(overlap)
    assert touching == pytest.approx(E, abs=1e-6)
    assert abs(want - E) > 0.02  # the overlap matters: a test that ignored it fails
    assert inside == pytest.approx(want, abs=0.1 * abs(want - E)), (touching, inside, want)
