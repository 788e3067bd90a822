"""The points of a sampling design that did not run (issue 50 item 4): each kept with its
index in the design, its input values named and united as the registry names them, its
status and the run's one-line reason; and which of the design's groups (Morris
trajectories, Saltelli blocks) are complete, the indices resting on those alone.

A design's estimator is built on groups of rows: a Morris trajectory (inputs + 1 rows,
one input stepped between consecutive rows) gives one elementary effect per input; a
Saltelli block (inputs + 2 rows: A, the inputs' AB rows, B) gives one term of each
Sobol index's estimator. A group with a failed row gives nothing exact, so it is dropped
whole (never imputed) and the count of groups kept travels with the indices.
"""

from __future__ import annotations

import math

from treeimpact.analytic.model.registry import BY_NAME

#: The failed points study.json lists in full (every failure is counted; a design whose
#: points nearly all fail lists its first ones).
MAX_LISTED = 200


def point_inputs(names, x) -> dict:
    """A design row ``x`` over ``names`` as {name: {value, unit}} (the registry's units)."""
    return {n: {"value": float(v), "unit": BY_NAME[n].unit} for n, v in zip(names, x)}


def point_text(index: int, inputs: dict, reason: str) -> str:
    """'point 14 (clamp_mass = 6 kg, root_share = 0.9): reason', one line: the design row
    ``index``, its ``inputs`` (:func:`point_inputs`) and the one-line ``reason``."""
    values = ", ".join(f"{n} = {v['value']:.6g}" + ("" if v["unit"] == "1" else f" {v['unit']}")
                       for n, v in inputs.items())
    return f"point {index} ({values}): {reason}"


def failed_points(names, X, rows, ok: str) -> list[dict]:
    """The rows of the design ``X`` (columns ``names``) that did not run: ``rows`` are the
    sweep's row of each point (None where it has none), ``ok`` the status of a run with
    numbers. Each: {index, inputs (:func:`point_inputs`), status, reason, text}."""
    out = []
    for i, (x, r) in enumerate(zip(X, rows)):
        if r is not None and r.get("status") == ok:
            continue
        status = "missing" if r is None else str(r.get("status"))
        reason = "no row in the sweep's table" if r is None else _reason(r.get("error"))
        inputs = point_inputs(names, x)
        out.append({"index": i, "inputs": inputs, "status": status, "reason": reason,
                    "text": point_text(i, inputs, reason)})
    return out


def _reason(error) -> str:
    if error is None or (isinstance(error, float) and math.isnan(error)):
        return "no reason recorded"
    return str(error).splitlines()[0] if str(error).strip() else "no reason recorded"


def complete_groups(count: int, size: int, failed: list[dict]) -> list[int]:
    """The groups (``count`` of ``size`` consecutive rows each) with no row in ``failed``
    (:func:`failed_points`), by index."""
    bad = {f["index"] // size for f in failed}
    return [g for g in range(count) if g not in bad]


def rows_of(groups: list[int], size: int) -> list[int]:
    """The row indices of the ``groups`` (of ``size`` rows each), in order."""
    return [g * size + k for g in groups for k in range(size)]


def failure_summary(failed: list[dict], points: int) -> dict:
    """The design's failures (``failed``, :func:`failed_points`) as study.json keeps them:
    {failed (count), failed_points (the first MAX_LISTED), failed_listed, errors (up to 5
    distinct reasons), points (the design's size, ``points``)}."""
    return {"failed": len(failed), "failed_points": failed[:MAX_LISTED],
            "failed_listed": min(len(failed), MAX_LISTED),
            "errors": sorted({f["reason"] for f in failed})[:5], "points": points}
