"""One Newton impact (eqs 20-21, 54; loss eq 55) and the chattering sequence it starts: the
guard on its length and its closure at the accumulation point (docs/solver.md, steps 1
and 3)."""

from __future__ import annotations

from treeimpact.analytic.errors import ParameterError

from .events import Impact, TailClosure

TAIL_ENERGY_FRACTION = 1e-13  # close a chattering tail once it holds less than this of E0
#: Impacts one chattering sequence may take before the solver refuses the model (1 / (1 - e)
#: growth, see docs/solver.md): ~1 s of work; at most 914 were needed at e = 0.99 over
#: 1500 random models (hypothesis, the ranges of tests/test_properties.py).
MAX_CHATTER_IMPACTS = 100_000


def newton_impact(index: int, t: float, x: float, U: float, u: float, dynamic_mass: float,
                  impactor_mass: float, restitution: float, reduced_mass: float) -> Impact:
    """Impact number ``index`` at time ``t`` (s) and contact position ``x`` (m) of the trunk
    (``dynamic_mass`` M_T, kg; approach velocity ``U``, m/s) and the pendulum
    (``impactor_mass`` m, kg; approach velocity ``u``, m/s): the separation velocities by
    momentum and ``restitution`` e (eqs 20-21, v by eq 54) and the loss (eq 55, with the
    ``reduced_mass`` mu, kg)."""
    M, m, e = dynamic_mass, impactor_mass, restitution
    approach = u - U
    v_new = ((m - M * e) * u + M * (1.0 + e) * U) / (M + m)  # eq 54
    V_new = v_new + e * approach  # eq 21
    loss = 0.5 * reduced_mass * (1.0 - e * e) * approach * approach  # eq 55
    return Impact(index, t, x, U, u, V_new, v_new, loss)


def common_velocity(M: float, m: float, vx: float, vy: float) -> float:
    """The velocity (m/s) of trunk (dynamic mass M, velocity vx) and pendulum (m, vy)
    moving together with their momentum (eq 20 with V = v)."""
    return (M * vx + m * vy) / (M + m)


def chatter_refused(restitution: float, reduced_mass: float, vx: float, vy: float,
                    initial_energy: float) -> ParameterError:
    """The error refusing a chattering sequence past :data:`MAX_CHATTER_IMPACTS` impacts,
    naming ``contact.restitution`` (``restitution``); it gives the relative kinetic energy
    left, mu (vx - vy)^2 / 2 (``reduced_mass`` mu kg, separation velocities ``vx``, ``vy``
    m/s), as a fraction of ``initial_energy`` (J)."""
    return ParameterError(
        f"contact.restitution = {restitution!r}: the chattering sequence still holds "
        f"{0.5 * reduced_mass * (vx - vy) ** 2 / initial_energy:.1e} of the input energy "
        f"after {MAX_CHATTER_IMPACTS} impacts (the exact solver's work grows as "
        f"1 / (1 - e)); allowed here: a smaller e, e <= 0.99 always runs")


def close_tail(after_impact: int, t: float, gamma: float, relative_acceleration: float,
               restitution: float, reduced_mass: float,
               tail_limit: float) -> TailClosure | None:
    """The rest of a chattering sequence in closed form, or None while it is still worth
    resolving impact by impact: after impact ``after_impact`` at ``t`` (s) with relative
    separation velocity ``gamma`` (m/s) under ``relative_acceleration`` a_rel (m/s^2), the
    remaining impacts of ``restitution`` e form a geometric sequence ending at
    t + 2 gamma / (|a_rel| (1 - e)) with loss mu gamma^2 / 2 (``reduced_mass`` mu, kg);
    closed only when e < 1, a_rel < 0 and that loss is below ``tail_limit`` (J)."""
    tail_energy = 0.5 * reduced_mass * gamma * gamma
    if restitution < 1.0 and relative_acceleration < 0.0 and tail_energy < tail_limit:
        t_inf = t + 2.0 * gamma / (abs(relative_acceleration) * (1.0 - restitution))
        return TailClosure(after_impact, t, t_inf, gamma, relative_acceleration, tail_energy)
    return None
