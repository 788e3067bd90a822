"""The headline: the shortest contact duration for which the 1-DOF model is within a
tolerance of the continuum trunk. Per scenario, the soft SDOF and the beam rung (the same
pad: only the trunk differs) over a log grid of contact durations. SI units."""

from __future__ import annotations

import math

import numpy as np

from .runs import OK, RunCache

#: Contact durations scanned (s): 0.2 ms (a hard impactor) to 50 ms (half the trunk's
#: quarter period; a very soft pad), 14 points, log-spaced.
DURATIONS = tuple(float(d) for d in np.geomspace(2e-4, 5e-2, 14))
#: What a harvester designer needs: trunk displacement, energy delivered to the tree, crown
#: acceleration (mean over t_c).
HEADLINE_METRICS = ("x_max", "energy_delivered", "crown_peak_acceleration")


def scan_requests(scenario, durations=DURATIONS) -> list:
    """The (scenario, backend, options) runs of one scan, for RunCache.prefetch."""
    return [(scenario, b, {"contact_duration": d}) for d in durations for b in ("soft", "beam")]


def contact_scan(scenario, cache: RunCache, durations=DURATIONS,
                 metrics=HEADLINE_METRICS, tolerance: float | None = None) -> dict:
    """{durations, gaps: {metric: [rel gap beam vs soft per duration]}, shortest: {metric:
    duration (s) from which every longer scanned contact is within ``tolerance``, or None},
    failed: [reasons]}. Runs come from (or go into) ``cache``. ``tolerance``: default the
    studies' criterion (compare.ladder.validity_tolerance)."""
    if tolerance is None:
        from .verdicts import validity_tolerance

        tolerance = validity_tolerance()
    gaps = {m: [] for m in metrics}
    failed = []
    for d in durations:
        soft = cache.run(scenario, "soft", contact_duration=d)
        beam = cache.run(scenario, "beam", contact_duration=d)
        for m in metrics:
            if soft.status == OK and beam.status == OK:
                a, b = soft.result.metrics[m], beam.result.metrics[m]
                gaps[m].append((b - a) / abs(a) if a and math.isfinite(a) else math.nan)
            else:
                gaps[m].append(math.nan)
        failed += [f"{r.backend} at {1e3 * d:.3g} ms: {r.reason}" for r in (soft, beam)
                   if r.status != OK]
    return {"durations": list(durations), "gaps": gaps, "tolerance": tolerance,
            "shortest": {m: shortest_within(durations, g, tolerance) for m, g in gaps.items()},
            "failed": failed}


def shortest_within(durations, gaps, tolerance: float) -> float | None:
    """The shortest scanned duration from which every longer one has |gap| <= tolerance (a
    NaN gap breaks the run); None if even the longest does not."""
    best = None
    for d, g in sorted(zip(durations, gaps), reverse=True):
        if not (math.isfinite(g) and abs(g) <= tolerance):
            break
        best = d
    return best
