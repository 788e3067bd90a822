"""The record fit's conclusion: whether the 1-DOF model explains the record (and with what
qualifications), or why not, from its diagnoses (docs/identification.md, "Diagnoses")."""

from __future__ import annotations

from dataclasses import dataclass

from .diagnosis import QUALIFYING, REFUSING, Diagnosis, DiagnosisKind


@dataclass(frozen=True)
class Conclusion:
    """What the record fit concludes; ``str()`` is the one line identify prints.

    Attributes:
        explained: True when the values are the tree's (the 1-DOF model explains the record
            to its noise), bool.
        reason: when not explained, the first refusing kind (:data:`diagnosis.REFUSING`),
            a ``DiagnosisKind``; None when explained.
        qualifiers: the kinds an explained record is explained with (drift, outliers,
            one-impact), a tuple of ``DiagnosisKind``.
        fitted: False when the record was not fitted at all (numbers that look like another
            unit, or no impact in it: the tree's free vibration), bool.
    """

    explained: bool
    reason: DiagnosisKind | None = None
    qualifiers: tuple = ()
    fitted: bool = True

    def __str__(self) -> str:
        if self.explained:
            extra = ", ".join(k.value for k in self.qualifiers)
            return "explained" + (f" ({extra})" if extra else "")
        if not self.fitted and self.reason is DiagnosisKind.FREE_VIBRATION:
            return "no impact in this record (free-vibration): not fitted"
        if not self.fitted:
            return f"NOT explained ({self.reason.value}): not fitted; declare the units"
        if self.reason is None:  # pragma: no cover - a refusing kind is always there
            return "NOT explained"
        return (f"NOT explained ({self.reason.value}): the values are the best 1-DOF fit, "
                f"not the tree's")


Conclusion.NONE = Conclusion(False)  # no conclusion reached (a default)


def conclude(explained: bool, diagnoses) -> Conclusion:
    """The conclusion of a fit that is ``explained`` (or not) with these diagnoses."""
    kinds = [d.kind for d in diagnoses]
    if explained:
        return Conclusion(True, qualifiers=tuple(k for k in kinds if k in QUALIFYING))
    return Conclusion(False, reason=next((k for k in REFUSING if k in kinds), None))


def not_fitted(diagnosis: Diagnosis) -> Conclusion:
    """The conclusion of a record not fitted (its numbers look like another unit, or it holds
    no impact), for the reason its ``diagnosis`` gives."""
    return Conclusion(False, reason=diagnosis.kind, fitted=False)
