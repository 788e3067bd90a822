"""A pendulum-test record as a user brings it: time, the trunk's displacement at the clamp
and optionally the pendulum's (SI), checked on reading (one-line errors naming the row)."""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from treeimpact.analytic.errors import ParameterError

MIN_SAMPLES = 20


@dataclass(frozen=True)
class Record:
    """A displacement record (SI): time t (s), trunk displacement at the clamp x (m), and the
    pendulum's displacement y (m) if measured, in the trunk's frame (y = x in contact)."""

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray | None = None

    def __post_init__(self):
        t, x = np.asarray(self.t, float), np.asarray(self.x, float)
        if t.ndim != 1 or t.shape != x.shape:
            raise ParameterError("record: t and x must be columns of the same length")
        if t.size < MIN_SAMPLES:
            raise ParameterError(f"record: {t.size} samples; at least {MIN_SAMPLES} needed")
        for name, v in (("t", t), ("x", x)) + ((("y", np.asarray(self.y, float)),)
                                               if self.y is not None else ()):
            bad = np.flatnonzero(~np.isfinite(v))
            if bad.size:
                raise ParameterError(f"record: {name} is not a finite number at row {bad[0] + 2}")
        steps = np.diff(t)
        if np.any(steps <= 0):
            row = int(np.flatnonzero(steps <= 0)[0]) + 3
            raise ParameterError(f"record: time t does not increase at row {row} (sorted, "
                                 "without repeats, is required)")
        if not np.max(x) - np.min(x) > 0:
            raise ParameterError("record: x never changes: the record holds no impact")


def read_record(path) -> Record:
    """A :class:`Record` from a CSV file with the header ``t,x`` or ``t,x,y`` (SI units)."""
    path = Path(path)
    try:
        with path.open(newline="", encoding="utf-8") as f:
            rows = list(csv.reader(f))
    except (OSError, UnicodeDecodeError) as exc:
        raise ParameterError(f"record {str(path)!r}: cannot be read ({exc})") from None
    if not rows:
        raise ParameterError(f"record {str(path)!r}: empty file")
    header = [h.strip() for h in rows[0]]
    if header not in (["t", "x"], ["t", "x", "y"]):
        raise ParameterError(f"record {str(path)!r}: header {','.join(header)!r}; allowed "
                             "'t,x' or 't,x,y' (s, m, m)")
    try:
        data = np.array([[float(v) for v in r] for r in rows[1:] if r], dtype=float)
    except ValueError as exc:
        raise ParameterError(f"record {str(path)!r}: not a number ({exc})") from None
    if data.ndim != 2 or data.shape[1] != len(header):
        raise ParameterError(f"record {str(path)!r}: every row needs {len(header)} values")
    return Record(data[:, 0], data[:, 1], data[:, 2] if len(header) == 3 else None)
