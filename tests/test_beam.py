"""Continuous Euler-Bernoulli trunk (analytic.continuum.beam) against exact solutions of the beam
equation."""

import dataclasses
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from treeimpact.analytic.continuum.beam import (
    assemble,
    beam_mode_shapes,
    beam_natural_frequencies,
    beam_static_stiffness,
    flexibility,
    mesh,
)
from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.parameters import Trunk
from treeimpact.analytic.model.reduction import reduce_trunk, static_flexibility
from treeimpact.analytic.model.scenario import load_scenario, shipped_scenarios

#: relative accuracy of the first 3 frequencies promised by the mesh rule (analytic.continuum.beam)
MESH_RULE = 1e-8
UNIFORM = Trunk(length=1.3, clamp_height=1.3, diameter=0.1, density=900.0, youngs_modulus=1.0e10)


def _scale(t: Trunk) -> float:
    """omega = (beta l)^2 * sqrt(E I / (rho A l^4)), rad/s."""
    return math.sqrt(t.bending_stiffness / (t.density * t.area * t.length ** 4))


def _roots(f, n, upper=12.0):
    """The first n sign changes of f on (0, upper], refined with brentq."""
    grid = np.linspace(0.05, upper, 4000)
    vals = [f(x) for x in grid]
    roots = []
    for x0, x1, f0, f1 in zip(grid[:-1], grid[1:], vals[:-1], vals[1:]):
        if f0 * f1 < 0:
            roots.append(brentq(f, x0, x1, xtol=1e-14, rtol=1e-15))
        if len(roots) == n:
            break
    return np.array(roots)


def _tip_mass_equation(mu):
    """Cantilever with tip mass ratio mu = M / (rho A l), in terms of x = beta l."""
    return lambda x: (1 + math.cos(x) * math.cosh(x)
                      + mu * x * (math.cos(x) * math.sinh(x) - math.sin(x) * math.cosh(x)))


def _basis(b, x):
    """Rows W, W', W'', W''' of (cos, sin, cosh, sinh)(b x)."""
    c, s, ch, sh = math.cos(b * x), math.sin(b * x), math.cosh(b * x), math.sinh(b * x)
    return np.array([[c, s, ch, sh],
                     [-b * s, b * c, b * sh, b * ch],
                     [-b * b * c, -b * b * s, b * b * ch, b * b * sh],
                     [b ** 3 * s, -b ** 3 * c, b ** 3 * sh, b ** 3 * ch]])


def _exact_frequencies(t: Trunk, n: int = 3) -> np.ndarray:
    """Exact omegas of the trunk from the 8x8 determinant of the two-span beam equation.

    Span 1 on [0, a], span 2 on [a, l] (local coordinate). Conditions: W(0) = 0 and
    E I W''(0) = k_theta W'(0) (W'(0) = 0 for the rigid clamp); W, W', W'' continuous at a and
    E I (W'''(a+) - W'''(a-)) = omega^2 m_c W(a); E I W''(l) = 0 and
    E I W'''(l) = -omega^2 m_f W(l) (from the weak form of E I w'''' = omega^2 rho A w).
    """
    a, l, ei = t.clamp_height, t.length, t.bending_stiffness
    rho_a = t.density * t.area

    def det(x):
        b = x / l
        w2 = b ** 4 * ei / rho_a
        A = np.zeros((8, 8))
        b0, ba, bl = _basis(b, 0.0), _basis(b, a), _basis(b, l - a)
        A[0, :4] = b0[0]
        A[1, :4] = (ei * b0[2] - t.base_stiffness * b0[1]) if math.isfinite(
            t.base_stiffness) else b0[1]
        for r in range(3):
            A[2 + r, :4], A[2 + r, 4:] = ba[r], -b0[r]
        A[5, :4], A[5, 4:] = -ei * ba[3] - t.clamp_mass * w2 * ba[0], ei * b0[3]
        A[6, 4:] = bl[2]
        A[7, 4:] = ei * bl[3] + t.crown_mass * w2 * bl[0]
        return np.linalg.det(A / np.abs(A).max(axis=1, keepdims=True))

    return _roots(det, n) ** 2 * _scale(t)


def test_textbook_beta_l_digits_solve_the_clamped_free_equation():
    exact = _roots(lambda x: 1 + math.cos(x) * math.cosh(x), 3)
    # textbook values are printed to 9 significant digits
    assert exact == pytest.approx([1.87510407, 4.69409113, 7.85475744], rel=3e-9)


def test_uniform_cantilever_frequencies_match_textbook_beta_l():
    beta_l = _roots(lambda x: 1 + math.cos(x) * math.cosh(x), 3)
    got = beam_natural_frequencies(UNIFORM, 3)
    assert got == pytest.approx(beta_l ** 2 * _scale(UNIFORM), rel=MESH_RULE)
    # the textbook digits themselves, within their printed precision plus the mesh rule
    textbook = np.array([1.87510407, 4.69409113, 7.85475744]) ** 2 * _scale(UNIFORM)
    assert got == pytest.approx(textbook, rel=MESH_RULE + 6e-9)


@pytest.mark.parametrize("mass_ratio", [0.5, 2.0, 20.0])
def test_tip_mass_cantilever_frequencies_match_exact_frequency_equation(mass_ratio):
    t = dataclasses.replace(UNIFORM, crown_mass=mass_ratio * UNIFORM.trunk_mass)
    expected = _roots(_tip_mass_equation(mass_ratio), 3) ** 2 * _scale(t)
    assert beam_natural_frequencies(t, 3) == pytest.approx(expected, rel=MESH_RULE)


def test_two_span_determinant_reproduces_tip_mass_equation():
    # cross-check of the test's own 8x8 determinant: a massless clamp at l/3, tip mass ratio 2
    t = dataclasses.replace(UNIFORM, clamp_height=UNIFORM.length / 3,
                            crown_mass=2.0 * UNIFORM.trunk_mass)
    expected = _roots(_tip_mass_equation(2.0), 3) ** 2 * _scale(t)
    assert _exact_frequencies(t) == pytest.approx(expected, rel=1e-11)  # both root-found to 1e-14


TRUNKS = {name: load_scenario(name).trunk for name in shipped_scenarios()}
TRUNKS["rigid-clamp-low-a"] = dataclasses.replace(TRUNKS["central-leader"],
                                                  base_stiffness=math.inf, clamp_height=0.05)
TRUNKS["heavy-masses-soft-root"] = dataclasses.replace(
    TRUNKS["open-center"], clamp_mass=100.0, crown_mass=500.0, base_stiffness=1.0e4)


@pytest.mark.parametrize("case", list(TRUNKS))
def test_clamp_crown_masses_and_root_spring_frequencies_match_exact_determinant(case):
    t = TRUNKS[case]
    assert beam_natural_frequencies(t, 3) == pytest.approx(_exact_frequencies(t), rel=MESH_RULE)


def test_first_mode_shape_of_uniform_cantilever_matches_closed_form():
    x = _roots(lambda v: 1 + math.cos(v) * math.cosh(v), 1)[0]
    z = np.linspace(0.0, UNIFORM.length, 37)
    b = x / UNIFORM.length
    sigma = (math.cosh(x) + math.cos(x)) / (math.sinh(x) + math.sin(x))
    phi = np.cosh(b * z) - np.cos(b * z) - sigma * (np.sinh(b * z) - np.sin(b * z))
    _, zz, shapes = beam_mode_shapes(UNIFORM, 1, z)
    assert np.array_equal(zz, z)
    # interpolation error of Hermite cubics, (beta h)^4 / 384 with h = l/160: ~1e-9
    assert shapes[0] == pytest.approx(phi / phi[-1], abs=1e-8)


def test_mode_shapes_normalised_at_clamp_are_one_at_a():
    t = TRUNKS["central-leader"]
    w, z, shapes = beam_mode_shapes(t, 2, normalise="clamp")
    i = int(np.argmin(np.abs(z - t.clamp_height)))
    assert z[i] == t.clamp_height  # the mesh has a node at a
    assert shapes[:, i] == pytest.approx([1.0, 1.0], rel=1e-12)
    assert w == pytest.approx(beam_natural_frequencies(t, 2), rel=1e-15)
    _, _, peak = beam_mode_shapes(t, 2, np.linspace(0.0, t.length, 20001))
    assert np.abs(peak).max() <= 1.0 + 1e-12  # "max" normalisation: largest magnitude is +1
    # grid spacing 5e-5 m misses the exact peak by ~phi'' dz^2 / 8 ~ 1e-8
    assert np.max(peak, axis=1) == pytest.approx([1.0, 1.0], abs=1e-7)
    assert shapes[0, 0] == 0.0  # no deflection at the root


def test_static_stiffness_of_rigid_clamp_is_3EI_over_a_cubed():
    t = dataclasses.replace(TRUNKS["central-leader"], base_stiffness=math.inf)
    a = t.clamp_height
    assert beam_static_stiffness(t) == pytest.approx(3 * t.bending_stiffness / a ** 3, rel=1e-12)


def test_static_stiffness_with_root_spring_adds_rigid_rotation_flexibility():
    t = TRUNKS["open-center"]
    a, ei, kt = t.clamp_height, t.bending_stiffness, t.base_stiffness
    assert beam_static_stiffness(t) == pytest.approx(1 / (a ** 3 / (3 * ei) + a ** 2 / kt),
                                                     rel=1e-12)


@pytest.mark.parametrize("case", list(TRUNKS))
def test_static_stiffness_equals_reduction_static_flexibility(case):
    t = TRUNKS[case]
    # both exact: finite-element solve against the closed form of eq 1 (+ root spring)
    assert beam_static_stiffness(t) * static_flexibility(t) == pytest.approx(1.0, rel=1e-12)


def test_static_stiffness_is_mesh_independent_hermite_nodal_exactness():
    """The assembled stiffness's flexibility at a is eq 1's on any mesh. K is solved in
    40-digit arithmetic (mpmath): a double-precision solve's round-off grows as cond(K),
    2.4e8 at 40 elements, and moved with the BLAS kernel (2.3e-10 to 7.5e-10 of the
    stiffness under the Prescott, Haswell and SkylakeX kernels, against the 1e-9 allowed)."""
    import mpmath

    t = TRUNKS["central-leader"]
    for n in (3, 17, 40):
        nodes = mesh(t, n)
        K, _, keep = assemble(t, nodes)
        i = int(np.argmin(np.abs(nodes - t.clamp_height)))
        j = int(np.nonzero(keep == 2 * i)[0][0])
        f = np.zeros(len(keep))
        f[j] = 1.0
        with mpmath.workdps(40):
            u = float(mpmath.lu_solve(mpmath.matrix(K.tolist()), mpmath.matrix(f.tolist()))[j])
        # what is left is the assembly's round-off of K, amplified by cond(K) ~ n^4:
        # 2.4e-11 at 40 elements, the same on every kernel (measured)
        assert 1 / u == pytest.approx(beam_static_stiffness(t), rel=1e-10)


@pytest.mark.parametrize("case", ["central-leader", "rigid-clamp-low-a"])
def test_closed_form_flexibility_is_inverse_of_assembled_hermite_stiffness(case):
    t = TRUNKS[case]
    nodes = mesh(t, 9)
    K, _, keep = assemble(t, nodes)
    F, keep_f = flexibility(t, nodes)
    assert np.array_equal(keep, keep_f)
    # cond(K) ~ 1e6 on 9-10 elements: the product is the identity to round-off
    assert np.abs(K @ F - np.eye(len(K))).max() < 1e-9


@pytest.mark.parametrize("case", shipped_scenarios())
def test_sdof_rayleigh_quotient_frequency_bounds_beam_first_frequency_from_above(case):
    t = TRUNKS[case]
    sdof = reduce_trunk(t)
    omega_sdof = math.sqrt(sdof.equivalent_stiffness / sdof.dynamic_mass)
    omega_beam = beam_natural_frequencies(t, 1)[0]
    gap = omega_sdof / omega_beam - 1
    print(f"{case}: SDOF omega_1 = {omega_sdof:.4f} rad/s, beam {omega_beam:.4f} rad/s, "
          f"gap {gap:+.4%}")
    # Rayleigh's principle (static shape is admissible): the SDOF frequency is an upper bound
    assert gap >= 0
    # the paper's 1-DOF premise: measured gaps 2.07 % (open-center), 4.88 % (central-leader),
    # 6.26 % (realistic-crown, the heavy crown the premise is expected to miss); 10 % bounds them
    assert gap < 0.10


@pytest.mark.parametrize("bad, message", [
    (dict(n_modes=0), "n_modes"), (dict(n_modes=21), "n_modes"), (dict(n_modes=2.0), "n_modes"),
    (dict(n_modes=True), "n_modes"), (dict(z=[-0.1]), "z"), (dict(z=[2.0]), "z"),
    (dict(normalise="tip"), "normalise")])
def test_bad_mode_shape_input_raises_one_line_parameter_error(bad, message):
    with pytest.raises(ParameterError, match=message) as err:
        beam_mode_shapes(UNIFORM, **bad)
    assert "\n" not in str(err.value)


def test_clamp_normalisation_refuses_mode_with_node_at_a():
    # uniform cantilever, a at the node of mode 2 (z = 0.7834 l): phi_2(a) ~ 0
    x = _roots(lambda v: 1 + math.cos(v) * math.cosh(v), 2)[1]
    sigma = (math.cosh(x) + math.cos(x)) / (math.sinh(x) + math.sin(x))
    node = brentq(lambda s: math.cosh(x * s) - math.cos(x * s)
                  - sigma * (math.sinh(x * s) - math.sin(x * s)), 0.5, 0.95, xtol=1e-15)
    t = dataclasses.replace(UNIFORM, clamp_height=node * UNIFORM.length)
    with pytest.raises(ParameterError, match="node"):
        beam_mode_shapes(t, 2, normalise="clamp")


def test_non_trunk_input_raises_parameter_error():
    with pytest.raises(ParameterError, match="trunk"):
        beam_natural_frequencies("central-leader")
    with pytest.raises(ParameterError, match="trunk"):
        beam_static_stiffness(None)
