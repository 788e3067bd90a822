"""The pad's contact phases and the rule that switches between them, written once for every
solver of the pad F = max(0, k_c delta + c_c delta') (:mod:`.law`): the exact linear
solver's two evaluations (:mod:`.exact_solve`, :mod:`.exact_record`) and the soft rung's
DOP853 integration (:mod:`.soft`).

The pad only pushes, and it releases when the force, not the overlap, reaches zero, so a
released pad may still overlap:

* ``CONTACT``: the law F = k_c delta + c_c delta' is positive and acts; the phase ends when
  F falls through 0, into ``OVERLAP`` if delta > 0 there, else ``FREE``;
* ``OVERLAP``: released with delta > 0 (F = 0); ends when the law rises through 0 (back to
  ``CONTACT``) or delta falls through 0 (``FREE``), whichever comes first;
* ``FREE``: apart, delta <= 0; ends when delta rises through 0 (``CONTACT``).
"""

from __future__ import annotations

import enum
from collections.abc import Callable

from treeimpact.analytic.errors import SimulationDiverged

#: Switches past which a solution is refused as chatter that does not end (a guard: the
#: shipped trees take 20-50).
MAX_SWITCHES = 100_000


class Signal(enum.Enum):
    """A function of the motion whose zero ends a phase."""

    DELTA = "delta"  # the overlap y - x, m
    LAW = "law"  # k_c delta + c_c delta', N


class ContactPhase(enum.Enum):
    """The pad's state between two switches (the module docstring)."""

    CONTACT = "contact"
    OVERLAP = "overlap"
    FREE = "free"

    @property
    def touching(self) -> bool:
        """Whether the pad's spring and dashpot act (the linear system's contact state)."""
        return self is ContactPhase.CONTACT

    def has_ended(self, delta, law):
        """Where this phase is over, given delta (m) and the law (N) at the samples
        (arrays or floats): the sign each ending event has once crossed."""
        if self is ContactPhase.CONTACT:
            return law <= 0.0
        if self is ContactPhase.OVERLAP:
            return (law > 0.0) | (delta < 0.0)
        return delta > 0.0

    def after(self, signal: Signal, delta: float) -> ContactPhase:
        """The phase that follows this one when ``signal`` crosses zero (``delta``, m, at
        that instant: a released pad still overlaps when delta > 0)."""
        if self is ContactPhase.CONTACT:
            return ContactPhase.OVERLAP if delta > 0.0 else ContactPhase.FREE
        if self is ContactPhase.FREE or signal is Signal.LAW:
            return ContactPhase.CONTACT
        return ContactPhase.FREE


def switch(phase: ContactPhase, root: Callable[[Signal], float],
           delta_at: Callable[[float], float], delta_hi: float, law_hi: float
           ) -> tuple[float, ContactPhase]:
    """(time into the phase, next phase) of the switch that ends ``phase`` in a bracket
    where :meth:`ContactPhase.has_ended` first holds at its upper end, with delta (m) and
    the law (N) there ``delta_hi``, ``law_hi``. ``root(signal)`` is the zero of the signal
    in the bracket (s), ``delta_at(s)`` the overlap at s (m)."""
    if phase is ContactPhase.CONTACT:
        s = root(Signal.LAW)
        return s, phase.after(Signal.LAW, delta_at(s))
    if phase is ContactPhase.FREE:
        return root(Signal.DELTA), ContactPhase.CONTACT
    ends = []  # overlap: whichever of the law rising and delta falling comes first
    if law_hi > 0.0:
        ends.append((root(Signal.LAW), ContactPhase.CONTACT))
    if delta_hi < 0.0:
        ends.append((root(Signal.DELTA), ContactPhase.FREE))
    return min(ends, key=lambda end: end[0])


def bracket(value: Callable[[float], float], lo: float, hi: float, f_hi: float):
    """(lo', value(lo')) with value(lo') of the sign opposite to ``f_hi`` (the value at
    ``hi``): lo itself, or, when the bracket's low end sits on the previous switch (value 0
    there, or the same sign), moved in by 1e-9, 1e-8, ... of the interval [lo, hi] until the
    sign differs; None when it never does."""
    f_lo = value(lo)
    if f_lo * f_hi > 0 or f_lo == 0.0:
        step = (hi - lo) * 1e-9
        while step < (hi - lo):
            f_lo = value(lo + step)
            if f_lo * f_hi < 0:
                return lo + step, f_lo
            step *= 10.0
        return None
    return lo, f_lo



def check_switches(switches: int, t: float) -> None:
    """Refuse a solution past :data:`MAX_SWITCHES` switches (at ``t``, s) as diverged."""
    if switches > MAX_SWITCHES:
        raise SimulationDiverged(f"beam: more than {MAX_SWITCHES} contact switches by "
                                 f"t = {t:.6g} s (chatter does not end)")
