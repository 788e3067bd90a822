"""The paper's identification procedure (eqs 39-48): tree properties from a pendulum test.

Steps (paper, "Determination of physical properties"):

1. find where the bodies begin to move together (the last sudden increase of slope of
   x(t), within a few ms of the first impact);
2. extrapolate x(t) linearly from there to the time axis and take that point as origin;
3. fit a polynomial to at most 10 ms of the record after the moving-together point;
4. with x0 = 0 at the new origin, V = a1 and b = -a2/a1 (eq 42);
5. omega_n = V / beta, beta = x_max e^(b tau) (eq 43, eq 38 with x0 = 0), the paper's xi
   = b / omega_n (``pair_damping_ratio``: trunk and pendulum moving together);
6. M_T from eq 44, K_T from eq 46, E from eq 47, u_1 from eq 48.

Readings of eqs 44 and 46 (see ``analytic.paper.reproduction.DISCREPANCIES``):

* ``"paper"``: the reading that reproduces Table 1: eq 44 with the + sign of its own
  derivation and, in eqs 44 and 46, omega_1 = the damped frequency omega_n sqrt(1 - xi^2)
  of the moving-together motion, the paper's xi = b / omega_n (``pair_damping_ratio``);
* ``"printed"``: eq 44 as printed (minus sign) with omega_1 = omega_n;
* ``"consistent"``: the momentum balance of the impact process, exact for any e,
  m u_1 - (M_T + m) V = K_T A_x + C_T x_0 + k A_y, closed with K_T = omega_n^2 (M_T + m) - k
  and C_T = 2 b (M_T + m) from the moving-together motion (eq 34).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.parameters import (
    STANDARD_GRAVITY,
    pendulum_impact_speed,
    pendulum_stiffness,
)
from treeimpact.analytic.model.two_body import two_body_model

from .events import find_events, impact_sequence, moving_together, peak
from .noise import NoiseSource

READINGS = ("paper", "printed", "consistent")


@dataclass(frozen=True)
class PendulumTest:
    """What the experimenter knows: the pendulum and where it struck (SI, angle in rad)."""

    impactor_mass: float  # m, kg
    equivalent_length: float  # l_e, m
    release_angle: float  # theta_r, rad
    clamp_height: float  # a, m
    diameter: float  # d, m
    gravity: float = STANDARD_GRAVITY

    @property
    def impact_speed(self) -> float:
        """u_1 = 2 sqrt(g l_e) sin(theta_r / 2), m/s (eq 48)."""
        return pendulum_impact_speed(self.gravity, self.equivalent_length, self.release_angle)

    @property
    def impactor_stiffness(self) -> float:
        """k = m g / l_e, N/m (eq 13)."""
        return pendulum_stiffness(self.impactor_mass, self.gravity, self.equivalent_length)

    @property
    def omega2_sq(self) -> float:
        """omega_2^2 = g / l_e, 1/s^2: the pendulum's own frequency squared (eq 13)."""
        return self.gravity / self.equivalent_length


def youngs_modulus(equivalent_stiffness: float, clamp_height: float, diameter: float) -> float:
    """E = K_T a^3 / (3 I), Pa, I = pi d^4 / 64 (eq 47; K_T = 3 E I / a^3, eq 8), from the
    ``equivalent_stiffness`` K_T (N/m), the ``clamp_height`` a (m) and the trunk's
    ``diameter`` d (m)."""
    return equivalent_stiffness * clamp_height ** 3 / (3.0 * (math.pi * diameter ** 4 / 64.0))


#: The symbols the identified quantities go by outside the code (:meth:`Identified.as_dict`,
#: :func:`truth_of`, the JSON): field name -> key.
KEYS = {"dynamic_mass": "M_T", "equivalent_stiffness": "K_T"}


@dataclass(frozen=True)
class Identified:
    """Result of the procedure (SI units)."""

    reading: str
    V: float
    b: float  # 1/s, eq 42
    omega_n: float  # rad/s, eq 43
    pair_damping_ratio: float  # b / omega_n, the paper's xi: trunk and pendulum together
    omega_1: float  # rad/s, the frequency used in eqs 44 and 46 under this reading
    u1: float  # m/s, eq 48
    x0: float  # m
    T0: float  # s
    A_x: float  # m s
    A_y: float  # m s
    dynamic_mass: float  # kg, eq 44
    equivalent_stiffness: float  # N/m, eq 46
    E: float  # Pa, eq 47
    x_max: float
    tau: float  # s, time of x_max from the extrapolated origin

    def as_dict(self) -> dict:
        """Every field, name -> value (SI), the quantities by their symbols (:data:`KEYS`)."""
        return {KEYS.get(name, name): value for name, value in asdict(self).items()}


def identify(*, a1: float, a2: float, x_max: float, tau: float, x0: float, T0: float,
             test: PendulumTest, A_x: float | None = None, A_y: float | None = None,
             reading: str = "paper") -> Identified:
    """Steps 4-6 from the regression coefficients a1 (m/s), a2 (m/s^2) and the record's
    x_max (m), tau (s), x0 (m), T0 (s), with the pendulum ``test``. A_x, A_y (m s) default
    to eq 45 as the table uses it, x0 T0 / 2 (the printed (x0 T0)^2 / 2 is dimensionally
    wrong). ``reading``: of eqs 44 and 46, one of :data:`READINGS` (module docstring)."""
    if reading not in READINGS:
        raise ParameterError(f"reading = {reading!r}: allowed {', '.join(READINGS)}")
    if not (a1 > 0):
        raise ParameterError(f"a1 = {a1!r} m/s: the fitted velocity must be > 0")
    b = -a2 / a1  # eq 42
    beta = x_max * math.exp(b * tau)
    omega_n = a1 / beta  # eq 43
    pair = b / omega_n  # the paper's xi
    A_x = 0.5 * x0 * T0 if A_x is None else A_x
    A_y = 0.5 * x0 * T0 if A_y is None else A_y
    m, k, w2 = test.impactor_mass, test.impactor_stiffness, test.omega2_sq
    u1, V = test.impact_speed, a1
    if reading == "consistent":
        omega_1 = omega_n
        dynamic_mass = ((m * (u1 - V) - k * A_y + k * A_x - m * omega_n ** 2 * A_x
                         - 2 * b * m * x0)
                        / (V + omega_n ** 2 * A_x + 2 * b * x0))
        equivalent_stiffness = omega_n ** 2 * (dynamic_mass + m) - k
    else:
        if reading == "paper":
            omega_1, sign = omega_n * math.sqrt(max(0.0, 1.0 - pair * pair)), 1.0
        else:
            omega_1, sign = omega_n, -1.0
        dynamic_mass = (m * (u1 - V - w2 * A_y)
                        / (V + omega_1 ** 2 * A_x + sign * 2 * pair * omega_1 * x0))
        equivalent_stiffness = omega_1 ** 2 * (dynamic_mass + m) - k  # eq 46
    E = youngs_modulus(equivalent_stiffness, test.clamp_height, test.diameter)  # eq 47
    return Identified(reading=reading, V=V, b=b, omega_n=omega_n, pair_damping_ratio=pair,
                      omega_1=omega_1,
                      u1=u1, x0=x0, T0=T0, A_x=A_x, A_y=A_y, dynamic_mass=dynamic_mass,
                      equivalent_stiffness=equivalent_stiffness, E=E,
                      x_max=x_max, tau=tau)


@dataclass(frozen=True)
class Regression:
    """Steps 1-3 on a record: where the bodies move together and the fitted polynomial,
    every displacement from the record's resting level (``baseline``)."""

    t_first: float  # s, first impact (first slope increase above the noise)
    t_together: float  # s, last slope increase: bodies move together
    x_together: float  # m, x at t_together (the paper's x0)
    t_origin: float  # s, origin after the linear extrapolation
    coefficients: tuple  # a0, a1, a2, ... in the shifted time
    x_max: float
    tau: float  # s, from t_origin
    baseline: float = 0.0  # m, the resting level removed (0: no rest recorded)
    noise: float = 0.0  # m, the record's noise the events were found against
    noise_source: str = NoiseSource.DIFFERENCES.value  # where the noise came from
    jump_threshold: float = 0.0  # m/s, the smallest slope increase counted as an impact
    slope_span: int = 1  # samples each side a slope was read over to find the impacts
    sequence: tuple = ()  # s, the impacts read as the impact process (first ... together)


def regress(t, x, *, window: float = 0.010, degree: int = 2, jump_fraction: float = 1e-4,
            search_time: float = 0.02, t_together: float | None = None,
            y=None) -> Regression:
    """Steps 1-3 of the procedure on a sampled displacement record x(t) (m, s).

    The events are found against the record's noise (:mod:`.events`): the resting level
    and the noise from the rest before the contact (else the sensor's zero and the
    high-pass noise); an impact is a slope increase larger than ``jump_fraction`` of the
    largest slope and than the noise could make, each read against the motion's own
    curvature; the bodies move together at the last impact of the sequence
    (:func:`.events.impact_sequence`: its gaps shrink, eq 33) within ``search_time`` (s) of
    the first or before the displacement's peak, or at ``t_together`` if given (e.g. from
    a contact channel, as Pellerin et al. recorded). The polynomial of ``degree`` is fitted
    over ``window`` (s, at most 10 ms) from there. ParameterError "not identifiable" when
    the record shows no impact, a second strike before its peak, impacts up to its peak,
    ends inside the window or before its peak, or (with the pendulum's record ``y``, m)
    the bodies apart on the way to the peak (:func:`.events.moving_together`).
    """
    t = np.asarray(t, float)
    x = np.asarray(x, float)
    if t.ndim != 1 or t.shape != x.shape or t.size < 10:
        raise ParameterError("record: t and x must be 1-D arrays of the same length (>= 10)")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(x))):
        raise ParameterError("record: t and x must be finite")
    if not (0 < window <= 0.010 + 1e-12):
        raise ParameterError(f"window = {window!r} s is out of range: allowed (0, 0.01] s")
    noise, impacts = find_events(t, x, jump_fraction)
    x = x - noise.baseline
    t_first = float(impacts.times[0])
    t_max, x_max = peak(t, x, noise.sigma)
    sequence = ()
    if t_together is None:  # the last impact of the sequence, before the peak
        dt = float(np.median(np.diff(t)))
        seq = impact_sequence(impacts.times, t_first, t_max, dt, search_time)
        t_together, sequence = float(seq[-1]), tuple(float(v) for v in seq)
        if y is not None:
            moving_together(t, x, np.asarray(y, float) - noise.baseline, t_together, t_max,
                            noise.sigma)
    sel = (t >= t_together) & (t <= t_together + window)
    if np.count_nonzero(sel) <= degree + 1:
        raise ParameterError("record: too few samples in the regression window")
    if t[-1] < t_together + window - np.median(np.diff(t)):
        left = 1e3 * (t[-1] - t_together)
        raise ParameterError(f"not identifiable: the record ends {left:.3g} ms after the "
                             f"bodies move together, inside the {1e3 * window:.3g} ms "
                             "regression window")
    s = t[sel] - t_together
    local = np.polynomial.polynomial.polyfit(s, x[sel], degree)
    x_tog, v_tog = local[0], local[1]
    t_origin = t_together - x_tog / v_tog  # linear extrapolation to x = 0
    coeffs = np.polynomial.polynomial.polyfit(t[sel] - t_origin, x[sel], degree)
    return Regression(t_first=t_first, t_together=t_together, x_together=float(x_tog),
                      t_origin=float(t_origin), coefficients=tuple(float(c) for c in coeffs),
                      x_max=x_max, tau=t_max - float(t_origin), baseline=noise.baseline,
                      noise=noise.sigma, noise_source=noise.source.value,
                      jump_threshold=impacts.threshold, slope_span=impacts.span,
                      sequence=sequence)


def short_process(t_first: float, t_together: float, t_origin: float, t_max: float,
                  x0_share: float) -> None:
    """Raises ParameterError "not identifiable" unless the line through the moving-together
    point (``t_together``, s; x0 at ``x0_share`` of x_max) reaches x = 0 (``t_origin``, s)
    no further before the first impact (``t_first``, s) than the first impact lies before
    the peak (``t_max``, s). Eqs 42-43 read the motion from that origin as if the bodies
    had moved together from it (x0 = 0: "the bodies move together within a very short time
    after the start of the impact process"); an origin earlier than that is a time the tree
    had not been struck yet, and tau = t_max - t_origin no time of the record (a long
    sequence ending near the peak: realistic-crown at e = 0.1, docs/identification.md)."""
    if t_first - t_origin > t_max - t_first:
        raise ParameterError(
            f"not identifiable: the impact process is not short (the bodies move together "
            f"{1e3 * (t_together - t_first):.3g} ms after the first impact, at "
            f"{100 * x0_share:.0f} % of x_max; the line through that point reaches x = 0 "
            f"{1e3 * (t_first - t_origin):.3g} ms before the first impact, more than the "
            f"{1e3 * (t_max - t_first):.3g} ms to the peak): eqs 42-43's x0 = 0 does not hold")


def identify_from_record(t, x, test: PendulumTest, *, y=None, reading: str = "paper",
                         **regress_kw) -> tuple[Identified, Regression]:
    """The whole procedure on a record x(t) (``x`` m at the times ``t`` s) of the pendulum
    ``test``, in the ``reading`` of eqs 44 and 46; ``regress_kw`` go to :func:`regress`.
    A_x comes from the record (trapezoid from the first impact to the moving-together
    point); A_y from the pendulum record ``y`` if given, else eq 45 (x0 T0 / 2).
    ParameterError "not identifiable" as :func:`regress`, when the impact process is not
    short (:func:`short_process`) or the result breaks a premise (:func:`check_identifiable`)."""
    t = np.asarray(t, float)
    x = np.asarray(x, float)
    reg = regress(t, x, y=y, **regress_kw)
    short_process(reg.t_first, reg.t_together, reg.t_origin, reg.t_origin + reg.tau,
                  reg.x_together / reg.x_max)
    x = x - reg.baseline
    x0 = reg.x_together
    T0 = reg.t_together - reg.t_first
    sel = (t >= reg.t_first) & (t <= reg.t_together)
    A_x = float(np.trapezoid(x[sel], t[sel])) if np.count_nonzero(sel) > 1 else 0.0
    A_y = None
    if y is not None:
        A_y = float(np.trapezoid(np.asarray(y, float)[sel], t[sel])) if np.count_nonzero(
            sel) > 1 else 0.0
    ident = identify(a1=reg.coefficients[1], a2=reg.coefficients[2], x_max=reg.x_max,
                     tau=reg.tau, x0=x0, T0=T0, test=test, A_x=A_x, A_y=A_y, reading=reading)
    check_identifiable(ident)
    return ident, reg


def procedure_readings(t, x, test: PendulumTest, *, y=None) -> dict:
    """The whole procedure (:func:`identify_from_record`) on the record x(t) (``x``, ``y`` m
    at the times ``t`` s) of the pendulum ``test`` in each of the :data:`READINGS`: reading
    -> M_T (kg), K_T (N/m), C_T = 2 b (M_T + m) (N s/m, eq 34: b of the pair moving
    together, mass M_T + m), E (Pa), ``pair_damping_ratio`` (the paper's xi = b / omega_n)
    and ``trunk_damping_ratio`` C_T / (2 sqrt(K_T M_T)); or ``{"error": one line}`` for a
    reading that cannot run on it (not identifiable, or its numbers fail)."""
    out = {}
    for reading in READINGS:
        try:
            with np.errstate(all="ignore"):  # a reading's numbers are checked: one line each
                ident, _ = identify_from_record(t, x, test, y=y, reading=reading)
        except (ParameterError, ValueError, FloatingPointError) as exc:
            out[reading] = {"error": " ".join(str(exc).split())}
            continue
        M, K = ident.dynamic_mass, ident.equivalent_stiffness  # > 0: check_identifiable
        equivalent_damping = 2.0 * ident.b * (M + test.impactor_mass)
        trunk = equivalent_damping / (2.0 * math.sqrt(K * M))
        out[reading] = {"M_T": M, "K_T": K, "C_T": equivalent_damping, "E": ident.E,
                        "pair_damping_ratio": ident.pair_damping_ratio,
                        "trunk_damping_ratio": trunk}
    return out


def check_identifiable(ident: Identified) -> Identified:
    """``ident`` if the procedure's premises hold on the record, else a one-line
    ParameterError starting "not identifiable": the moving-together motion decays and
    oscillates (pair damping ratio b / omega_n in (0, 1), eqs 35-36), the common velocity
    is below the impact speed (V < u1: the pendulum gave the trunk momentum, eq 44), and M_T
    and K_T come out positive (eqs 44 and 46). A number that breaks them is not a property
    of the tree."""
    problem = None
    if not 0.0 < ident.pair_damping_ratio < 1.0:
        problem = (f"pair_damping_ratio = {ident.pair_damping_ratio:.3g} (b = {ident.b:.3g} "
                   f"1/s, omega_n = {ident.omega_n:.3g} rad/s): the motion after moving "
                   "together does not decay as a damped oscillation (eqs 35-36 need "
                   "0 < b / omega_n < 1)")
    elif not ident.V < ident.u1:
        problem = (f"V = {ident.V:.3g} m/s is not below the impact speed u1 = "
                   f"{ident.u1:.3g} m/s (eq 44)")
    elif not (ident.dynamic_mass > 0.0 and ident.equivalent_stiffness > 0.0):
        problem = (f"M_T = {ident.dynamic_mass:.3g} kg, K_T = "
                   f"{ident.equivalent_stiffness:.3g} N/m: eqs 44 and 46 give "
                   "a non-positive mass or stiffness")
    if problem is not None:
        raise ParameterError(f"not identifiable: {problem}")
    return ident


def pendulum_test_of(scenario) -> PendulumTest:
    """The experimenter's knowledge of a shipped scenario (pendulum impactor only)."""
    imp = scenario.impactor
    if not hasattr(imp, "equivalent_length"):
        raise ParameterError("impactor.type: the identification procedure needs a pendulum")
    return PendulumTest(impactor_mass=imp.mass, equivalent_length=imp.equivalent_length,
                        release_angle=imp.release_angle_rad, clamp_height=scenario.trunk.clamp_height,
                        diameter=scenario.trunk.diameter, gravity=imp.gravity)


def truth_of(scenario) -> dict:
    """What the procedure should find for a scenario's SDOF model (SI)."""
    mod = two_body_model(scenario)
    dynamic_mass, equivalent_stiffness, equivalent_damping, m, k = (
        mod.dynamic_mass, mod.equivalent_stiffness, mod.equivalent_damping, mod.impactor_mass,
        mod.impactor_stiffness)
    wn = math.sqrt((equivalent_stiffness + k) / (dynamic_mass + m))
    b = equivalent_damping / (2 * (dynamic_mass + m))
    return {"M_T": dynamic_mass, "K_T": equivalent_stiffness, "b": b, "omega_n": wn,
            "pair_damping_ratio": b / wn,
            "E": youngs_modulus(equivalent_stiffness, scenario.trunk.clamp_height,
                                scenario.trunk.diameter)}


def identification_errors(ident: Identified, truth: dict) -> dict:
    """Relative errors (identified - true) / true of ``ident`` against ``truth``
    (:func:`truth_of`) for M_T, K_T, pair_damping_ratio, E, b, omega_n."""
    vals = ident.as_dict()
    return {k: (vals[k] - v) / v for k, v in truth.items()}
