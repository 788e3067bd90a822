"""Report section: the paper reproduced (Table 1 printed vs recomputed, the discrepancies)."""

from __future__ import annotations

from treeimpact.analytic.results import to_jsonable
from treeimpact.analytic.model.registry import units_of

from .base import Section

UNITS = {"u1": "m/s", "V": "m/s", "x0": "m", "T0": "s", "A_x": "m s", **units_of("M_T"),
         **units_of("K_T", "E"), "b": "1/s", "omega_n": "rad/s", "xi": "1",
         "energy_loss_pct": "%"}


class PaperSection(Section):
    """The paper reproduced: Table 1 printed against recomputed, the restitutions that
    reproduce V, x0 and T0, and the discrepancies (the reproduction,
    :func:`analytic.paper.reproduction.reproduce`, runs when the section is made)."""

    template = "paper"
    title = "The paper reproduced"
    anchor = "paper"

    def __init__(self):
        # lazy: +360 ms at import otherwise (scipy, numpy),
        # which this module's other callers do not need
        from treeimpact.analytic.paper.reproduction import reproduce

        self.data = reproduce()

    def context(self) -> dict:
        """The template's names: each tree's rows with their units, the e estimates and the
        discrepancies."""
        trees = []
        for name, rows in self.data["trees"].items():
            trees.append({"name": name, "rows": [
                {"quantity": q, "unit": UNITS.get(q, ""), **row} for q, row in rows.items()]})
        return {"trees": trees, "estimates": self.data.get("restitution_estimates", {}),
                "discrepancies": self.data["discrepancies"]}

    def to_json(self) -> dict:
        """The reproduction and the quantities' units."""
        return to_jsonable({**self.data, "units": UNITS})
