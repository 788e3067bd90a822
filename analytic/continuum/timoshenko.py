"""Timoshenko beam element: shear deformation and rotary inertia for the continuum trunk.

The two-node element of Friedman & Kosmatka (1993, "An improved two-node Timoshenko beam
finite element", Computers & Structures 47(3):473-481; the same matrices as Przemieniecki,
Theory of Matrix Structural Analysis, 1968, sec. 5.6 and 11.7): deflection w and section
rotation psi interpolated by the exact static solution of the Timoshenko beam (interdependent
cubic / quadratic shape functions), with the shear parameter phi = 12 E I / (kappa G A h^2).
Its stiffness matrix holds the static solution exactly (nodal loads), so the mesh's
flexibility at the clamp is a^3 / (3 E I) + a / (kappa G A) with any number of elements;
its consistent mass carries the translational (rho A) and rotary (rho I) inertia. phi = 0
and rho I = 0 give the Hermite element of :mod:`analytic.continuum.beam`. Design notes:
docs/beam-impact.md (Timoshenko section).
"""

from __future__ import annotations

import math

import numpy as np

from treeimpact.analytic.errors import ParameterError

#: Beam theories of the continuum trunk: Euler-Bernoulli (Hermite cubics, no shear, no rotary
#: inertia; the default) and Timoshenko (this module).
BEAM_THEORIES = ("euler-bernoulli", "timoshenko")


def check_beam_theory(beam_theory) -> str:
    """``beam_theory`` if it is one of :data:`BEAM_THEORIES`, else a one-line ParameterError."""
    if beam_theory not in BEAM_THEORIES:
        raise ParameterError(f"--beam-theory = {beam_theory!r}: allowed "
                             f"{', '.join(BEAM_THEORIES)}")
    return beam_theory


def shear_parameter(h: float, ei: float, shear_rigidity: float) -> float:
    """phi = 12 E I / (kappa G A h^2) (1) of an element of length ``h`` (m), bending
    stiffness ``ei`` = E I (N m^2) and ``shear_rigidity`` kappa G A (N); 0 when rigid in
    shear (inf)."""
    return 0.0 if math.isinf(shear_rigidity) else 12.0 * ei / (shear_rigidity * h * h)


def stiffness(h: float, ei: float, phi: float) -> np.ndarray:
    """Element stiffness (N/m, N, N m) of length ``h`` (m), ``ei`` = E I (N m^2) and shear
    parameter ``phi`` (:func:`shear_parameter`), dofs (w1, psi1, w2, psi2): Friedman &
    Kosmatka eq 21."""
    c = ei / (h ** 3 * (1.0 + phi))
    return c * np.array([[12.0, 6 * h, -12.0, 6 * h],
                         [6 * h, (4 + phi) * h * h, -6 * h, (2 - phi) * h * h],
                         [-12.0, -6 * h, 12.0, -6 * h],
                         [6 * h, (2 - phi) * h * h, -6 * h, (4 + phi) * h * h]])


def translational_mass(h: float, rho_a: float, phi: float) -> np.ndarray:
    """The consistent mass of the lateral inertia ``rho_a`` = rho A (kg/m) with the shape
    functions of an element of length ``h`` (m) and shear parameter ``phi`` (Friedman &
    Kosmatka eq 23; 420ths of the Hermite matrix at phi = 0). With C (N s/m^2) in place of
    rho A it is the consistent damping of eq 9's force C w'."""
    p2 = phi * phi
    a = 13 / 35 + 7 * phi / 10 + p2 / 3
    b = (11 / 210 + 11 * phi / 120 + p2 / 24) * h
    c = 9 / 70 + 3 * phi / 10 + p2 / 6
    d = (13 / 420 + 3 * phi / 40 + p2 / 24) * h
    e = (1 / 105 + phi / 60 + p2 / 120) * h * h
    f = (1 / 140 + phi / 60 + p2 / 120) * h * h
    return rho_a * h / (1.0 + phi) ** 2 * np.array([[a, b, c, -d],
                                                     [b, e, d, -f],
                                                     [c, d, a, -b],
                                                     [-d, -f, -b, e]])


def rotary_mass(h: float, rho_i: float, phi: float) -> np.ndarray:
    """The consistent mass of the rotary inertia ``rho_i`` = rho I (kg m) of the sections of
    an element of length ``h`` (m) and shear parameter ``phi`` (Friedman & Kosmatka eq 24;
    the Rayleigh beam's matrix at phi = 0)."""
    p2 = phi * phi
    a = 6 / 5
    b = (1 / 10 - phi / 2) * h
    e = (2 / 15 + phi / 6 + p2 / 3) * h * h
    f = (-1 / 30 - phi / 6 + p2 / 6) * h * h
    return rho_i / ((1.0 + phi) ** 2 * h) * np.array([[a, b, -a, b],
                                                      [b, e, -b, f],
                                                      [-a, -b, a, -b],
                                                      [b, f, -b, e]])


def element_matrices(h: float, ei: float, rho_a: float, rho_i: float,
                     shear_rigidity: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(K, M, M_rho_A / rho_A)`` of one element of length ``h`` (m), bending stiffness
    ``ei`` (N m^2), lateral and rotary inertias ``rho_a`` (kg/m) and ``rho_i`` (kg m), and
    ``shear_rigidity`` kappa G A (N; inf: Euler-Bernoulli): stiffness, consistent mass with
    rotary inertia, and the lateral mass's shape (for the damping matrix, per kg/m)."""
    phi = shear_parameter(h, ei, shear_rigidity)
    shape = translational_mass(h, 1.0, phi)
    return stiffness(h, ei, phi), rho_a * shape + rotary_mass(h, rho_i, phi), shape
