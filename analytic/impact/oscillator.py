"""Closed-form free motion of a damped linear oscillator (paper eqs 13-14, 34-36).

    x'' + 2 beta x' + Omega^2 x = 0        (per unit mass: beta = C/2M, Omega^2 = K/M)

covers the tree between impacts (eq 14, under-, critically or over-damped), the
linearised pendulum (beta = 0, Omega = omega_2), the billet (beta = Omega = 0, free
flight) and the two bodies moving together (eq 34).

The motion is written with the fundamental solutions phi, psi (phi(0)=1, phi'(0)=0,
psi(0)=0, psi'(0)=1): x(t) = x0 phi(t) + v0 psi(t). The displacement *from the start*,
x(t) - x0 = x0 (phi - 1) + v0 psi, is evaluated without cancellation (expm1, half-angle
forms) so that the gap between two bodies that touch at t = 0 is accurate even for the
nanosecond flights at the end of a chattering sequence.

Every function takes ``xp`` = ``math`` (fast scalars) or ``numpy`` (arrays).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np

_CRITICAL_TOL = 1e-10  # |beta^2 - Omega^2| below this fraction of Omega^2: critically damped


@dataclass(frozen=True)
class Oscillator:
    """x'' + 2 beta x' + omega_sq x = 0 (beta >= 0 in 1/s, omega_sq >= 0 in 1/s^2)."""

    beta: float
    omega_sq: float

    def __reduce__(self):
        # pickled as its two parameters: the cached closures (scalar_advance, _bounds5) are
        # rebuilt on use (results cross process pools: compare.runs.cache.RunCache.prefetch)
        return (self.__class__, (self.beta, self.omega_sq))

    @classmethod
    def from_mck(cls, mass: float, damping: float, stiffness: float) -> "Oscillator":
        """The oscillator of m x'' + c x' + k x = 0 (``mass`` m kg, ``damping`` c N s/m,
        ``stiffness`` k N/m); one shared instance per (m, c, k), so that its constants
        (regime, :attr:`scalar_advance`, ...) are computed once."""
        return _from_mck(cls, mass, damping, stiffness)

    @cached_property
    def regime(self) -> str:
        """"under", "over" or "critical" (damped): beta^2 against omega_sq, critical within
        a relative ``_CRITICAL_TOL`` (and for the billet, beta = omega_sq = 0)."""
        d = self.beta ** 2 - self.omega_sq
        scale = max(self.beta ** 2, self.omega_sq)
        if scale == 0.0 or abs(d) <= _CRITICAL_TOL * scale:
            return "critical"
        return "under" if d < 0 else "over"

    @property
    def fastest_rate(self) -> float:
        """Largest characteristic rate |lambda|, 1/s (sets the sampling of root searches)."""
        d = self.beta ** 2 - self.omega_sq
        if d > 0:
            return self.beta + math.sqrt(d)
        return math.sqrt(self.omega_sq) if self.omega_sq > 0 else self.beta

    def fundamentals(self, t, xp=math):
        """(phi - 1, psi, phi', psi') at time(s) t >= 0 (s): the free responses to a unit
        displacement and a unit velocity; ``xp``: the math module for a scalar t, numpy for
        an array."""
        b, w2 = self.beta, self.omega_sq
        reg = self.regime
        if reg == "under":
            w = math.sqrt(w2 - b * b)
            e = xp.exp(-b * t)
            em1 = xp.expm1(-b * t)
            c = xp.cos(w * t)
            s = xp.sin(w * t)
            h = xp.sin(0.5 * w * t)
            r = b / w
            phi_m1 = em1 * (c + r * s) - 2.0 * h * h + r * s
            psi = e * s / w
            dpsi = e * (c - r * s)
        elif reg == "over":
            sd = math.sqrt(b * b - w2)
            r1, r2 = -b + sd, -b - sd
            m1, m2 = xp.expm1(r1 * t), xp.expm1(r2 * t)
            phi_m1 = (r1 * m2 - r2 * m1) / (r1 - r2)
            psi = (m1 - m2) / (r1 - r2)
            dpsi = (r1 * (m1 + 1.0) - r2 * (m2 + 1.0)) / (r1 - r2)
        else:  # critical (includes the billet, beta = Omega = 0)
            e = xp.exp(-b * t)
            em1 = xp.expm1(-b * t)
            phi_m1 = em1 * (1.0 + b * t) + b * t
            psi = t * e
            dpsi = e * (1.0 - b * t)
        return phi_m1, psi, -w2 * psi, dpsi

    def advance(self, t, x0, v0, xp=math):
        """(x(t) - x0, v(t)) from the state (x0, v0) at t = 0 (SI); ``xp``: the math module
        for a scalar t (:attr:`scalar_advance`), numpy for an array."""
        if xp is math:
            return self.scalar_advance(t, x0, v0)
        phi_m1, psi, dphi, dpsi = self.fundamentals(t, xp)
        return x0 * phi_m1 + v0 * psi, x0 * dphi + v0 * dpsi

    @cached_property
    def scalar_advance(self):
        """:meth:`advance` for one float t, specialised to the regime (the solver's hot path).

        Same formulas as :meth:`fundamentals`, with the constants computed once and the
        trigonometric functions from the half angle (sin wt = 2 sh ch, cos wt = 1 - 2 sh^2).
        """
        b, w2 = self.beta, self.omega_sq
        reg = self.regime
        expm1, sin, cos = math.expm1, math.sin, math.cos
        if reg == "under":
            w = math.sqrt(w2 - b * b)
            r, hw = b / w, 0.5 * w
            if b == 0.0:
                def adv(t, x0, v0):
                    sh, ch = sin(hw * t), cos(hw * t)
                    s, h2 = 2.0 * sh * ch, 2.0 * sh * sh
                    return -x0 * h2 + v0 * s / w, -x0 * w * s + v0 * (1.0 - h2)
                return adv

            def adv(t, x0, v0):
                em1 = expm1(-b * t)
                e = 1.0 + em1
                sh, ch = sin(hw * t), cos(hw * t)
                s, h2 = 2.0 * sh * ch, 2.0 * sh * sh
                c = 1.0 - h2
                psi = e * s / w
                return (x0 * (em1 * (c + r * s) - h2 + r * s) + v0 * psi,
                        -x0 * w2 * psi + v0 * e * (c - r * s))
            return adv
        if reg == "over":
            sd = math.sqrt(b * b - w2)
            r1, r2 = -b + sd, -b - sd
            inv = 1.0 / (r1 - r2)

            def adv(t, x0, v0):
                m1, m2 = expm1(r1 * t), expm1(r2 * t)
                psi = (m1 - m2) * inv
                return (x0 * (r1 * m2 - r2 * m1) * inv + v0 * psi,
                        -x0 * w2 * psi + v0 * (r1 * (m1 + 1.0) - r2 * (m2 + 1.0)) * inv)
            return adv

        def adv(t, x0, v0):
            em1 = expm1(-b * t)
            e = 1.0 + em1
            psi = t * e
            return (x0 * (em1 * (1.0 + b * t) + b * t) + v0 * psi,
                    -x0 * w2 * psi + v0 * e * (1.0 - b * t))
        return adv

    def acceleration(self, x, v):
        """x'' = -2 beta v - omega_sq x at the state (x, v) (m/s^2 for m, m/s)."""
        return -2.0 * self.beta * v - self.omega_sq * x

    def derivative_bounds(self, x0: float, v0: float, n_max: int = 5) -> list[float]:
        """Bounds B_n >= |x^(n)(t)| for all t >= 0, n = 0 to ``n_max``, of the motion from the
        state (``x0``, ``v0``) at t = 0 (m, m/s; B_n in m/s^n), from the modal form.

        Underdamped: x = R e^{-beta t} cos(w t + phase), and every derivative multiplies the
        complex amplitude by -beta + i w, of modulus Omega: B_n = R Omega^n.
        Overdamped: x = A e^{r1 t} + B e^{r2 t}: B_n = |A| |r1|^n + |B| |r2|^n.
        Critical: x = (A + B t) e^{-beta t}; e^{-beta t} |A + B t| <= |A| + |B| / (e beta),
        so B_n = beta^n (|A| + |B| / (e beta)) + n beta^(n-1) |B| (billet: beta = 0, B_0 = inf).
        Bounds from the state at a later time are tighter once a transient has decayed.
        """
        if n_max == 5:
            return self._bounds5(x0, v0)
        b, w2 = self.beta, self.omega_sq
        reg = self.regime
        if reg == "under":
            w = math.sqrt(w2 - b * b)
            amp = math.hypot(x0, (v0 + b * x0) / w)
            om = math.sqrt(w2)
            return [amp * om ** n for n in range(n_max + 1)]
        if reg == "over":
            sd = math.sqrt(b * b - w2)
            r1, r2 = -b + sd, -b - sd
            ca = abs((v0 - r2 * x0) / (r1 - r2))
            cb = abs((r1 * x0 - v0) / (r1 - r2))
            return [ca * abs(r1) ** n + cb * abs(r2) ** n for n in range(n_max + 1)]
        ca, cb = abs(x0), abs(v0 + b * x0)
        if b == 0.0:
            return [math.inf if cb > 0 else ca, cb] + [0.0] * (n_max - 1)
        return [b ** n * (ca + cb / (math.e * b)) + n * b ** (n - 1) * cb
                for n in range(n_max + 1)]

    @cached_property
    def _bounds5(self):
        """:meth:`derivative_bounds` with n_max = 5 (the solver's hot path): the same numbers,
        with the powers of the rates computed once."""
        b, w2 = self.beta, self.omega_sq
        reg = self.regime
        hypot = math.hypot
        if reg == "under":
            w = math.sqrt(w2 - b * b)
            om = math.sqrt(w2)
            p1, p2, p3, p4, p5 = (om ** n for n in range(1, 6))

            def bounds(x0, v0):
                amp = hypot(x0, (v0 + b * x0) / w)
                return [amp, amp * p1, amp * p2, amp * p3, amp * p4, amp * p5]
            return bounds
        if reg == "over":
            sd = math.sqrt(b * b - w2)
            r1, r2 = -b + sd, -b - sd
            d = r1 - r2
            pa = [abs(r1) ** n for n in range(6)]
            pb = [abs(r2) ** n for n in range(6)]

            def bounds(x0, v0):
                ca = abs((v0 - r2 * x0) / d)
                cb = abs((r1 * x0 - v0) / d)
                return [ca * a + cb * c for a, c in zip(pa, pb)]
            return bounds
        if b == 0.0:
            return lambda x0, v0: self.derivative_bounds(x0, v0, 6)[:6]
        pw = [b ** n for n in range(6)]
        pw1 = [n * b ** (n - 1) for n in range(6)]
        eb = math.e * b

        def bounds(x0, v0):
            ca, cb = abs(x0), abs(v0 + b * x0)
            c0 = ca + cb / eb
            return [p * c0 + q * cb for p, q in zip(pw, pw1)]
        return bounds

    def first_zero(self, f0: float, df0: float) -> float:
        """First s > 0 where a solution f of this oscillator's equation, f(0) = f0 > 0 and
        f'(0) = df0, vanishes (math.inf if never): in closed form.

        Any linear combination of x and x' (the contact force while moving together, eq 34)
        solves the same equation. Underdamped: f = e^{-beta s} (f0 cos ws + Q sin ws),
        Q = (df0 + beta f0) / w, zero at ws = atan2(f0 w, -(df0 + beta f0)) in (0, pi).
        Overdamped: f = A e^{r1 s} + B e^{r2 s} vanishes once, where e^{(r1 - r2) s} = -B/A,
        if A < 0. Critical: f = e^{-beta s} (f0 + (df0 + beta f0) s).
        """
        if not f0 > 0.0:
            raise ValueError(f"f0 = {f0!r}: must be positive")
        b, w2 = self.beta, self.omega_sq
        reg = self.regime
        if reg == "under":
            w = math.sqrt(w2 - b * b)
            return math.atan2(f0 * w, -(df0 + b * f0)) / w
        if reg == "over":
            sd = math.sqrt(b * b - w2)
            r1, r2 = -b + sd, -b - sd
            a = (df0 - r2 * f0) / (r1 - r2)  # B = f0 - A
            return math.log1p(f0 / -a) / (r1 - r2) if a < 0.0 else math.inf
        slope = df0 + b * f0
        return f0 / -slope if slope < 0.0 else math.inf


def first_peak_time(osc: Oscillator, x0: float, v0: float) -> float:
    """First s > 0 (s) at which x of ``osc`` from (x0 m, v0 m/s) has a local maximum, inf if
    never. The velocity solves the same equation, so its zeros have the closed forms of
    :meth:`Oscillator.first_zero`; at a zero x'' = -Omega^2 x, and later maxima of a damped
    oscillation are lower (underdamped: one every 2 pi / w)."""
    if v0 > 0.0:
        return osc.first_zero(v0, osc.acceleration(x0, v0))
    if osc.regime != "under":  # the velocity vanishes at most once: at a minimum, if at all
        return math.inf
    half = math.pi / math.sqrt(osc.omega_sq - osc.beta ** 2)  # between zeros of v
    if v0 < 0.0:  # x falls to a minimum first
        return osc.first_zero(-v0, -osc.acceleration(x0, v0)) + half
    if x0 == 0.0:  # at rest at the equilibrium
        return math.inf
    return half if x0 < 0.0 else 2.0 * half  # at rest at a minimum / a maximum


@lru_cache(maxsize=256)
def _from_mck(cls, mass: float, damping: float, stiffness: float) -> Oscillator:
    return cls(beta=damping / (2.0 * mass), omega_sq=stiffness / mass)


@lru_cache(maxsize=8)
def _leggauss(nodes: int):
    return np.polynomial.legendre.leggauss(nodes)


def gauss_legendre_integral(func, t0: float, t1: float, rate: float, nodes: int = 20) -> float:
    """int_{t0}^{t1} func(t) dt for a smooth (entire) integrand, by composite Gauss-Legendre.

    Panels are at most 0.5/rate long, so each panel sees less than a tenth of a period of the
    fastest motion and 20 nodes integrate it to round-off.
    """
    if t1 <= t0:
        return 0.0
    panels = max(1, int(math.ceil((t1 - t0) * max(rate, 1e-12) / 0.5)))
    xg, wg = _leggauss(nodes)
    edges = np.linspace(t0, t1, panels + 1)
    half = 0.5 * np.diff(edges)
    mid = 0.5 * (edges[1:] + edges[:-1])
    t = (mid[:, None] + half[:, None] * xg[None, :]).ravel()
    vals = np.asarray(func(t), dtype=float).reshape(panels, nodes)
    return float(np.sum(half * (vals @ wg)))
