"""A tree's scenario from measured quantities: the reduction of eqs 7-11 inverted.

A researcher knows the clamp height a, the trunk diameter d, the pendulum (m, l_e,
theta_r) and measured M_T, K_T and the damping rate b of the moving-together motion (or
the regression of Figs 4-5: a1, a2, x_max, tau). With chosen l, rho, E and m_c, the trunk
of :class:`analytic.model.parameters.Trunk` that reduces
(:func:`analytic.model.reduction.reduce_trunk`) to exactly those M_T, K_T and C_T has

* base_stiffness k_theta from K_T: 1 / K_T = a^3 / (3 E I) + a^2 / k_theta (eq 8 with the
  root spring), so K_T must lie below the rigid-clamp value 3 E I / a^3;
* crown_mass m_f from M_T (eq 7): M_T = rho A J + m_c + m_f phi(l)^2 with the static shape
  phi of that k_theta;
* damping C from C_T = 2 b (M_T + m) (eq 34: the moving-together motion decays at b) and
  C_T = C J (eq 10 as derived).

The shipped scenarios were calibrated this way; :func:`calibration_notes` records it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from treeimpact.analytic.errors import ParameterError

from .parameters import LIMITS, Trunk
from .reduction import reduce_trunk, static_mode_shape


@dataclass(frozen=True)
class MeasuredTree:
    """Measured properties of a tree at its clamp (Table 1), validated on construction.

    Attributes:
        dynamic_mass: M_T, kg.
        equivalent_stiffness: K_T, the tree's equivalent spring at the clamp, N/m.
        damping_rate: b, the decay rate of the moving-together motion (eq 42), 1/s.
    """

    dynamic_mass: float  # M_T, kg (Table 1)
    equivalent_stiffness: float  # K_T, N/m: the tree's equivalent spring at the clamp (Table 1)
    damping_rate: float  # b, 1/s: decay rate of the moving-together motion (eq 42)

    def __post_init__(self):
        for name, v, unit in (("dynamic_mass", self.dynamic_mass, "kg"),
                              ("equivalent_stiffness", self.equivalent_stiffness, "N/m")):
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ParameterError(f"{name} = {v!r} {unit}: allowed (0, inf) {unit}")
        b = self.damping_rate
        if not (isinstance(b, (int, float)) and math.isfinite(b) and b >= 0):
            raise ParameterError(f"damping_rate = {b!r} 1/s: allowed [0, inf) 1/s")


def damping_rate_from_regression(a1: float, a2: float) -> float:
    """b = -a2 / a1, 1/s (eq 42), from the regression x = a1 t + a2 t^2 (eq 40)."""
    if not (math.isfinite(a1) and a1 > 0):
        raise ParameterError(f"a1 = {a1!r} m/s: allowed (0, inf) m/s (the common velocity V)")
    if not (math.isfinite(a2) and a2 <= 0):
        raise ParameterError(f"a2 = {a2!r} m/s^2: allowed (-inf, 0] m/s^2 (decelerating)")
    return -a2 / a1


def stiffness_from_regression(*, a1: float, a2: float, x_max: float, tau: float,
                              dynamic_mass: float, impactor_mass: float,
                              impactor_stiffness: float) -> float:
    """K_T, N/m: omega_n = a1 / (x_max e^(b tau)) (eqs 38 and 43 with x0 = 0), then
    K_T = omega_n^2 (M_T + m) - k (eq 46 with omega_1 = omega_n, the moving-together motion).

    Args:
        a1: the regression's linear coefficient (eq 40), the common velocity V, m/s.
        a2: its quadratic coefficient, m/s^2 (b = -a2 / a1, eq 42).
        x_max: the largest displacement, m.
        tau: the time of x_max from the regression's origin, s.
        dynamic_mass: M_T, kg.
        impactor_mass: m, kg.
        impactor_stiffness: the pendulum's k = m g / l_e, N/m (eq 13).

    Returns:
        K_T, N/m.

    Raises:
        ParameterError: an input out of range, an overdamped motion (b >= omega_n) or
            K_T <= 0.
    """
    b = damping_rate_from_regression(a1, a2)
    for name, v, unit in (("x_max", x_max, "m"), ("tau", tau, "s")):
        if not (math.isfinite(v) and v > 0):
            raise ParameterError(f"{name} = {v!r} {unit}: allowed (0, inf) {unit}")
    omega_n = a1 / (x_max * math.exp(b * tau))
    if b >= omega_n:
        raise ParameterError(f"x_max = {x_max!r} m, tau = {tau!r} s: give omega_n = "
                             f"{omega_n:.4g} rad/s <= b = {b:.4g} 1/s, an overdamped motion "
                             "with no maximum of that kind (eq 37)")
    equivalent_stiffness = omega_n ** 2 * (dynamic_mass + impactor_mass) - impactor_stiffness
    if equivalent_stiffness <= 0:
        raise ParameterError(f"x_max = {x_max!r} m, tau = {tau!r} s: give K_T = "
                             f"{equivalent_stiffness:.4g} N/m <= 0 (eq 46)")
    return equivalent_stiffness


def calibrate_trunk(chosen: Trunk, measured: MeasuredTree, *, impactor_mass: float) -> Trunk:
    """A trunk that reduces exactly to a measured tree: the crown mass from M_T (eq 7), the
    root spring from K_T (eq 8) and the distributed damping from C_T = 2 b (M_T + m)
    (eq 10), the rest as chosen (module docstring).

    Args:
        chosen: the :class:`Trunk` whose l, a, d, rho, E and m_c are kept (its crown_mass,
            damping and base_stiffness are ignored).
        measured: the :class:`MeasuredTree` (M_T kg, K_T N/m, b 1/s).
        impactor_mass: m, the pendulum's mass, kg (it enters C_T).

    Returns:
        Trunk: the calibrated trunk.

    Raises:
        ParameterError: K_T above the rigid-clamp trunk's 3 E I / a^3, or M_T below the bare
            trunk's own (each named with its allowed range).
    """
    a = chosen.clamp_height
    rigid = a ** 3 / (3.0 * chosen.bending_stiffness)  # m/N: flexibility of the rigid clamp
    base = _base_stiffness(measured.equivalent_stiffness, a, rigid)
    trunk = replace(chosen, base_stiffness=base, crown_mass=0.0, damping=0.0)
    shape = static_mode_shape(trunk)
    j = shape.square_integral()
    tip = float(shape.outer(trunk.length))
    own = reduce_trunk(trunk).dynamic_mass  # rho A J + m_c: the trunk without its crown
    crown = (measured.dynamic_mass - own) / tip ** 2
    high = own + LIMITS["trunk.crown_mass"][1] * tip ** 2
    if not 0.0 <= crown <= LIMITS["trunk.crown_mass"][1]:
        raise ParameterError(
            f"dynamic_mass = {measured.dynamic_mass:.6g} kg: "
            + (f"below the bare trunk's {own:.6g} kg (rho A J + m_c, eq 7)" if crown < 0 else
               f"needs a crown mass of {crown:.6g} kg, above the "
               f"{LIMITS['trunk.crown_mass'][1]:g} kg allowed (eq 7)")
            + f"; allowed [{own:.6g}, {high:.6g}] kg for this l, d, rho and m_c")
    equivalent_damping = 2.0 * measured.damping_rate * (measured.dynamic_mass + impactor_mass)
    _check_damping(measured.damping_rate, equivalent_damping / j,
                   measured.dynamic_mass + impactor_mass, j)
    return replace(trunk, crown_mass=crown, damping=equivalent_damping / j)


def _base_stiffness(equivalent_stiffness: float, a: float, rigid: float) -> float:
    """The root spring (N m/rad) that makes the trunk's clamp stiffness
    ``equivalent_stiffness`` (N/m, eq 8: 1/K_T = a^3 / (3 E I) + a^2 / k_r, ``rigid`` the
    first term, m/N, at clamp height ``a``, m); ParameterError naming equivalent_stiffness
    and its allowed range (k_r within trunk.base_stiffness's) when there is none."""
    k_low = LIMITS["trunk.base_stiffness"][0]
    low, high = 1.0 / (rigid + a ** 2 / k_low), 1.0 / rigid
    flexibility = 1.0 / equivalent_stiffness
    if flexibility < rigid * (1.0 - 1e-12):
        raise ParameterError(
            f"equivalent_stiffness = {equivalent_stiffness:.6g} N/m: above the rigid-clamp "
            f"trunk's 3 E I / a^3 = {high:.6g} N/m (eq 8); allowed [{low:.6g}, {high:.6g}] "
            "N/m for this E, d and a (a stiffer tree needs a larger E)")
    base = math.inf if flexibility <= rigid else a ** 2 / (flexibility - rigid)
    if base < k_low:
        raise ParameterError(
            f"equivalent_stiffness = {equivalent_stiffness:.6g} N/m: needs a root spring of "
            f"{base:.6g} N m/rad, below the {k_low:g} N m/rad allowed (eq 8); allowed "
            f"[{low:.6g}, {high:.6g}] N/m for this E, d and a")
    return base


def _check_damping(b: float, damping: float, masses: float, j: float) -> None:
    """ParameterError naming damping_rate ``b`` (1/s) and its allowed range when the
    distributed ``damping`` C = 2 b (M_T + m) / J (N s/m^2, eq 10; ``masses`` = M_T + m, kg,
    ``j`` the mode shape's square integral, m) lies beyond trunk.damping's range."""
    high = LIMITS["trunk.damping"][1]
    if damping > high:
        raise ParameterError(
            f"damping_rate = {b:.6g} 1/s: needs a trunk damping of {damping:.6g} N s/m^2, "
            f"above the {high:g} N s/m^2 allowed (eq 10); allowed [0, {high * j / (2 * masses):.6g}]"
            " 1/s for this M_T, m and trunk")


def calibration_notes(measured: MeasuredTree, *, given: str, chosen: str) -> dict:
    """The ``[calibration]`` table of a scenario file calibrated by :func:`calibrate_trunk`
    from the ``measured`` tree: what was ``given`` and ``chosen`` (free text), and what was
    calibrated from which measured value."""
    return {
        "given": given,
        "chosen": chosen,
        "calibrated": (f"m_f from M_T = {measured.dynamic_mass:.6g} kg (eq 7), base_stiffness "
                       f"from K_T = {measured.equivalent_stiffness:.6g} N/m (eq 8 with the root "
                       "spring), "
                       f"C from C_T = 2 b (M_T + m), b = {measured.damping_rate:.6g} 1/s"),
    }



def with_clamp_mass(trunk: Trunk, clamp_mass: float, *, impactor_mass: float) -> Trunk:
    """``trunk`` with the ``clamp_mass`` m_c (kg), recalibrated (crown mass, root spring,
    damping; :func:`calibrate_trunk`) so that it reduces to the same M_T, K_T and C_T as
    before (eqs 7, 8, 10): the unmeasured clamp varied on the same measured tree.
    ``impactor_mass`` (kg) fixes b = C_T / (2 (M_T + m))."""
    tree = reduce_trunk(trunk)
    measured = MeasuredTree(dynamic_mass=tree.dynamic_mass,
                            equivalent_stiffness=tree.equivalent_stiffness,
                            damping_rate=tree.equivalent_damping
                            / (2.0 * (tree.dynamic_mass + impactor_mass)))
    return calibrate_trunk(replace(trunk, clamp_mass=clamp_mass), measured,
                           impactor_mass=impactor_mass)


def root_for_share(trunk: Trunk, share: float) -> float:
    """The root spring k_theta (N m/rad) that makes the root's share of ``trunk``'s static
    flexibility at the clamp ``share`` (1): share = (a^2 / k_theta) / (a^3 / (3 E I) +
    a^2 / k_theta) (eq 8 with the root spring), so k_theta = 3 E I (1 - share) / (a share);
    inf (the paper's rigid clamp) at share 0. ParameterError naming root_share outside
    [0, 1)."""
    if not 0.0 <= share < 1.0:
        raise ParameterError(f"root_share = {share!r}: allowed [0, 1) (the root's share of "
                             "the flexibility at the clamp)")
    if share == 0.0:
        return math.inf
    return 3.0 * trunk.bending_stiffness * (1.0 - share) / (trunk.clamp_height * share)


def damping_for_ratio(trunk: Trunk, ratio: float) -> float:
    """The distributed damping C (N s/m^2) that gives ``trunk`` (its crown, clamp, root
    spring as they are) the damping ratio ``ratio`` = C_T / (2 sqrt(K_T M_T)) (eq 14):
    C_T = 2 ratio sqrt(K_T M_T) with M_T, K_T of eqs 7, 8, and C = C_T / J (eq 10 as
    derived, J the static shape's square integral, m)."""
    tree = reduce_trunk(replace(trunk, damping=0.0))
    j = static_mode_shape(trunk).square_integral()
    return 2.0 * ratio * math.sqrt(tree.equivalent_stiffness * tree.dynamic_mass) / j
