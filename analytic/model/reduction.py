"""Beam-to-SDOF reduction of the trunk (paper eqs 1-11).

The trunk is a uniform Euler-Bernoulli cantilever with point masses m_c at the clamp
height a and m_f at the top l. Its deflection is assumed to keep the *static* shape under
a point load at a (eq 1, eq 5), normalised to 1 at a. With that shape the Lagrangian
(eqs 6-10) gives the one-degree-of-freedom trunk of eq 11,

    M_T eta'' + C_T eta' + K_T eta = F.

An optional rotational spring k_theta at the ground (root/soil compliance) adds a rigid
rotation to the static shape; with k_theta = inf this is exactly the paper's model.
The shape is piecewise cubic, so its integrals have closed forms (checked against
numpy polynomials in tests/test_reduction.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.polynomial import Polynomial

from .parameters import Trunk


@dataclass(frozen=True)
class StaticModeShape:
    """Static deflection under a unit load at a, normalised to 1 at a (eq 5).

    ``inner`` holds on 0 <= x <= a, ``outer`` on a <= x <= l (polynomials in x, metres).
    """

    inner: Polynomial
    outer: Polynomial
    clamp_height: float
    length: float

    def __call__(self, x):
        x = np.asarray(x, dtype=float)
        return np.where(x <= self.clamp_height, self.inner(x), self.outer(x))

    def square_integral(self) -> float:
        """J = int_0^l phi(x)^2 dx, m (the bracket of eqs 7 and 10 times l)."""
        a, l = self.clamp_height, self.length
        pi = (self.inner ** 2).integ()
        po = (self.outer ** 2).integ()
        return float(pi(a) - pi(0.0) + po(l) - po(a))

    @property
    def base_slope(self) -> float:
        """phi'(0), 1/m: rotation of the base spring per unit deflection at a."""
        return float(self.inner.deriv()(0.0))


def static_flexibility(trunk: Trunk) -> float:
    """Deflection of ``trunk`` at a per unit load at a, m/N: a^3 / (3 E I) + a^2 / k_theta
    (eq 1)."""
    a = trunk.clamp_height
    f = a ** 3 / (3.0 * trunk.bending_stiffness)
    if math.isfinite(trunk.base_stiffness):
        f += a ** 2 / trunk.base_stiffness
    return f


def _shape_coefficients(trunk: Trunk) -> tuple[float, ...]:
    """(c1, c2, c3, d0, d1) of the static shape of eq 5 normalised at a: phi = c1 x + c2 x^2
    + c3 x^3 on [0, a] (bending of eq 1 plus the base rotation), phi = d0 + d1 x on [a, l]."""
    a, ei = trunk.clamp_height, trunk.bending_stiffness
    rot = a / trunk.base_stiffness if math.isfinite(trunk.base_stiffness) else 0.0
    ya = static_flexibility(trunk)  # unit load F = 1 at a
    return (rot / ya, a / (2.0 * ei * ya), -1.0 / (6.0 * ei * ya),
            -a ** 3 / (6.0 * ei * ya), (a ** 2 / (2.0 * ei) + rot) / ya)


def static_mode_shape(trunk: Trunk) -> StaticModeShape:
    """The static shape of eq 5 of ``trunk`` (with the base-spring rotation when k_theta is
    finite)."""
    c1, c2, c3, d0, d1 = _shape_coefficients(trunk)
    return StaticModeShape(Polynomial([0.0, c1, c2, c3]), Polynomial([d0, d1]),
                           trunk.clamp_height, trunk.length)


def _square_integral(trunk: Trunk) -> float:
    """J = int_0^l phi^2 dx (m) of :func:`static_mode_shape` expanded term by term (the
    polynomial integral :meth:`StaticModeShape.square_integral` checks it in the tests)."""
    c1, c2, c3, d0, d1 = _shape_coefficients(trunk)
    a, l = trunk.clamp_height, trunk.length
    inner = (c1 * c1 * a ** 3 / 3.0 + c1 * c2 * a ** 4 / 2.0 + (c2 * c2 + 2.0 * c1 * c3) * a ** 5
             / 5.0 + c2 * c3 * a ** 6 / 3.0 + c3 * c3 * a ** 7 / 7.0)
    outer = d0 * d0 * (l - a) + d0 * d1 * (l * l - a * a) + d1 * d1 * (l ** 3 - a ** 3) / 3.0
    return inner + outer


def crown_factor(trunk: Trunk) -> float:
    """phi(l) of ``trunk``: crown displacement per unit displacement at a in the static shape
    of eq 5."""
    _, _, _, d0, d1 = _shape_coefficients(trunk)
    return d0 + d1 * trunk.length


@dataclass(frozen=True)
class TreeSDOF:
    """The trunk reduced to one degree of freedom at the impact point (eq 11)."""

    dynamic_mass: float  # M_T, kg (eq 7)
    equivalent_damping: float  # C_T, N s/m (eq 10, derived form)
    equivalent_stiffness: float  # K_T, N/m (eq 8)

    @property
    def natural_frequency(self) -> float:
        """omega_1 = sqrt(K_T / M_T), rad/s (eq 14)."""
        return math.sqrt(self.equivalent_stiffness / self.dynamic_mass)

    @property
    def damping_ratio(self) -> float:
        """xi with 2 xi omega_1 = C_T / M_T (eq 14)."""
        return self.equivalent_damping / (
            2.0 * math.sqrt(self.equivalent_stiffness * self.dynamic_mass))


def reduce_trunk(trunk: Trunk) -> TreeSDOF:
    """M_T, C_T and K_T of eqs 7, 10 and 8 of ``trunk`` from the Lagrangian with the static
    shape.

    Follows the derivation, not the printed eq 10: the printed C_T carries an extra factor
    1/2 (see ``analytic.paper.reproduction.DISCREPANCIES``).
    """
    j = _square_integral(trunk)
    return TreeSDOF(
        dynamic_mass=mass_parts(trunk, j).total,
        equivalent_damping=trunk.damping * j,
        equivalent_stiffness=1.0 / static_flexibility(trunk),
    )


@dataclass(frozen=True)
class MassParts:
    """Where M_T comes from (eq 7): M_T = rho A J + m_c + phi(l)^2 m_f, each part in kg.

    Attributes:
        trunk: rho A J, the trunk's wood weighted by its static shape squared.
        clamp: m_c, the clamp at a (phi(a) = 1).
        crown: phi(l)^2 m_f, the crown weighted by its motion per unit x at a, squared.
        crown_weight: phi(l)^2 (1): how many times the crown's mass counts.
    """

    trunk: float
    clamp: float
    crown: float
    crown_weight: float

    @property
    def total(self) -> float:
        """M_T, kg (eq 7)."""
        return self.trunk + self.clamp + self.crown


def mass_parts(trunk: Trunk, square_integral: float | None = None) -> MassParts:
    """The three parts of ``trunk``'s M_T (eq 7, :func:`reduce_trunk`'s sum), kg;
    ``square_integral``: J (m) when the caller has it (None: computed)."""
    tip = crown_factor(trunk)
    j = _square_integral(trunk) if square_integral is None else square_integral
    return MassParts(trunk=trunk.density * trunk.area * j,
                     clamp=trunk.clamp_mass, crown=trunk.crown_mass * tip ** 2,
                     crown_weight=tip ** 2)


def printed_dynamic_mass(trunk: Trunk) -> float:
    """M_T (kg) of ``trunk`` exactly as printed after eq 7 (rigid clamp)."""
    a, l = trunk.clamp_height, trunk.length
    return (trunk.trunk_mass * ((3 * l * (l - a) + a ** 2) / (4 * a ** 2) - a / (70 * l))
            + trunk.clamp_mass + trunk.crown_mass * ((3 * l - a) / (2 * a)) ** 2)


def printed_damping(trunk: Trunk) -> float:
    """C_T (N s/m) of ``trunk`` exactly as printed after eq 10 (rigid clamp), including its
    factor 1/2."""
    a, l = trunk.clamp_height, trunk.length
    return trunk.damping * l / 2 * ((3 * l * (l - a) + a ** 2) / (4 * a ** 2) - (a / l) / 70)


def printed_stiffness(trunk: Trunk) -> float:
    """K_T = 3 E I / a^3 (N/m) of ``trunk`` as printed after eq 8 (rigid clamp)."""
    return 3.0 * trunk.bending_stiffness / trunk.clamp_height ** 3
