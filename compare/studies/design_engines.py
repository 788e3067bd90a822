"""The design map's spot checks by the engines (issue 43, item 3): at the corners of the
a/l x contact duration map and at the cells nearest its 5 % line on x_max, MuJoCo's and
Bullet's hinged chains and MuJoCo's flex rod run the same cell and are compared with the
continuum trunk, each metric against its stated tolerance (tolerances.toml ``[step.chain]``
for a chain, ``[step.rod]`` for the rod); a disagreement is reported, not hidden. SI units.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from treeimpact.analytic.continuum.beam_impact import simulate_beam

from ..runs.backends import get_backend
from ..runs.cache import OK, attempt
from ..runs.pool import process_map
from ..runs.verdicts import load_tolerances
from .design import INPUTS
from .design_words import along, shown
from .sweep.apply import apply_point


@dataclass(frozen=True)
class EngineRung:
    """An engine's flexible trunk: its label, backend, options, tolerance section."""

    label: str
    backend: str
    options: tuple  # (name, value) pairs
    step: str  # tolerances.toml [step.<step>]


RUNGS = (EngineRung("MuJoCo chain", "mujoco", (), "chain"),
         EngineRung("MuJoCo flex rod", "mujoco", (("trunk", "flex"),), "rod"),
         EngineRung("Bullet chain", "bullet", (), "chain"))
METRICS = ("x_max", "energy_delivered", "crown_peak_acceleration")


def spot_points(x, y, z, pair, here: dict, tol: float) -> list[dict]:
    """The cells checked on the map ``z`` over ``x`` and ``y`` (the inputs ``pair``): its
    four corners, then for each crossing of ``tol`` along ``pair[1]`` at the operating point
    ``here`` (design_words.along) the cell nearest it; {input: value} each, no repeats."""
    pts = [(x[0], y[0]), (x[0], y[-1]), (x[-1], y[0]), (x[-1], y[-1])]
    flip = (pair[1], pair[0])
    found, _ = along(y, x, np.asarray(z).T, flip, here, tol)
    cy = INPUTS[pair[1]].coordinate(np.asarray(y))
    i = int(np.argmin(np.abs(INPUTS[pair[0]].coordinate(np.asarray(x))
                             - INPUTS[pair[0]].coordinate(here[pair[0]]))))
    for lo, hi in found:
        for end in (lo, hi):
            if end not in (y[0], y[-1]):
                j = int(np.argmin(np.abs(cy - INPUTS[pair[1]].coordinate(end))))
                pts.append((x[i], y[j]))
    out = []
    for a, b in pts:
        p = {pair[0]: float(a), pair[1]: float(b)}
        if p not in out:
            out.append(p)
    return out


def spot_check(item) -> dict:
    """One cell, ``item`` = (scenario, point): the continuum's metrics and each engine
    rung's relative difference from them, its tolerance and verdict, or why it has none
    ({"point", "beam", "rungs": {label: {metric: {rel, tolerance, within}} | {error}}})."""
    scenario, point = item
    s, _ = apply_point(scenario, point)
    beam = simulate_beam(s).metrics
    table = load_tolerances()["step"]
    out = {"point": point, "beam": {m: beam[m] for m in METRICS}, "rungs": {}}
    for rung in RUNGS:
        run = attempt(get_backend(rung.backend), s, dict(rung.options))
        if run.status != OK:
            out["rungs"][rung.label] = {"error": run.reason}
            continue
        got = {}
        for m in METRICS:
            rel = (run.result.metrics[m] - beam[m]) / abs(beam[m])
            tol = float(table[rung.step][m]["rel"])
            got[m] = {"rel": rel, "tolerance": tol, "within": abs(rel) <= tol}
        out["rungs"][rung.label] = got | {"wall_s": run.wall_s}
    return out


def spot_sentence(checks: list, pair) -> str:
    """The spot checks ``checks`` (:func:`spot_check` each, cells over the inputs ``pair``)
    in words: how many (cell, engine, metric) comparisons are within their stated tolerance
    and every one that is not, with its difference and tolerance."""
    total, bad = 0, []
    for c in checks:
        at = ", ".join(f"{INPUTS[n].label} = {shown(n, c['point'][n])}" for n in pair)
        for label, got in c["rungs"].items():
            if "error" in got:
                bad.append(f"{label} at {at}: no run ({got['error']})")
                continue
            for m in METRICS:
                total += 1
                g = got[m]
                if not g["within"]:
                    bad.append(f"{label} {m} {100 * g['rel']:+.1f} % (tolerance "
                               f"{100 * g['tolerance']:.1f} %) at {at}")
    head = (f"The engines' flexible trunks agree with the continuum within their stated "
            f"tolerances in {total - len([b for b in bad if 'no run' not in b])} of {total} "
            f"comparisons at {len(checks)} cells")
    return head + (": they disagree on " + "; ".join(bad) + "." if bad else ".")


def spot_checks(scenario, x, y, z, pair, here: dict, tol: float, workers=None) -> dict:
    """The spot checks of one map (:func:`spot_points` of ``z`` over ``x``, ``y``, ``pair``
    at ``here`` and ``tol``) on the tree ``scenario``, run on compare.runs.pool's ``workers``:
    {"cells": [...], "sentence": str}."""
    points = spot_points(x, y, z, pair, here, tol)
    checks = process_map(spot_check, [(scenario, p) for p in points], workers=workers)
    return {"cells": checks, "sentence": spot_sentence(checks, pair),
            "all_within": all(g.get("within", False) for c in checks
                              for r in c["rungs"].values() for g in r.values()
                              if isinstance(g, dict)) and not any(
                                  "error" in r for c in checks for r in c["rungs"].values())}
