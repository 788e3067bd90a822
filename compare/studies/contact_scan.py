"""The headline: the shortest contact duration for which the 1-DOF model is within a
tolerance of the continuum trunk. Per scenario, the soft SDOF and the beam rung (the same
pad: only the trunk differs) over a log grid of contact durations, run as a sweep
(resumable, on the sweeps' pool). SI units."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..runs.cache import OK
from ..runs.verdicts import validity_tolerance
from .sweep.run import SweepSpec, run_sweeps

#: Contact durations scanned (s): 0.2 ms (a hard impactor) to 50 ms (half the trunk's
#: quarter period; a very soft pad), 14 points, log-spaced.
DURATIONS = tuple(float(d) for d in np.geomspace(2e-4, 5e-2, 14))
#: What a harvester designer needs: trunk displacement, energy delivered to the tree, crown
#: acceleration (mean over t_c).
HEADLINE_METRICS = ("x_max", "energy_delivered", "crown_peak_acceleration")


def scan_sweep(scenario, out, durations=DURATIONS):
    """The scan of one scenario as a sweep (:class:`compare.studies.sweep.run.SweepSpec`) into
    ``out``: ``contact_duration`` over ``durations`` on the soft and beam rungs."""
    return SweepSpec(scenario, ["contact_duration=" + ",".join(repr(float(d))
                                                               for d in durations)],
                     Path(out), ("soft", "beam"), identify=False)


def contact_scan(scenario, out, durations=DURATIONS, metrics=HEADLINE_METRICS,
                 tolerance: float | None = None, *, workers=None, progress=False) -> dict:
    """Run (or resume) the scan of ``scenario`` over the contact ``durations`` (s) into the
    directory ``out`` on ``workers`` processes (``progress``: a bar on stderr) and read its
    ``metrics`` against ``tolerance`` (:func:`scan_result`)."""
    (res,) = run_sweeps([scan_sweep(scenario, out, durations)], workers=workers,
                        progress=progress)
    return scan_result(res.table, durations, metrics, tolerance)


def scan_result(table, durations=DURATIONS, metrics=HEADLINE_METRICS,
                tolerance: float | None = None) -> dict:
    """{durations, gaps: {metric: [rel gap beam vs soft per duration]}, shortest: {metric:
    duration (s) from which every longer scanned contact is within ``tolerance``, or None},
    contact: {soft|beam: {first_contact_duration: [s], pad_damping_ratio: [1]}} (what the
    pad does against each trunk's clamp: the scanned duration is the pad's collision time
    on the 1-DOF pair, not the contact the continuum sees), failed: [reasons]} from a scan's
    sweep table, for the scanned ``durations`` (s) and ``metrics``. ``tolerance``: default
    the studies' criterion (compare.runs.verdicts.validity_tolerance)."""
    if tolerance is None:
        tolerance = validity_tolerance()
    rows = {(r["target"], float(r["contact_duration"])): r
            for r in table.to_dict("records")}
    gaps = {m: [] for m in metrics}
    contact = {rung: {"first_contact_duration": [], "pad_damping_ratio": []}
               for rung in ("soft", "beam")}
    failed = []
    for d in durations:
        soft, beam = rows.get(("soft", float(d))), rows.get(("beam", float(d)))
        both = soft is not None and beam is not None and soft["status"] == beam["status"] == OK
        for m in metrics:
            a, b = (float(soft[m]), float(beam[m])) if both else (math.nan, math.nan)
            gaps[m].append((b - a) / abs(a) if a and math.isfinite(a) else math.nan)
        for rung, row in (("soft", soft), ("beam", beam)):
            ok = row is not None and row["status"] == OK
            contact[rung]["first_contact_duration"].append(
                float(row["first_contact_duration"]) if ok else math.nan)
            contact[rung]["pad_damping_ratio"].append(
                float(row["model.pad_damping_ratio"]) if ok else math.nan)
        failed += [f"{r['target']} at {1e3 * d:.3g} ms: {r['error']}" for r in (soft, beam)
                   if r is not None and r["status"] != OK]
    return {"durations": list(durations), "gaps": gaps, "tolerance": tolerance,
            "shortest": {m: shortest_within(durations, g, tolerance) for m, g in gaps.items()},
            "contact": contact, "failed": failed}


def shortest_within(durations, gaps, tolerance: float) -> float | None:
    """The shortest of the scanned ``durations`` (s) from which every longer one has
    |gap| <= ``tolerance`` (``gaps``: the relative gap at each; a NaN gap breaks the run);
    None if even the longest does not."""
    best = None
    for d, g in sorted(zip(durations, gaps), reverse=True):
        if not (math.isfinite(g) and abs(g) <= tolerance):
            break
        best = d
    return best
