"""Physical parameters of the paper's trunk, impactor and contact (SI units).

Every dataclass is frozen and validates itself on construction: a bad value raises
:class:`ParameterError` with one line naming the field and its allowed range.

Symbols follow the paper (Figs 1-3): trunk length ``l``, clamp (impact) height ``a``,
diameter ``d``, density ``rho``, Young's modulus ``E``, clamp mass ``m_c``, crown mass
``m_f``, distributed viscous damping ``C`` (eq 9), pendulum mass ``m``, equivalent length
``l_e`` and release angle ``theta_r`` (eq 48), restitution ``e`` (eq 21).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

from treeimpact.analytic.errors import ParameterError

from .registry import PARAMETERS, default_of

#: A scenario's name: it becomes part of file names (the scenario's, figures, sweeps).
_NAME = re.compile(r"[A-Za-z0-9_-][A-Za-z0-9 ._-]{0,63}")

STANDARD_GRAVITY = 9.81  # m/s^2, the value the paper uses (after eq 48)


#: Physical plausibility limits (SI) of every field: what an orchard tree, a harvester's
#: pendulum or billet, and a contact pad can be, with generous margins (README table).
#: Beyond them the models leave their assumptions (small deflections, a beam) or the
#: numbers leave what double precision and a bounded run can resolve. A view of the
#: registry (:mod:`.registry`): dotted path -> (low, high, unit).
LIMITS = {p.path: (p.low, p.high, p.unit) for p in PARAMETERS if p.path is not None}


#: Default E / G of the trunk's wood (Timoshenko beam theory only): the USDA Wood Handbook
#: (FPL-GTR-282, 2021, Table 5-1, about 12 % moisture) lists G_LR / E_L and G_LT / E_L of
#: hardwoods between about 0.04 and 0.15, typically 0.06-0.09 (white ash 0.109 and 0.077,
#: eastern cottonwood 0.076 and 0.052, yellow birch G_LR / E_L 0.074); a round stem shears in
#: both planes, so G = E / 13 (G / E = 0.077), the middle of the typical range. No green-wood
#: ratios are tabulated: the ratio is taken as is. docs/beam-impact.md.
DEFAULT_E_OVER_G = 13.0
#: Poisson's ratio for the shear coefficient: a typical longitudinal ratio of hardwoods
#: (Wood Handbook Table 5-2: white ash mu_LR 0.371, mu_LT 0.440).
DEFAULT_POISSON = 0.4
#: kappa = 6 (1 + nu) / (7 + 6 nu) of a solid circular section (Cowper 1966, J. Appl. Mech.
#: 33:335-340) at DEFAULT_POISSON: 0.8936 (0.886-0.900 for nu in [0.3, 0.5]).
DEFAULT_SHEAR_COEFFICIENT = 6.0 * (1.0 + DEFAULT_POISSON) / (7.0 + 6.0 * DEFAULT_POISSON)


def check_limit(path: str, value, *, high=None) -> float:
    """:func:`check_range` of ``value`` against the :data:`LIMITS` of the dotted field
    ``path`` (``high``: a tighter bound, e.g. a <= l)."""
    low, top, unit = LIMITS[path]
    if high is not None and high < top:
        top = high
    return check_range(path, value, low=low, high=None if math.isinf(top) else top,
                       unit=unit if unit != "1" else "", allow_inf=math.isinf(top))


def check_range(path: str, value, *, low=None, high=None, low_open=False, high_open=False,
           unit: str = "", allow_inf: bool = False) -> float:
    """Return ``value`` as float or raise a one-line :class:`ParameterError`.

    Args:
        path: the name the error gives (a field's dotted path or a flag).
        value: the number to check (bool and non-numbers are refused).
        low: the lower bound, or None.
        high: the upper bound, or None.
        low_open: the lower bound is excluded.
        high_open: the upper bound is excluded.
        unit: the unit the error names, or "".
        allow_inf: an infinite value is allowed (within the bounds).

    Returns:
        ``value`` as a float.

    Raises:
        ParameterError: not a number, NaN, infinite (unless allowed) or out of range.
    """
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(f"{path}: expected a number{f' in {unit}' if unit else ''}, got {value!r}")
    try:
        v = float(value)
    except OverflowError:  # an integer beyond double precision
        raise ParameterError(f"{path}: a number of {len(str(abs(value)))} digits is beyond "
                             "double precision (about 1.8e308)") from None
    lo = "(" if low_open else "["
    hi = ")" if high_open else "]"
    rng = f"{lo}{'-inf' if low is None else f'{low:g}'}, {'inf' if high is None else f'{high:g}'}{hi}"
    u = f" {unit}" if unit else ""
    if math.isnan(v) or (math.isinf(v) and not allow_inf):
        raise ParameterError(f"{path} = {value!r}{u}: must be a finite number in {rng}{u}")
    bad = ((low is not None and (v < low or (low_open and v == low)))
           or (high is not None and (v > high or (high_open and v == high))))
    if bad:
        raise ParameterError(f"{path} = {value!r}{u} is out of range: allowed {rng}{u}")
    return v


def pendulum_stiffness(mass: float, gravity: float, equivalent_length: float) -> float:
    """k = m g / l_e, N/m from the ``mass`` m (kg), ``gravity`` g (m/s^2) and
    ``equivalent_length`` l_e (m): the pendulum as a spring for small swings (Fig 3, eq 13)."""
    return mass * gravity / equivalent_length


def pendulum_impact_speed(gravity: float, equivalent_length: float,
                          release_angle: float) -> float:
    """u_1 = 2 sqrt(g l_e) sin(theta_r / 2), m/s (eq 48), from ``gravity`` g (m/s^2),
    ``equivalent_length`` l_e (m) and ``release_angle`` theta_r (rad)."""
    return 2.0 * math.sqrt(gravity * equivalent_length) * math.sin(release_angle / 2.0)


@dataclass(frozen=True)
class Trunk:
    """Uniform cantilever trunk with clamp and crown point masses (eqs 1-11), validated on
    construction against :data:`LIMITS` (ParameterError naming the field otherwise).

    Attributes:
        length: l, the height of the lumped crown above the ground, m.
        clamp_height: a, the impact (clamp) height, at most l, m.
        diameter: d, m.
        density: rho, kg/m^3.
        youngs_modulus: E, Pa.
        clamp_mass: m_c, the harvester's clamp at a, kg.
        crown_mass: m_f, fruit, leaves and scaffold wood at l, kg.
        damping: C, the distributed viscous damping (eq 9), N s/m^2.
        base_stiffness: k_theta, a rotational root spring at the ground, N m/rad (inf: the
            paper's rigid clamp).
        shear_modulus: G, Pa (Timoshenko beam theory only; None: E / 13).
        shear_coefficient: kappa, 1 (Timoshenko only; None: 0.894).
    """

    length: float  # l, m: height of the lumped crown mass above the ground
    clamp_height: float  # a, m: height of the impact point (clamp)
    diameter: float  # d, m
    density: float  # rho, kg/m^3
    youngs_modulus: float  # E, Pa
    clamp_mass: float = 0.0  # m_c, kg
    crown_mass: float = 0.0  # m_f, kg
    damping: float = 0.0  # C, N s/m^2: viscous damping force per unit length per unit velocity
    base_stiffness: float = math.inf  # k_theta, N m/rad
    # Timoshenko beam theory only (None: the defaults above); inf: rigid in shear
    shear_modulus: float | None = None  # G, Pa (default E / DEFAULT_E_OVER_G)
    shear_coefficient: float | None = None  # kappa, 1 (default DEFAULT_SHEAR_COEFFICIENT)

    def __post_init__(self):
        check_limit("trunk.length", self.length)
        check_limit("trunk.clamp_height", self.clamp_height,
               high=self.length if isinstance(self.length, (int, float)) else None)
        check_limit("trunk.diameter", self.diameter)
        check_limit("trunk.density", self.density)
        check_limit("trunk.youngs_modulus", self.youngs_modulus)
        check_limit("trunk.clamp_mass", self.clamp_mass)
        check_limit("trunk.crown_mass", self.crown_mass)
        check_limit("trunk.damping", self.damping)
        check_limit("trunk.base_stiffness", self.base_stiffness)
        if self.shear_modulus is not None:
            check_limit("trunk.shear_modulus", self.shear_modulus)
        if self.shear_coefficient is not None:
            check_limit("trunk.shear_coefficient", self.shear_coefficient)

    @property
    def area(self) -> float:
        """Cross-section A = pi d^2 / 4, m^2."""
        return math.pi * self.diameter ** 2 / 4.0

    @property
    def second_moment(self) -> float:
        """Area moment of inertia I = pi d^4 / 64, m^4."""
        return math.pi * self.diameter ** 4 / 64.0

    @property
    def bending_stiffness(self) -> float:
        """E I, N m^2."""
        return self.youngs_modulus * self.second_moment

    @property
    def shear_rigidity(self) -> float:
        """kappa G A, N: the section's shear stiffness (Timoshenko; inf when rigid in shear),
        with the defaults for a G or kappa not given."""
        g = (self.youngs_modulus / DEFAULT_E_OVER_G if self.shear_modulus is None
             else self.shear_modulus)
        kappa = (DEFAULT_SHEAR_COEFFICIENT if self.shear_coefficient is None
                 else self.shear_coefficient)
        return kappa * g * self.area

    @property
    def trunk_mass(self) -> float:
        """m_t = rho A l, kg (after eq 7)."""
        return self.density * self.area * self.length


@dataclass(frozen=True)
class Pendulum:
    """Pendulum impactor released from rest at ``release_angle_deg`` (eq 48); after the first
    impact it is linearised as mass m on a spring k = m g / l_e (Fig 3, eq 13), natural
    frequency omega_2 = sqrt(g / l_e). Validated on construction (ParameterError).

    Attributes:
        mass: m, kg.
        equivalent_length: l_e, m.
        release_angle_deg: theta_r, deg (degrees here as in the scenario files, the command
            line and the JSON; :attr:`release_angle_rad` gives radians).
        gravity: g, m/s^2 (the paper's 9.81).
    """

    mass: float  # m, kg
    equivalent_length: float  # l_e, m
    release_angle_deg: float  # theta_r, deg
    gravity: float = STANDARD_GRAVITY  # g, m/s^2

    def __post_init__(self):
        check_limit("impactor.mass", self.mass)
        check_limit("impactor.equivalent_length", self.equivalent_length)
        check_limit("impactor.release_angle_deg", self.release_angle_deg)
        check_limit("impactor.gravity", self.gravity)

    @property
    def stiffness(self) -> float:
        """Equivalent spring k = m g / l_e, N/m (Fig 3, eq 13)."""
        return pendulum_stiffness(self.mass, self.gravity, self.equivalent_length)

    @property
    def natural_frequency(self) -> float:
        """omega_2 = sqrt(g / l_e), rad/s (eq 14)."""
        return math.sqrt(self.gravity / self.equivalent_length)

    @property
    def impact_speed(self) -> float:
        """u_1 = 2 sqrt(g l_e) sin(theta_r / 2), m/s (eq 48)."""
        return pendulum_impact_speed(self.gravity, self.equivalent_length,
                                     self.release_angle_rad)

    @property
    def release_angle_rad(self) -> float:
        """theta_r in radians, rad."""
        return math.radians(self.release_angle_deg)


@dataclass(frozen=True)
class Billet:
    """A mass striking at ``impact_speed`` (the paper's spring-loaded billet): unrestrained
    (``stiffness`` 0, omega_2 = 0, "substituted as zero" after Table 1) or held by a spring
    k at its rest position where it first touches (m y'' + k y = -F, eq 13 with k for
    m g / l_e). Validated on construction (ParameterError).

    Attributes:
        mass: m, kg.
        impact_speed: u_1, m/s.
        stiffness: k, the billet's spring, N/m (0: a free billet).
    """

    mass: float  # m, kg
    impact_speed: float  # u_1, m/s
    stiffness: float = 0.0  # k, N/m

    def __post_init__(self):
        check_limit("impactor.mass", self.mass)
        check_limit("impactor.impact_speed", self.impact_speed)
        check_limit("impactor.stiffness", self.stiffness)

    @property
    def natural_frequency(self) -> float:
        """omega_2 = sqrt(k / m), rad/s (0 for a free billet)."""
        return math.sqrt(self.stiffness / self.mass)


@dataclass(frozen=True)
class Contact:
    """The contact between impactor and trunk: Newton's e (eq 21) and, for the soft
    (spring-dashpot) models, the pad given by its stiffness or by its contact duration
    (at most one of them; neither: the default 0.5 ms duration). Validated on construction.

    Attributes:
        restitution: e, 1.
        stiffness: k_c, the pad's stiffness, N/m (``contact.stiffness``, the
            ``contact_stiffness`` option).
        duration: the pad's contact duration, the undamped collision time pi sqrt(mu / k_c)
            of the 1-DOF pair, s (``contact.duration``, the ``contact_duration`` option; not
            the touch duration, first touch to release).
    """

    restitution: float  # e, dimensionless
    stiffness: float | None = None  # k_c, N/m
    duration: float | None = None  # s

    def __post_init__(self):
        check_limit("contact.restitution", self.restitution)
        if self.stiffness is not None:
            check_limit("contact.stiffness", self.stiffness)
        if self.duration is not None:
            check_limit("contact.duration", self.duration)
        if self.stiffness is not None and self.duration is not None:
            raise ParameterError("contact: give either stiffness (N/m) or duration (s), not both")


#: s: the pad's duration where a scenario gives neither stiffness nor duration (the
#: registry's default, with its source).
DEFAULT_CONTACT_DURATION = default_of("contact_duration")


@dataclass(frozen=True)
class Scenario:
    """One impact experiment: trunk, impactor and contact, simulated until ``t_end``.
    Validated on construction (ParameterError naming the field).

    Attributes:
        name: names its files (1-64 letters, digits, '.', '_', '-' or spaces).
        trunk: the :class:`Trunk`.
        impactor: the :class:`Pendulum` or :class:`Billet`.
        contact: the :class:`Contact`.
        t_end: the simulated time after the first contact, s.
        description: one line for people.
        notes: the scenario file's ``[calibration]`` table: what was given, chosen and
            calibrated (free text).
    """

    name: str
    trunk: Trunk
    impactor: Pendulum | Billet
    contact: Contact
    t_end: float = 0.1  # s
    description: str = ""
    notes: dict = field(default_factory=dict, compare=False, hash=False)

    def __post_init__(self):
        if not (isinstance(self.name, str) and _NAME.fullmatch(self.name)):
            raise ParameterError(f"name = {self.name!r}: allowed 1-64 letters, digits, '.', "
                                 "'_', '-' or spaces, not starting with '.' or a space (it "
                                 "names files: the scenario's, a report's figures)")
        if not isinstance(self.trunk, Trunk):
            raise ParameterError("trunk: expected a Trunk")
        if not isinstance(self.impactor, (Pendulum, Billet)):
            raise ParameterError("impactor: expected a Pendulum or a Billet")
        if not isinstance(self.contact, Contact):
            raise ParameterError("contact: expected a Contact")
        check_limit("t_end", self.t_end)

    def to_dict(self) -> dict:
        """The scenario as run, in the JSON layout of ``treeimpact simulate``."""
        t = self.trunk
        imp = self.impactor
        impactor = {"mass": imp.mass}
        if isinstance(imp, Pendulum):
            impactor.update(type="pendulum", equivalent_length=imp.equivalent_length,
                            release_angle_deg=imp.release_angle_deg, gravity=imp.gravity)
        else:
            impactor.update(type="billet", impact_speed=imp.impact_speed,
                            stiffness=imp.stiffness)
        return {
            "name": self.name,
            "t_end": self.t_end,
            "trunk": {
                "length": t.length, "clamp_height": t.clamp_height, "diameter": t.diameter,
                "density": t.density, "youngs_modulus": t.youngs_modulus,
                "clamp_mass": t.clamp_mass, "crown_mass": t.crown_mass, "damping": t.damping,
                "base_stiffness": None if math.isinf(t.base_stiffness) else t.base_stiffness,
                "shear_modulus": t.shear_modulus, "shear_coefficient": t.shear_coefficient,
            },
            "impactor": impactor,
            "contact": {"restitution": self.contact.restitution,
                        "stiffness": self.contact.stiffness,
                        "duration": self.contact.duration},
        }
