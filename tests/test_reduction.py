"""Beam-to-SDOF reduction (eqs 1-11) against a symbolic Lagrangian derivation (sympy)."""

import math

import pytest
import sympy as sp

from treeimpact.analytic.model.parameters import Trunk
from treeimpact.analytic.model.reduction import (
    printed_damping,
    printed_dynamic_mass,
    printed_stiffness,
    reduce_trunk,
    static_mode_shape,
)

x, a, l, E, I, rho, A, C, mc, mf, kth = sp.symbols("x a l E I rho A C m_c m_f k_theta",
                                                   positive=True)


def symbolic_reduction(base_spring: bool):
    """M_T, C_T, K_T from T, P and V of eqs 7-10 with the static shape of eq 1 (+ base spring)."""
    F = 1
    rot = F * a / kth if base_spring else 0
    inner = F * x ** 2 * (3 * a - x) / (6 * E * I) + rot * x  # eq 1, x <= a
    outer = F * a ** 2 * (3 * x - a) / (6 * E * I) + rot * x  # eq 1, x >= a
    ya = inner.subs(x, a)
    phi_in, phi_out = sp.simplify(inner / ya), sp.simplify(outer / ya)  # eq 5
    J = sp.integrate(phi_in ** 2, (x, 0, a)) + sp.integrate(phi_out ** 2, (x, a, l))
    M_T = rho * A * J + mc + mf * phi_out.subs(x, l) ** 2  # eq 7
    C_T = C * J  # P = (C/2) int w_t^2 = C_T eta_t^2 / 2, eqs 9-10
    V2 = E * I * sp.integrate(sp.diff(phi_in, x, 2) ** 2, (x, 0, a))  # eq 8 (outer is linear)
    if base_spring:
        V2 += kth * sp.diff(phi_in, x).subs(x, 0) ** 2
    return sp.simplify(M_T), sp.simplify(C_T), sp.simplify(V2)


TRUNKS = {
    "rigid-clamp": Trunk(length=1.2, clamp_height=0.35, diameter=0.14, density=900.0,
                         youngs_modulus=8e9, clamp_mass=4.0, crown_mass=20.0, damping=3000.0),
    "base-spring": Trunk(length=0.9, clamp_height=0.3, diameter=0.12, density=950.0,
                         youngs_modulus=9e9, clamp_mass=3.0, crown_mass=10.0, damping=2000.0,
                         base_stiffness=2.0e5),
}


def _subs(expr, t: Trunk):
    vals = {a: t.clamp_height, l: t.length, E: t.youngs_modulus, I: t.second_moment,
            rho: t.density, A: t.area, C: t.damping, mc: t.clamp_mass, mf: t.crown_mass}
    if math.isfinite(t.base_stiffness):
        vals[kth] = t.base_stiffness
    return float(expr.subs(vals))


@pytest.mark.parametrize("case", list(TRUNKS))
def test_lagrangian_reduction_matches_symbolic_derivation(case):
    t = TRUNKS[case]
    M_T, C_T, K_T = symbolic_reduction(math.isfinite(t.base_stiffness))
    red = reduce_trunk(t)
    assert red.dynamic_mass == pytest.approx(_subs(M_T, t), rel=1e-12)
    assert red.equivalent_damping == pytest.approx(_subs(C_T, t), rel=1e-12)
    assert red.equivalent_stiffness == pytest.approx(_subs(K_T, t), rel=1e-12)


def test_printed_eq7_dynamic_mass_equals_derivation():
    M_T, _, _ = symbolic_reduction(False)
    printed = (rho * A * l * ((3 * l * (l - a) + a ** 2) / (4 * a ** 2) - a / (70 * l)) + mc
               + mf * ((3 * l - a) / (2 * a)) ** 2)
    assert sp.simplify(M_T - printed) == 0
    t = TRUNKS["rigid-clamp"]
    assert printed_dynamic_mass(t) == pytest.approx(reduce_trunk(t).dynamic_mass, rel=1e-12)


def test_printed_eq10_damping_is_half_the_derivation():
    _, C_T, _ = symbolic_reduction(False)
    printed = C * l / 2 * ((3 * l * (l - a) + a ** 2) / (4 * a ** 2) - (a / l) / 70)
    assert sp.simplify(C_T / printed) == 2  # recorded in analytic.paper.reproduction.DISCREPANCIES
    t = TRUNKS["rigid-clamp"]
    assert reduce_trunk(t).equivalent_damping == pytest.approx(2 * printed_damping(t), rel=1e-12)


def test_eq8_stiffness_is_3EI_over_a_cubed():
    _, _, K_T = symbolic_reduction(False)
    assert sp.simplify(K_T - 3 * E * I / a ** 3) == 0
    t = TRUNKS["rigid-clamp"]
    assert reduce_trunk(t).equivalent_stiffness == pytest.approx(printed_stiffness(t), rel=1e-13)


def test_base_spring_stiffness_is_series_of_bending_and_rotation():
    t = TRUNKS["base-spring"]
    expected = 1.0 / (t.clamp_height ** 3 / (3 * t.bending_stiffness)
                      + t.clamp_height ** 2 / t.base_stiffness)
    assert reduce_trunk(t).equivalent_stiffness == pytest.approx(expected, rel=1e-13)


def test_static_mode_shape_is_one_at_the_clamp_and_continuous():
    for t in TRUNKS.values():
        shape = static_mode_shape(t)
        assert float(shape(t.clamp_height)) == pytest.approx(1.0, rel=1e-14)
        assert float(shape.inner(t.clamp_height)) == pytest.approx(
            float(shape.outer(t.clamp_height)), rel=1e-13)
        assert float(shape.inner.deriv()(t.clamp_height)) == pytest.approx(
            float(shape.outer.deriv()(t.clamp_height)), rel=1e-12)


def test_closed_form_shape_integrals_match_polynomial_integration():
    """J and phi(l) of reduce_trunk (expanded by hand) against numpy's polynomial integral of
    the same shape, with and without the base spring."""
    from treeimpact.analytic.model.reduction import _square_integral, crown_factor

    for t in TRUNKS.values():
        shape = static_mode_shape(t)
        assert _square_integral(t) == pytest.approx(shape.square_integral(), rel=1e-13)
        assert crown_factor(t) == pytest.approx(float(shape.outer(t.length)), rel=1e-14)


def test_shipped_scenarios_reduce_to_table_1():
    from treeimpact.analytic.model.scenario import load_scenario

    for name, (mt, kt) in {"open-center": (87.0, 1.2e6), "central-leader": (110.0, 1.5e6)}.items():
        red = reduce_trunk(load_scenario(name).trunk)
        assert red.dynamic_mass == pytest.approx(mt, rel=1e-6)  # calibrated to Table 1
        assert red.equivalent_stiffness == pytest.approx(kt, rel=1e-6)
