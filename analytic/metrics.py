"""Every output metric, declared once (:data:`METRICS`): its key, SI unit, glossary label,
meaning, the paper's equation, whether the ladder compares it and what a run needs for it to
have a value. The metric lists, the units' table, the ladder's metrics, the tolerances' and
glossary's checks and the API's ``Metrics`` read the declaration (docs/whole-event-metrics.md).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

#: What a run must have for a metric to have a value (:attr:`Metric.needs`; NaN without it):
#: the bodies moving together (eq 34), the bodies parted for good by t_end (the whole-event
#: energies and impulse are read after the last separation), or a contact-force history
#: (none under Newton's instantaneous impacts, eqs 20-21: the analytic rung's are NaN).
class Needs(enum.Enum):
    """What a run must have for a metric to have a value (:attr:`Metric.needs`)."""

    TOGETHER = "moving together"
    PARTED = "parted"
    FORCE = "contact force"


TOGETHER, PARTED, FORCE = Needs.TOGETHER, Needs.PARTED, Needs.FORCE


@dataclass(frozen=True)
class Metric:
    """One output metric, declared once in :data:`METRICS`; the metric lists, the units'
    table, the ladder's metrics and the checks of the API, tolerances and glossary read it.

    Attributes:
        name: its key in every backend's ``metrics`` dict, the JSON and ``treeimpact.Metrics``.
        unit: its SI unit ("1": a ratio or a count).
        label: its glossary term (docs/glossary.md), the words a table or tooltip names it by.
        meaning: what it is, in one line (the command line's and the ladder table's words).
        equation: the paper's equation or table it is ("eq 56", "Table 1"); "" for none.
        ladder: whether the ladder compares it between rungs (then every [step.*] and
            [engines.*] section of compare/runs/tolerances.toml has its entry).
        count: whether it is a whole number (a count of impacts or contacts).
        needs: what a run must have for it to have a value (:class:`Needs`), None for
            nothing.
    """

    name: str
    unit: str
    label: str
    meaning: str
    equation: str = ""
    ladder: bool = True
    count: bool = False
    needs: Needs | None = None


#: Every output metric, in the order of every backend's ``metrics`` dict (paper's symbols).
METRICS = (
    Metric("n_impacts", "1", "impacts resolved", "impacts resolved before the bodies move "
           "together (eqs 20-21)", "eqs 20-21", ladder=False, count=True),
    Metric("T0", "s", "T0", "duration of the impact process: first impact to moving together "
           "(Table 1)", "Table 1", needs=TOGETHER),
    Metric("x0", "m", "x0", "trunk displacement when the bodies begin to move together "
           "(Table 1)", "Table 1", needs=TOGETHER),
    Metric("V", "m/s", "V", "common velocity when the bodies begin to move together (eq 34)",
           "eq 34", needs=TOGETHER),
    Metric("x_max", "m", "x_max", "largest displacement of the impact point (eq 37-38)",
           "eqs 37-38"),
    Metric("t_xmax", "s", "t_xmax", "time of x_max after the first impact"),
    Metric("t_sep", "s", "t_sep", "time at which the bodies separate after moving together",
           needs=TOGETHER),
    Metric("A_x", "m s", "A_x", "area under x(t) over the impact process (eq 44)", "eq 44",
           ladder=False, needs=TOGETHER),
    Metric("A_y", "m s", "A_y", "area under y(t) over the impact process (eq 44)", "eq 44",
           ladder=False, needs=TOGETHER),
    Metric("impact_loss", "J", "impact loss", "mechanical energy lost in the impacts, eq 56",
           "eq 56"),
    Metric("impact_loss_inelastic", "J", "inelastic impact loss", "e = 0 approximation of the "
           "impact loss, eq 57", "eq 57", ladder=False),
    Metric("energy_transferred", "J", "energy transferred", "energy transferred to the tree, "
           "eq 58 with the loss of eq 56", "eq 58 with eq 56's loss", needs=TOGETHER),
    Metric("theta_b", "rad", "rebound angle", "rebound angle of the pendulum (eq 58); NaN for "
           "a billet", "eq 58", needs=TOGETHER),
    Metric("ledger_residual", "1", "ledger residual", "largest |energy ledger error| / initial "
           "energy over all events", ladder=False),
    # whole-event metrics: every contact, robust to chattering (no moving-together point)
    Metric("energy_delivered", "J", "energy delivered", "work of the contact force on the "
           "trunk over all contacts", needs=PARTED),
    Metric("contact_dissipation", "J", "contact dissipation", "energy lost in the contact "
           "over all contacts (eq 56 summed)", "eq 56 summed", needs=PARTED),
    Metric("rebound_energy", "J", "rebound energy", "pendulum's energy after its last "
           "separation", needs=PARTED),
    Metric("impulse", "N s", "impulse", "total impulse of the contact force", needs=PARTED),
    Metric("peak_force", "N", "peak force", "largest contact force averaged over one "
           "collision duration t_c (NaN for Newton impulses)", needs=FORCE),
    Metric("contact_episodes", "1", "contact episodes", "separate contacts (Newton: impacts + "
           "moving-together phases)", count=True),
    Metric("first_contact_duration", "s", "first contact", "the first contact, first touch "
           "to release: what the pad does against the clamp (NaN for Newton impulses)",
           ladder=False, needs=FORCE),
    Metric("crown_peak", "m", "crown peak", "largest |displacement| of the crown (top mass) "
           "at l"),
    Metric("crown_peak_acceleration", "m/s^2", "crown acceleration", "largest |acceleration| "
           "of the crown averaged over t_c (NaN for Newton impulses)", needs=FORCE),
)
#: Metric keys, in the backends' order.
METRIC_KEYS = tuple(m.name for m in METRICS)
#: Metric key -> (unit, meaning).
METRIC_UNITS = {m.name: (m.unit, m.meaning) for m in METRICS}
#: The metrics the ladder compares between rungs (compare.tree.ladder re-exports it).
LADDER_METRICS = tuple(m.name for m in METRICS if m.ladder)


def metrics_needing(needs: Needs) -> tuple[str, ...]:
    """The keys of the metrics whose value ``needs`` (:attr:`Metric.needs`) of a run."""
    return tuple(m.name for m in METRICS if m.needs is needs)
