"""The discrepancy ladder's rungs: one table, read by the ladder (report, ``pytest compare``)
and by the sweeps. Each rung changes one assumption of the rung it is compared with.

Design notes: docs/ladder.md.
"""

from __future__ import annotations

from dataclasses import dataclass

from .backends import ENGINES

#: Sampling (s) of the exact solution for the figures and the identification: 20 us, the
#: record spacing at which analytic.identify.procedure's tests recover b and omega_n.
ANALYTIC_SAMPLE_STEP = 2e-5


def analytic_samples(t_end: float) -> int:
    """Samples of the analytic rungs' trajectory over [0, t_end] (s) at ANALYTIC_SAMPLE_STEP."""
    return int(round(t_end / ANALYTIC_SAMPLE_STEP)) + 1


#: Rung kinds: (level, the one assumption the rung changes against its previous rung).
KINDS = {
    "newton": (1, "the paper: analytic SDOF + Newton restitution (eqs 12-35)"),
    "contact": (2, "contact model: the spring-dashpot pad (k_c, c_c) with the same e"),
    "beam": (3, "1-DOF assumption: continuum Euler-Bernoulli trunk, the same pad"),
    "convention": (4, "restitution convention: c_c recalibrated so e holds on the clamp's "
                      "effective mass"),
    "engine": (5, "engine numerics: engine SDOF (slide joint) + the pad"),
    "chain": (6, "discretisation: the engine's hinged-segment trunk against the continuum"),
    "pendulum": (7, "pendulum linearisation: full pendulum released from theta_r"),
}


@dataclass(frozen=True)
class Rung:
    """One rung: which backend with which options, and the rung it is compared with."""

    id: str
    kind: str
    backend: str
    options: tuple  # sorted (name, value) pairs passed to the backend
    previous: str | None
    drop: tuple = ()  # swept options the rung ignores (segments for an SDOF trunk)

    @property
    def level(self) -> int:
        return KINDS[self.kind][0]

    @property
    def assumption(self) -> str:
        return KINDS[self.kind][1]

    @property
    def engine(self) -> str | None:
        return self.backend if self.backend in ENGINES else None


def rung_table(engines=ENGINES, *, segments: int | None = None,
               analytic_options: tuple = ()) -> list[Rung]:
    """The rungs in ladder order. ``segments``: the engines' chain (in its rung id and
    options; None leaves it to the backend or a sweep axis)."""
    chain_opts = (("segments", segments),) if segments is not None else ()
    suffix = "" if segments is None else str(segments)
    rungs = [Rung("analytic", "newton", "analytic", tuple(analytic_options), None),
             Rung("soft", "contact", "soft", (), "analytic"),
             Rung("beam", "beam", "beam", (), "soft"),
             Rung("beam-effective", "convention", "beam", (("calibration", "effective"),),
                  "beam")]
    for eng in engines:
        sdof, chain = f"{eng}-sdof", f"{eng}-chain{suffix}"
        rungs += [
            Rung(sdof, "engine", eng, (("pendulum", "linear"), ("trunk", "sdof")), "soft",
                 drop=("segments",)),
            Rung(chain, "chain", eng, tuple(sorted((("pendulum", "linear"), ("trunk", "chain"),
                                                    *chain_opts))), "beam"),
            Rung(f"{chain}-full", "pendulum", eng,
                 tuple(sorted((("pendulum", "full"), ("trunk", "chain"), *chain_opts))), chain),
        ]
    return rungs
