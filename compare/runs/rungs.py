"""The discrepancy ladder's rungs: one table, read by the ladder (report, ``pytest compare``)
and by the sweeps. Each rung changes one assumption of the rung it is compared with.

Design notes: docs/ladder.md.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

from .backends import BACKENDS, ENGINE_REGISTRY, ENGINES

#: Sampling (s) of the exact solution for the figures and the identification: 20 us, the
#: record spacing at which analytic.identify.procedure's tests recover b and omega_n.
ANALYTIC_SAMPLE_STEP = 2e-5


def analytic_samples(t_end: float) -> int:
    """Samples of the analytic rungs' trajectory over [0, t_end] (s) at ANALYTIC_SAMPLE_STEP."""
    return int(round(t_end / ANALYTIC_SAMPLE_STEP)) + 1


class RungKind(StrEnum):
    """What a rung changes against the rung it is compared with (the strings tables show)."""

    NEWTON = "newton"
    CONTACT = "contact"
    BEAM = "beam"
    BEAM_THEORY = "beam_theory"
    CONVENTION = "convention"
    ENGINE = "engine"
    CHAIN = "chain"
    PENDULUM = "pendulum"
    ROD = "rod"  # the engine's own elastic trunk (MuJoCo's 1-D flex), where it has one
    MODEL = "model"  # a sweep's engine as configured, compared with the soft SDOF

    @property
    def level(self) -> int:
        """Place in the ladder (1 the paper's model); a sweep's MODEL target stands with the
        engine rungs."""
        return _KINDS[self][0]

    @property
    def assumption(self) -> str:
        """The one assumption this rung changes against its previous rung."""
        return _KINDS[self][1]

    @property
    def letter(self) -> str:
        """The letter a validity map marks the dominating step with."""
        return _KINDS[self][2]

    @property
    def step(self) -> str:
        """The step, in a few words, as the maps' legend names it."""
        return _KINDS[self][3]

    @property
    def engine_rung(self) -> bool:
        """An engine's own rung (run by each engine, compared across the engines)."""
        return self in ENGINE_KINDS


#: kind -> (level, assumption, map letter, map step)
_KINDS = {
    RungKind.NEWTON: (1, "the paper: analytic SDOF + Newton restitution (eqs 12-35)", "N",
                      "the paper's model"),
    RungKind.CONTACT: (2, "contact model: the spring-dashpot pad (k_c, c_c) with the same e",
                       "C", "contact model (spring-dashpot vs Newton's e)"),
    RungKind.BEAM: (3, "1-DOF assumption: continuum Euler-Bernoulli trunk, the same pad", "B",
                    "1-DOF assumption (continuum trunk vs SDOF, same pad)"),
    RungKind.BEAM_THEORY: (4, "beam theory: the continuum with shear and rotary inertia "
                              "(Timoshenko, the scenario's shear modulus), the same pad", "T",
                           "beam theory (Timoshenko vs Euler-Bernoulli continuum)"),
    RungKind.CONVENTION: (5, "restitution convention: c_c recalibrated so e holds on the "
                             "clamp's effective mass", "R",
                          "restitution convention (c_c for e on the clamp's mass)"),
    RungKind.ENGINE: (6, "engine numerics: engine SDOF (slide joint) + the pad", "E",
                      "engine numerics (engine SDOF vs analytic soft contact)"),
    RungKind.CHAIN: (7, "discretisation: the engine's hinged-segment trunk against the "
                        "continuum", "D", "discretisation (engine's hinged chain vs continuum)"),
    RungKind.ROD: (7, "discretisation: the engine's own elastic rod (MuJoCo flex) against the "
                      "continuum", "F", "discretisation (engine's own elastic rod vs continuum)"),
    RungKind.PENDULUM: (8, "pendulum linearisation: full pendulum released from theta_r", "P",
                        "pendulum linearisation (full vs linear pendulum)"),
    RungKind.MODEL: (6, "engine as configured against the soft SDOF (numerics, trunk and "
                        "pendulum together)", "M",
                     "engine as configured vs analytic soft contact (numerics, trunk and "
                     "pendulum together; run a ladder sweep to separate them)"),
}
#: The kinds each engine runs (the ladder compares the engines with each other on these).
ENGINE_KINDS = (RungKind.ENGINE, RungKind.CHAIN, RungKind.PENDULUM)
#: The ``trunk`` option value of an engine's own elastic rod: an engine whose ``trunk``
#: option offers it (its OPTIONS in the backend registry) runs the ROD rung as well.
ROD_TRUNK = "flex"


def offers_rod(engine: str) -> bool:
    """Whether ``engine``'s ``trunk`` option offers :data:`ROD_TRUNK`, read from the backend
    registry's options table (no engine is imported); False for a backend not registered
    or whose options cannot be read here."""
    backend = BACKENDS.get(engine)
    return backend is not None and backend.offers("trunk", ROD_TRUNK)


@dataclass(frozen=True)
class Rung:
    """One rung: which backend with which options, and the rung it is compared with."""

    id: str
    kind: RungKind
    backend: str
    options: tuple  # sorted (name, value) pairs passed to the backend
    previous: str | None
    drop: tuple = ()  # swept options the rung ignores (segments for an SDOF trunk)

    @property
    def level(self) -> int:
        """The rung kind's level (:attr:`RungKind.level`)."""
        return self.kind.level

    @property
    def assumption(self) -> str:
        """The one assumption this rung changes (:attr:`RungKind.assumption`)."""
        return self.kind.assumption

    @property
    def engine(self) -> str | None:
        """The engine backend this rung runs, or None (an analytic rung)."""
        return self.backend if self.backend in ENGINE_REGISTRY else None


def rung_table(engines=ENGINES, *, segments: int | None = None,
               analytic_options: tuple = ()) -> list[Rung]:
    """The rungs in ladder order. ``segments``: the engines' chain and rod (in their rung
    ids and options; None leaves it to the backend or a sweep axis); ``analytic_options``:
    the paper's model's (name, value) pairs (the ladder's record sampling); ``engines``: the
    engine backends, in order. An engine whose
    ``trunk`` option offers its own elastic rod (:func:`offers_rod`) adds the ROD rung, the
    rod with the linear pendulum and the same segments against the continuum (``beam``)."""
    chain_opts = (("segments", segments),) if segments is not None else ()
    suffix = "" if segments is None else str(segments)
    rungs = [Rung("analytic", RungKind.NEWTON, "analytic", tuple(analytic_options), None),
             Rung("soft", RungKind.CONTACT, "soft", (), "analytic"),
             Rung("beam", RungKind.BEAM, "beam", (), "soft"),
             Rung("beam-timoshenko", RungKind.BEAM_THEORY, "beam",
                  (("beam_theory", "timoshenko"),), "beam"),
             Rung("beam-effective", RungKind.CONVENTION, "beam",
                  (("calibration", "effective"),), "beam")]
    for eng in engines:
        sdof, chain = f"{eng}-sdof", f"{eng}-chain{suffix}"
        rungs += [
            Rung(sdof, RungKind.ENGINE, eng, (("pendulum", "linear"), ("trunk", "sdof")),
                 "soft", drop=("segments",)),
            Rung(chain, RungKind.CHAIN, eng,
                 tuple(sorted((("pendulum", "linear"), ("trunk", "chain"), *chain_opts))),
                 "beam"),
            Rung(f"{chain}-full", RungKind.PENDULUM, eng,
                 tuple(sorted((("pendulum", "full"), ("trunk", "chain"), *chain_opts))), chain),
        ]
        if offers_rod(eng):
            rungs.append(Rung(f"{eng}-{ROD_TRUNK}{suffix}", RungKind.ROD, eng,
                              tuple(sorted((("pendulum", "linear"), ("trunk", ROD_TRUNK),
                                            *chain_opts))), "beam"))
    return rungs
