"""The paper's identification procedure run on a rung's record: one typed result, read by
the ladder, the sweeps and the report.

Design notes: docs/identification.md.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from treeimpact.analytic.errors import ParameterError, one_line
from treeimpact.analytic.identify.procedure import (
    identification_errors,
    identify_from_record,
    pendulum_test_of,
    truth_of,
)
from treeimpact.analytic.model.parameters import Pendulum, Scenario
from treeimpact.analytic.model.registry import units_of

from ..runs.cache import OK, SKIPPED, Status

#: Parameters recovered by the identification procedure, compared with the model's truth,
#: by their names in analytic.identify.procedure (Identified, truth_of), the ladder
#: (``id_`` + name), the sweeps (``id.`` and ``truth.`` + name) and the report:
#: ``pair_damping_ratio`` is the paper's xi = b / omega_n of trunk and pendulum moving
#: together (eqs 42-43), not the trunk's own damping ratio.
IDENT_METRICS = ("M_T", "K_T", "pair_damping_ratio", "E")
_UNIT = units_of("M_T", "K_T", "E")  # the registry's units of the true values
IDENT_UNITS = {"M_T": (_UNIT["M_T"], "identified dynamic mass (eq 44)"),
               "K_T": (_UNIT["K_T"], "identified stiffness (eq 46)"),
               "pair_damping_ratio": ("1", "pair damping ratio xi = b / omega_n = C_T / (2 sqrt((K_T + k)(M_T + m))): "
                      "trunk and pendulum moving together (eqs 42-43)"),
               "E": (_UNIT["E"], "identified Young's modulus (eq 47)")}


@dataclass(frozen=True)
class RungIdentification:
    """The procedure's outcome on one record: ``status`` OK with the identified ``values``
    (IDENT_METRICS, SI), their relative ``errors`` against the scenario's ``truth`` and the
    ``regression`` of Figs 4-5 (s, m, m/s, m/s^2); else SKIPPED and the ``reason`` (a
    record the premises do not hold on says "not identifiable: ...")."""

    status: Status
    reason: str | None = None
    values: dict = field(default_factory=dict)
    errors: dict = field(default_factory=dict)
    truth: dict = field(default_factory=dict)
    regression: dict | None = None
    identified: dict | None = None  # every quantity of the procedure (Identified.as_dict)

    @property
    def ok(self) -> bool:
        """Whether the procedure ran (status OK)."""
        return self.status == OK

    def to_json(self) -> dict:
        """status, reason, values, errors, truth and regression, as a dict."""
        return {"status": self.status, "reason": self.reason, "values": self.values,
                "errors": self.errors, "truth": self.truth, "regression": self.regression}


def rung_truth(scenario: Scenario) -> dict:
    """What the procedure should find on a rung's record of ``scenario``: :func:`truth_of`
    (SI; :data:`IDENT_METRICS` among its keys)."""
    return truth_of(scenario)


def identify_rung(result, scenario: Scenario) -> RungIdentification:
    """The paper's procedure run on a rung's displacement record (its ``result``, a run of
    ``scenario``; eqs 39-48, "paper" reading, A_y from the pendulum record)."""
    if not isinstance(scenario.impactor, Pendulum):
        return RungIdentification(SKIPPED, "the identification procedure needs a pendulum")
    truth = rung_truth(scenario)
    shown = {k: truth[k] for k in IDENT_METRICS}
    src = result.trajectory if result.trajectory is not None else result.record
    if src is None:
        return RungIdentification(SKIPPED, "the run has no displacement record", truth=shown)
    try:
        ident, reg = identify_from_record(src.t, src.x, pendulum_test_of(scenario), y=src.y,
                                          reading="paper")
    except (ParameterError, ValueError, FloatingPointError) as exc:
        text = one_line(exc)  # "not identifiable: ..." when the premises fail
        return RungIdentification(SKIPPED, text if text.startswith("not identifiable")
                                  else f"identification failed: {text}", truth=shown)
    errors = identification_errors(ident, truth_of(scenario))
    identified = ident.as_dict()  # by the symbols IDENT_METRICS names
    return RungIdentification(
        OK, values={k: identified[k] for k in IDENT_METRICS},
        errors={k: errors[k] for k in IDENT_METRICS}, truth=shown,
        regression={"t_first": reg.t_first, "t_together": reg.t_together,
                    "x_together": reg.x_together, "t_origin": reg.t_origin,
                    "coefficients": list(reg.coefficients), "x_max": reg.x_max,
                    "tau": reg.tau},
        identified=identified)


def rung_identification(run, scenario: Scenario) -> RungIdentification:
    """:func:`identify_rung` of a finished ``run`` of ``scenario``, computed once and kept
    with the run."""
    if run.identification is None:
        run.identification = identify_rung(run.result, scenario)
    return run.identification
