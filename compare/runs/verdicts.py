"""Judging the ladder: the tolerance file (compare/runs/tolerances.toml, every entry with its
reason), the verdict of one comparison, and what each verdict means.

Design notes: docs/ladder.md.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from enum import StrEnum
from functools import lru_cache
from pathlib import Path

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.metrics import FORCE, PARTED, TOGETHER, metrics_needing
from treeimpact.analytic.results import finite_number, to_jsonable

from .bounds import validate_bound
from .bounds.base import relative_step  # noqa: F401 (compare.runs.verdicts.relative_step)
from .bounds.continuum import BANDS
from .findings import (
    REFUSAL_QUANTITIES,
    TreePhysics,
    cause_text,
    finding_band,
    finding_for,
    validate_cause,
    validate_when,
)

TOLERANCES_PATH = Path(__file__).with_name("tolerances.toml")


class Verdict(StrEnum):
    """What a comparison of a value with its reference found (the strings tables show)."""

    OK = "ok"  # within its tolerance
    EXCEEDS = "exceeds"  # beyond its tolerance
    REPORTED = "reported"  # shown without a tolerance (report_only in the file)
    FINDING = "finding"  # a documented finding, inside its band
    OUT_OF_BAND = "out-of-band"  # a documented finding, outside its band
    FINDING_LOST = "finding-lost"  # a documented finding that is now within tolerance
    AMBIGUOUS = "ambiguous"  # a peak time of two near-equal maxima: not a robust quantity
    NOT_AVAILABLE = "n/a"  # a value does not exist (a rung without it, a NaN)
    SKIPPED = "skipped"  # the quantity does not exist for this tree's motion (WHY_NONE)

    @property
    def flagged(self) -> bool:
        """A failed check: the report flags it (exceeds, out-of-band, finding-lost)."""
        return self in (Verdict.EXCEEDS, Verdict.OUT_OF_BAND, Verdict.FINDING_LOST)

    @property
    def passes(self) -> bool:
        """A cross-check in ``pytest compare`` passes on it: judged and held (ok, finding) or
        documented as not judged (ambiguous); reported and n/a are no pass there."""
        return self in (Verdict.OK, Verdict.FINDING, Verdict.AMBIGUOUS)


# --------------------------------------------------------------------------- tolerances


@lru_cache(maxsize=4)
def _load(path: str) -> dict:
    with open(path, "rb") as fh:
        data = tomllib.load(fh)
    _validate(data, path)
    return data


def load_tolerances(path: str | Path | None = None) -> dict:
    """The tolerance file at ``path`` (default ``compare/runs/tolerances.toml``), validated: every
    entry has a reason."""
    return _load(str(TOLERANCES_PATH if path is None else path))


def validity_tolerance() -> float:
    """The studies' criterion (relative, 5 %: tolerances.toml [study] validity): the maps'
    contour, the contact scan's headline and the report's answer table."""
    return float(load_tolerances()["study"]["validity"]["rel"])


def _validate(data: dict, path: str) -> None:
    def need_reason(where, entry):
        if not isinstance(entry, dict) or not str(entry.get("reason", "")).strip():
            raise ParameterError(f"{path}: {where}: every tolerance needs a one-line reason")
        if "rel" in entry and not (isinstance(entry["rel"], (int, float)) and entry["rel"] >= 0):
            raise ParameterError(f"{path}: {where}.rel: allowed [0, inf)")
        validate_bound(f"{path}: {where}", entry)
        if "measured" in entry and not str(entry["measured"]).strip():
            raise ParameterError(f"{path}: {where}.measured: the shipped trees' measurements "
                                 "in words, or no key")
        if "rel" not in entry and "bound" not in entry and not entry.get("report_only") \
                and not entry.get("undefined") \
                and where != "identification_reported" \
                and not where.startswith("identification_refused"):
            raise ParameterError(f"{path}: {where}: give rel, bound or report_only = true "
                                 "(or undefined = true: no check)")

    for section in ("step", "engines"):
        for kind, metrics in data.get(section, {}).items():
            for metric, entry in metrics.items():
                need_reason(f"{section}.{kind}.{metric}", entry)
    for metric, entry in data.get("identification", {}).items():
        need_reason(f"identification.{metric}", entry)
    need_reason("identification_reported", data.get("identification_reported"))
    for name, entry in data.get("identification_refused", {}).items():
        need_reason(f"identification_refused.{name}", entry)
        if not str(entry.get("match", "")).startswith("not identifiable"):
            raise ParameterError(f"{path}: identification_refused.{name}.match: the "
                                 "refusal's words, starting 'not identifiable'")
        validate_when(f"{path}: identification_refused.{name}", entry.get("when", {}),
                      REFUSAL_QUANTITIES)
    for name, entry in data.get("study", {}).items():
        need_reason(f"study.{name}", entry)
    for kind, entry in data.get("ledger", {}).items():
        need_reason(f"ledger.{kind}", entry)
    for i, f in enumerate(data.get("finding", [])):
        for key in ("name", "metric", "cause", "reason", "kinds", "when"):
            if key not in f:
                raise ParameterError(f"{path}: finding[{i}].{key}: missing")
        _validate_band(f"{path}: finding[{i}]", f)
        if "scenario" in f:
            raise ParameterError(f"{path}: finding[{i}].scenario: a finding is recognised "
                                 "from its physical cause (when), never from a tree's name")
        validate_when(f"{path}: finding[{i}]", f["when"])
        validate_cause(f"{path}: finding[{i}]", f)


def _validate_band(where: str, f: dict) -> None:
    """A finding gives a fixed ``band`` [lo, hi] (lo < hi) or a registered ``band_bound``
    (a ``mesh`` band with its ``mesh_rel`` >= 0 and the reason for it), not both."""
    if ("band" in f) == ("band_bound" in f):
        raise ParameterError(f"{where}: give band or band_bound (one)")
    if "band" in f:
        lo, hi = f["band"]
        if not lo < hi:
            raise ParameterError(f"{where}.band: need lo < hi")
        return
    if f["band_bound"] not in BANDS:
        raise ParameterError(f"{where}.band_bound = {f['band_bound']!r}: allowed "
                             f"{', '.join(sorted(BANDS))}")
    if f["band_bound"] == "mesh" and not (isinstance(f.get("mesh_rel"), (int, float))
                                          and f["mesh_rel"] >= 0
                                          and str(f.get("mesh_reason", "")).strip()):
        raise ParameterError(f"{where}: a mesh band needs mesh_rel >= 0 and mesh_reason")


# --------------------------------------------------------------------------- checks


@dataclass(frozen=True)
class Check:
    """One comparison of the ladder: a rung's value against a reference, with its verdict."""

    scenario: str
    rung: str
    metric: str
    value: float
    reference: str  # the reference rung id, or "truth"
    reference_value: float
    rel_diff: float  # (value - reference) / |reference|
    tolerance: float | None  # relative, None when only reported
    verdict: Verdict
    reason: str
    finding: str | None = None
    band: tuple | None = None

    def to_json(self) -> dict:
        """Every field, JSON-safe (the band as a list)."""
        return to_jsonable(self.__dict__ | {"band": list(self.band) if self.band else None})


#: Why a metric has no value on a run, from the tree's physics: the moving-together
#: metrics (eq 34, eq 45, eq 58) when the impactor parts before the trunk catches up with it,
#: the whole-event energies and impulse when the bodies have not parted for good by t_end,
#: the contact history on the Newton model's impulsive impacts.
MOVING_TOGETHER = metrics_needing(TOGETHER)  # analytic.metrics.METRICS
WHY_NONE = {
    **dict.fromkeys(MOVING_TOGETHER,
                    "the bodies never move together on this tree (the impactor parts before "
                    "the trunk catches up: no impact process of eqs 12-35 whose T0, x0, V, "
                    "t_sep or eq 58's rebound after it could be compared)"),
    "theta_b": ("eq 58's rebound angle is a pendulum's after it parts from the trunk's "
                "moving-together phase: a billet has no angle, and a pendulum that never "
                "moves together with the trunk has no such phase"),
    **dict.fromkeys(metrics_needing(PARTED),
                    "the bodies have not parted for good by t_end on this tree (the energies "
                    "and the impulse are read after the last separation)"),
    **dict.fromkeys(metrics_needing(FORCE),
                    "Newton impacts are instantaneous (eqs 20-21): no contact force history"),
}


#: Why an identified value (``id_*``) has no value on either record of a comparison.
WHY_NO_IDENTIFICATION = ("the paper's procedure (eqs 39-48) refused both records: it reads a "
                         "pendulum's moving-together phase before x_max, which this tree's "
                         "motion or impactor does not give")


def absent_reason(metric: str, value, reference_value, rung: str, reference: str) -> str | None:
    """Why a comparison has no pair of numbers, from the tree's physics (:data:`WHY_NONE`).

    Args:
        metric: the metric compared.
        value: the rung's value (SI; NaN or None when it has none).
        reference_value: the reference's value (SI; NaN or None when it has none).
        rung: the rung checked.
        reference: what it is compared with (a rung id, "truth").

    Returns:
        The reason, or None when both values exist or the absence is not explained: a value
        on neither side; or a moving-together metric on one side only (one model's bodies
        move together, the other's never do or do not part by t_end: different regimes).
    """
    has = (finite_number(value), finite_number(reference_value))
    if all(has):
        return None
    if not any(has):
        why = WHY_NONE.get(metric, WHY_NO_IDENTIFICATION if metric.startswith("id_") else
                           "neither run reports it")
        return f"{metric} has no value on {rung} nor on {reference}: {why}"
    if metric not in MOVING_TOGETHER or reference == "truth":
        return None
    on, off = (rung, reference) if has[0] else (reference, rung)
    return (f"{metric} has a value on {on} but none on {off}: on {off} the bodies never move "
            f"together or do not part by t_end, on {on} they do: the two models are in "
            f"different regimes, no pair of numbers to compare")


def judge(scenario: str, rung: str, kind: str, metric: str, value, reference: str,
          reference_value, entry: dict | None, tol: dict,
          physics: TreePhysics | None = None, pair=None) -> Check:
    """The verdict of one comparison of ``value`` with ``reference_value`` (:class:`Verdict`).

    Args:
        scenario: the scenario's name.
        rung: the rung checked.
        kind: the comparison's kind (a rung kind, ``engines-KIND``), where findings apply.
        metric: the metric compared.
        value: the rung's value (SI).
        reference: what it is compared with (a rung id, "truth").
        reference_value: its value (SI).
        entry: the tolerance file's entry (rel, reason; report_only), or None.
        tol: the whole tolerance file (its recorded findings).
        physics: the tree's physical quantities, which decide the findings whose cause
            it shows (:func:`compare.runs.findings.finding_for`); None: no finding applies.
        pair: the comparison's :class:`compare.runs.bounds.Pair` (the tree and its two runs), on
            which a finding's ``band_bound`` is evaluated; None: such a finding is only
            reported.

    Returns:
        The :class:`Check`: the relative difference, the tolerance, the verdict and the
        reason (a recorded finding's band and its cause in this tree's quantities where one
        applies, :func:`compare.runs.findings.cause_text`).
    """
    rel = relative_step(value, reference_value)
    finding = finding_for(tol, physics, kind, metric, rung)
    tolerance = None if entry is None or entry.get("report_only") else float(entry["rel"])
    why = absent_reason(metric, value, reference_value, rung, reference)
    if why is not None:  # the quantity does not exist for the tree: no verdict column n/a
        return Check(scenario, rung, metric, _f(value), reference, _f(reference_value), rel,
                     tolerance, Verdict.SKIPPED, why)
    reason = entry["reason"] if entry else "no tolerance entry"
    if finding is not None:
        band, words = finding_band(finding, pair)
        reason = cause_text(finding, physics)  # this tree's numbers only
        reason = f"{reason}; {words}" if words else reason
        if not math.isfinite(rel):
            verdict = Verdict.NOT_AVAILABLE
        elif band is None:
            verdict = Verdict.REPORTED
        elif tolerance is not None and abs(rel) <= tolerance:
            verdict = Verdict.FINDING_LOST
        elif band[0] <= rel <= band[1]:
            verdict = Verdict.FINDING
        else:
            verdict = Verdict.OUT_OF_BAND
        return Check(scenario, rung, metric, _f(value), reference, _f(reference_value), rel,
                     tolerance, verdict, reason, finding["name"], band)
    if not math.isfinite(rel):
        verdict = Verdict.NOT_AVAILABLE
    elif tolerance is None:
        verdict = Verdict.REPORTED
    else:
        verdict = Verdict.OK if abs(rel) <= tolerance else Verdict.EXCEEDS
    return Check(scenario, rung, metric, _f(value), reference, _f(reference_value), rel,
                 tolerance, verdict, reason)


def _f(v) -> float:
    return float(v) if finite_number(v) else math.nan
