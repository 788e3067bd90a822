"""The long tables a sweep's maps are drawn from: each run's discrepancy from the paper's
model and its step from the rung below (:func:`discrepancies`), each identification's error
from the truth (:func:`identification_errors`), and the swept parameters a map can have as
its axes. Design notes: docs/sweeps.md.
"""

from __future__ import annotations

import numpy as np

from treeimpact.analytic.metrics import METRIC_KEYS

# the ladder's metrics, so a study and the report speak of the same things
from treeimpact.compare.runs.cache import OK
from treeimpact.compare.tree.ladder import LADDER_METRICS

from .execute import IDENT_KEYS


def _rel(value, reference):
    value = np.asarray(value, float)
    reference = np.asarray(reference, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = (value - reference) / np.abs(reference)
    out[~np.isfinite(out)] = np.nan
    return out


def discrepancies(df, metrics=LADDER_METRICS):
    """Long table of the sweep table ``df``: one row per (point, target, metric) of
    ``metrics`` with rel, step and the dominating rung.

    Columns: point, target, backend, kind, metric, value, analytic, rel, step, dominant
    (kind of the largest step), plus the swept parameters of the point.
    """
    # lazy: +201 ms at import otherwise (pandas, numpy, pyarrow),
    # which this module's other callers do not need
    import pandas as pd

    ok = df[df["status"] == OK]
    metrics = [m for m in metrics if m in df.columns]
    kind_of = dict(zip(df["target"], df["kind"]))
    prev_of = {t: (p if isinstance(p, str) else None)
               for t, p in zip(df["target"], df["previous"])}
    ref = ok[ok["target"] == "analytic"].set_index("point")
    by_target = {t: g.set_index("point") for t, g in ok.groupby("target")}
    axis_cols = axis_names(df)
    frames = []
    for target, g in by_target.items():
        if target == "analytic":
            continue
        chain = []  # (kind, this target, previous target) down to the analytic reference
        t = target
        while t is not None and prev_of.get(t) is not None and len(chain) < 10:
            chain.append((kind_of.get(t), t, prev_of[t]))
            t = prev_of[t]
        for m in metrics:
            analytic = ref[m].reindex(g.index) if m in ref else pd.Series(np.nan, g.index)
            steps = {}
            for kind, a, b in chain:
                va = by_target[a][m].reindex(g.index) if a in by_target else np.nan
                vb = by_target[b][m].reindex(g.index) if b in by_target else np.nan
                steps[kind] = _rel(va, vb)
            step_arr = np.vstack(list(steps.values())) if steps else np.full((1, len(g)), np.nan)
            mag = np.where(np.isfinite(step_arr), np.abs(step_arr), -1.0)
            idx = np.argmax(mag, axis=0)
            kinds = list(steps)
            dominant = [kinds[i] if kinds and mag[i, j] >= 0 else None
                        for j, i in enumerate(idx)]
            own_step = steps.get(kind_of.get(target), np.full(len(g), np.nan)) if chain else \
                np.full(len(g), np.nan)
            frame = pd.DataFrame({
                "point": g.index, "target": target, "backend": g["backend"].to_numpy(),
                "kind": kind_of.get(target), "metric": m, "value": g[m].to_numpy(float),
                "analytic": np.asarray(analytic, float), "rel": _rel(g[m], analytic),
                "step": own_step, "dominant": dominant})
            for c in axis_cols:
                frame[c] = g[c].to_numpy()
            frames.append(frame)
    if not frames:
        return pd.DataFrame(columns=["point", "target", "backend", "kind", "metric", "value",
                                     "analytic", "rel", "step", "dominant"])
    return pd.concat(frames, ignore_index=True)


_NON_AXIS = {"scenario", "point", "target", "backend", "kind", "previous", "status", "error",
             "wall_s", "t_end", "task", "worker", "finished"}


def axis_names(df) -> list[str]:
    """The swept parameters of a sweep table ``df`` (columns between the base and metric
    columns)."""
    return [c for c in df.columns if c not in _NON_AXIS and c not in METRIC_KEYS
            and not c.startswith(("model.", "id.", "truth.")) and c != "id_error"]


def numeric_axes(df) -> list[str]:
    """The swept parameters of the sweep table ``df`` with two or more numeric values (the
    ones a map can have as an axis)."""
    out = []
    for c in axis_names(df):
        vals = df[c].dropna().unique()
        if len(vals) >= 2 and all(isinstance(v, (int, float, np.integer, np.floating))
                                  for v in vals):
            out.append(c)
    return out


def relevant_axes(df, target: str, axes: list[str]) -> list[str]:
    """The swept parameters among ``axes`` that change ``target``'s runs in the sweep table
    ``df`` (its task differs along them with the others held): ``segments`` does not change
    the analytic reference, for example."""
    sub = df[df["target"] == target]
    out = []
    for a in axes:
        others = [c for c in axes if c != a]
        groups = sub.groupby(others, dropna=False)["task"] if others else [(None, sub["task"])]
        if any(g.nunique() > 1 for _, g in groups):
            out.append(a)
    return out


def identification_errors(df):
    """Long table of identification errors of the sweep table ``df``: point, target,
    parameter, identified, truth, rel."""
    # lazy: +201 ms at import otherwise (pandas, numpy, pyarrow),
    # which this module's other callers do not need
    import pandas as pd

    ok = df[df["status"] == OK]
    frames = []
    axes = axis_names(df)
    for k in IDENT_KEYS:
        if f"id.{k}" not in ok or f"truth.{k}" not in ok:
            continue
        f = pd.DataFrame({"point": ok["point"], "target": ok["target"], "parameter": k,
                          "identified": ok[f"id.{k}"].astype(float),
                          "truth": ok[f"truth.{k}"].astype(float)})
        f["rel"] = _rel(f["identified"], f["truth"])
        if "id_error" in ok:  # why a cell has no value (shown on the map)
            f["id_error"] = ok["id_error"].to_numpy()
        for c in axes:
            f[c] = ok[c].to_numpy()
        frames.append(f)
    if not frames:
        return pd.DataFrame(columns=["point", "target", "parameter", "identified", "truth",
                                     "rel"])
    return pd.concat(frames, ignore_index=True)
