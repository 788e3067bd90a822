"""A family of trees across the impact regimes (issue 50 items 2 and 8): trees and impactors
unlike the shipped three, each built from physics and its regime read off the paper's own
model (the exact solution of eqs 12-35), not assumed.

Every member starts from central-leader's trunk (Table 1's geometry and wood) and chooses
what sets the regime: the mass ratio m/M_T (eq 7's M_T of the member's own clamped trunk),
the clamp a/l, the crown mass m_f, the restitution e and the impactor (the paper's pendulum,
or a free or spring-loaded billet, eq 57). The rest follows: the impactor's mass is m/M_T
times M_T, a billet strikes at the pendulum's eq 48 speed, and t_end is what the exact
solution needs to show the regime (the last event plus half a trunk period), or, for the
member whose moving-together phase t_end cuts, half-way through that phase.

:func:`family` returns each member with its :class:`Regime` as the exact solver found it,
and refuses (RuntimeError) a member whose regime is not the one it was built for: a change
of the model that moves a tree out of its regime fails here, not silently in the tests that
rely on it. Used by tests/test_family.py (small sizes) and benchmarks/bench_family.py.
"""

from __future__ import annotations

import dataclasses
import enum
import math
from functools import lru_cache
from pathlib import Path

from treeimpact.analytic.impact.events import Motion
from treeimpact.analytic.impact.solver import solve_impacts
from treeimpact.analytic.model.parameters import Billet, Contact, Scenario
from treeimpact.analytic.model.reduction import reduce_trunk
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.analytic.model.scenario_toml import scenario_toml
from treeimpact.analytic.model.two_body import two_body_model

#: A re-strike is an impact after a free flight of at least this fraction of the trunk's
#: undamped period 2 pi sqrt(M_T / K_T): the trunk swung away and came back. The impacts of
#: a chattering sequence (eqs 12-35) follow each other within a small fraction of it.
RESTRIKE_FRACTION = 0.25
#: The events a member's t_end must show are those up to the shipped trees' t_end, s.
HORIZON = 0.1


class Impactor(enum.Enum):
    """The impactor the paper names (abstract, eq 57)."""

    PENDULUM = "pendulum"
    BILLET = "billet"


@dataclasses.dataclass(frozen=True)
class Regime:
    """What the exact solution of a tree does up to its t_end.

    Attributes:
        n_impacts: Newton impacts (eqs 20-21), a chattering tail's counted as the solver does.
        together: the bodies move together at least once (eq 34).
        cut: the run ends while they move together (t_end falls inside that phase).
        restrike: an impact follows a free flight of at least :data:`RESTRIKE_FRACTION` of
            the trunk's period.
    """

    n_impacts: int
    together: bool
    cut: bool
    restrike: bool

    def label(self) -> str:
        """One line: e.g. '7 impacts, moving together, parted'."""
        parts = [f"{self.n_impacts} impact{'s' * (self.n_impacts != 1)}"]
        parts.append("moving together" if self.together else "never moving together")
        if self.together:
            parts.append("cut by t_end" if self.cut else "parted")
        if self.restrike:
            parts.append("re-strike")
        return ", ".join(parts)


@dataclasses.dataclass(frozen=True)
class Member:
    """One tree of the family: the physical choices and the regime it is built for.

    Attributes:
        name: the scenario's name.
        why: the regime or tree property it stands for (one line).
        mass_ratio: m/M_T, 1 (eq 7's M_T of this member's clamped trunk).
        a_over_l: clamp height over the crown's height, 1.
        crown_mass: m_f, kg (None: central-leader's).
        restitution: e, 1.
        impactor: pendulum or billet.
        billet_stiffness: k, N/m (a billet's spring; 0 free).
        cut: t_end half-way through the first moving-together phase.
        expect: the :class:`Regime` fields it must show (name -> value; n_impacts may be a
            (low, high) range, both included).
    """

    name: str
    why: str
    mass_ratio: float
    a_over_l: float = 0.315
    crown_mass: float | None = None
    restitution: float = 0.1
    impactor: Impactor = Impactor.PENDULUM
    billet_stiffness: float = 0.0
    cut: bool = False
    expect: tuple = ()


_MANY = (3, 10 ** 6)  # "many impacts": a chattering sequence of at least three
MEMBERS = (
    Member("bounce-off", "light pendulum (m/M_T 0.06): one impact and bounce-off", 0.06, 0.35,
           expect=(("n_impacts", (1, 1)), ("together", False))),
    Member("heavy-pendulum", "heavy pendulum (m/M_T 1.2): chattering, moving together", 1.2,
           expect=(("n_impacts", _MANY), ("together", True), ("cut", False))),
    Member("never-together", "bouncy pad (e 0.5): impacts without moving together", 0.8,
           restitution=0.5, expect=(("n_impacts", (2, 10 ** 6)), ("together", False))),
    Member("cut-by-t-end", "heavy pendulum, t_end inside the moving-together phase", 1.2,
           cut=True, expect=(("together", True), ("cut", True))),
    Member("re-strike", "light pendulum (m/M_T 0.1): the trunk swings back and strikes again",
           0.1, expect=(("together", False), ("restrike", True))),
    Member("heavy-crown", "a 40 kg crown (m/M_T 0.3)", 0.3, crown_mass=40.0,
           expect=(("n_impacts", (1, 10 ** 6)),)),
    Member("light-crown", "a 0.5 kg crown (m/M_T 1.2)", 1.2, crown_mass=0.5,
           expect=(("together", True),)),
    Member("low-clamp", "clamp at a/l 0.12 (m/M_T 0.15)", 0.15, a_over_l=0.12,
           expect=(("n_impacts", (1, 10 ** 6)),)),
    Member("high-clamp", "clamp at a/l 0.8 (m/M_T 1.2)", 1.2, a_over_l=0.8,
           expect=(("together", True),)),
    Member("free-billet", "a free billet (k = 0, m/M_T 0.36) at the pendulum's speed", 0.36,
           impactor=Impactor.BILLET, expect=(("n_impacts", (1, 10 ** 6)),)),
    Member("spring-billet", "a billet on a 2 kN/m spring (m/M_T 0.1)", 0.1,
           impactor=Impactor.BILLET, billet_stiffness=2000.0,
           expect=(("n_impacts", (1, 10 ** 6)),)),
)
BY_NAME = {m.name: m for m in MEMBERS}


def _solution(scenario: Scenario):
    return solve_impacts(two_body_model(scenario), scenario.t_end)


def regime(scenario: Scenario) -> Regime:
    """The :class:`Regime` of ``scenario`` from its exact solution (eqs 12-35) to t_end."""
    sol = _solution(scenario)
    model = sol.model
    period = 2.0 * math.pi * math.sqrt(model.dynamic_mass / model.equivalent_stiffness)
    times = [i.t for i in sol.impacts]
    gaps = [b - a for a, b in zip(times, times[1:])]
    return Regime(n_impacts=sol.n_impacts, together=bool(sol.together_starts),
                  cut=bool(sol.phases) and sol.phases[-1].kind is Motion.TOGETHER,
                  restrike=any(g >= RESTRIKE_FRACTION * period for g in gaps))


def _t_end(scenario: Scenario, cut: bool) -> float:
    """t_end from the exact solution up to :data:`HORIZON`:
    the last impact, separation or x_max plus half a trunk period; ``cut``: half-way
    between the first moving-together start and the separation ending it."""
    sol = _solution(dataclasses.replace(scenario, t_end=HORIZON))
    model = sol.model
    if cut:
        t0 = sol.together_starts[0][0]
        t1 = next(s.t for s in sol.separations if s.t > t0)
        return 0.5 * (t0 + t1)
    half = math.pi * math.sqrt(model.dynamic_mass / model.equivalent_stiffness)
    last = max([i.t for i in sol.impacts] + [s.t for s in sol.separations] + [sol.x_max[1]])
    return last + half


def build(member: Member) -> Scenario:
    """The member's scenario: central-leader's trunk clamped at a/l with its crown, the
    impactor of mass m/M_T * M_T (eq 7), e, and t_end from :func:`_t_end`."""
    base = load_scenario("central-leader")
    changes = {"clamp_height": member.a_over_l * base.trunk.length}
    if member.crown_mass is not None:
        changes["crown_mass"] = member.crown_mass
    trunk = dataclasses.replace(base.trunk, **changes)
    mass = member.mass_ratio * reduce_trunk(trunk).dynamic_mass
    pendulum = dataclasses.replace(base.impactor, mass=mass)
    if member.impactor is Impactor.BILLET:  # eq 48's speed of the same pendulum
        impactor = Billet(mass=mass, impact_speed=two_body_model(dataclasses.replace(
            base, impactor=pendulum)).impact_speed, stiffness=member.billet_stiffness)
    else:
        impactor = pendulum
    contact = Contact(restitution=member.restitution, duration=base.contact.duration)
    scen = Scenario(name=member.name, trunk=trunk, impactor=impactor, contact=contact,
                    description=f"family: {member.why}",
                    notes={"family": member.why})
    return dataclasses.replace(scen, t_end=_t_end(scen, member.cut))


def check(member: Member, found: Regime) -> None:
    """Raise RuntimeError when ``found`` is not the regime ``member`` was built for."""
    for name, want in member.expect:
        got = getattr(found, name)
        ok = want[0] <= got <= want[1] if isinstance(want, tuple) else got == want
        if not ok:
            raise RuntimeError(f"family tree {member.name!r}: {name} = {got!r}, built for "
                               f"{want!r} ({member.why}; found: {found.label()})")


@lru_cache(maxsize=None)
def family() -> tuple:
    """Every member as (Member, Scenario, Regime), each regime checked (:func:`check`)."""
    out = []
    for member in MEMBERS:
        scen = build(member)
        found = regime(scen)
        check(member, found)
        out.append((member, scen, found))
    return tuple(out)


def write_family(folder) -> dict:
    """Each member's scenario TOML in ``folder`` (created): name -> path."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = {}
    for member, scen, _ in family():
        path = folder / f"{member.name}.toml"
        path.write_text(scenario_toml(scen))
        paths[member.name] = path
    return paths
