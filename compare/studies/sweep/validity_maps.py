"""Validity maps of a sweep: per target and pair of swept parameters, the discrepancy of
each metric from the paper's model (or the step from the rung below) on the study's colour
scale, the cells within the tolerance outlined, the dominating rung's letter in each cell.
Design notes: docs/sweeps.md.
"""

from __future__ import annotations

from pathlib import Path

from treeimpact.analytic.errors import ParameterError
from treeimpact.compare.runs.figure_text import save_figure
from treeimpact.compare.tree.ladder import LADDER_METRICS

from .discrepancy import discrepancies, numeric_axes, relevant_axes
from .map_cells import (
    _extend,
    _grid_figure,
    _heat,
    _in_order,
    _label,
    _line,
    _pairs,
    _percent_colorbar,
    _safe,
    _tolerance_of,
    _worst,
    colour_scale,
)


def validity_maps(df, figdir, *, metrics=LADDER_METRICS, tolerance=None, pairs=None,
                  prefix: str = "validity", order=None, value: str = "rel",
                  skip=()) -> list[dict]:
    """Draw the validity maps of a sweep table ``df`` into ``figdir`` (files named
    ``prefix``-TARGET); returns one dict per figure (path, target, axes, caption, its colour
    ``scale``) plus per-metric summaries (fraction within ``tolerance``, worst |rel| and
    where, dominating rung counts) of the ``metrics``. ``pairs``: the axis pairs to map
    (default: every pair of the axes that change the target); ``skip``: targets not drawn
    (mapped from another sweep). ``order``: target ids
    in the order their maps are listed. ``value``: "rel" maps each target against the
    paper's model, "step" against the rung below it (beam vs soft: the 1-DOF assumption
    alone). Every map shares one colour scale (:func:`colour_scale`)."""
    if value not in ("rel", "step"):
        raise ParameterError(f"value: {value!r}, allowed 'rel' or 'step'")
    figdir = Path(figdir)
    figdir.mkdir(parents=True, exist_ok=True)
    disc = discrepancies(df, metrics)
    if disc.empty:
        return []
    num = numeric_axes(df)
    scale = colour_scale(min(_tolerance_of(tolerance, m) for m in metrics))
    out = []
    for target, dt in _in_order(disc.groupby("target", sort=False), order):
        if target in skip:  # drawn from another sweep of the study
            continue
        if value == "step":
            dt = dt.assign(rel=dt["step"])  # the maps and summaries read the step
        ms = [m for m in metrics if dt[dt["metric"] == m]["rel"].notna().any()]
        if not ms:
            continue
        summary = _summaries(dt, ms, tolerance)
        plot_pairs = _plot_pairs(df, target, num, pairs)
        for a, b in plot_pairs:
            path = figdir / f"{prefix}-{_safe(target)}-{_safe(a)}{'-' + _safe(b) if b else ''}.png"
            _draw_target(df, dt, target, (a, b), ms, tolerance, scale, value, path)
            out.append({"path": path, "target": target, "axes": [a, b] if b else [a],
                        "caption": _validity_caption(target, a, b, tolerance, value),
                        "summary": summary, "scale": scale if b else None})
        if not plot_pairs:
            out.append({"path": None, "target": target, "axes": [], "caption": "",
                        "summary": summary, "scale": None})
    return out


def _plot_pairs(df, target: str, num: list[str], pairs) -> list[tuple]:
    """The (a, b) axis pairs ``target``'s maps are drawn over (b None: a line plot): the
    ``pairs`` asked for among the numeric axes ``num``, else every pair of the axes that
    change the target's runs in the sweep table ``df``."""
    rel_axes = relevant_axes(df, target, num)
    if pairs is not None:
        return _pairs(num, pairs)
    if len(rel_axes) >= 2:
        return _pairs(rel_axes)
    if len(rel_axes) == 1:
        return [(rel_axes[0], None)]
    return []


def _draw_target(df, dt, target: str, axis_pair: tuple, ms: list[str], tolerance, scale: dict,
                 value: str, path: Path) -> None:
    """One figure of ``target``'s discrepancies ``dt`` over ``axis_pair`` (a, b; b None: a
    line plot), a panel per metric of ``ms`` (heatmaps on the study's colour ``scale``),
    saved to ``path``; ``value``: "rel" (letters of the dominant rung) or "step"."""
    a, b = axis_pair
    fig, axes = _grid_figure(len(ms), dt[a].nunique(), dt[b].nunique() if b else 3)
    im = None
    for ax, m in zip(axes, ms):
        tol = _tolerance_of(tolerance, m)
        sub = dt[dt["metric"] == m]
        if b is None:
            _line(ax, _worst(sub, "rel", a, a), a, "rel", tol, f"{m}: rel. discrepancy")
        else:
            cell = _worst(sub, "rel", a, b)
            im = _heat(ax, cell, a, b, "rel", tol, f"{m} (tol {tol:.0%})",
                       letters="dominant" if value == "rel" else None, scale=scale)
    if im is not None:
        cb = fig.colorbar(im, ax=axes, shrink=0.8, aspect=25,
                          extend=_extend(dt["rel"], scale["vmax"]))
        _percent_colorbar(cb, scale, ("against the paper's model" if value == "rel"
                                      else "step from the rung below")
                          + f" (%)\nsaturates at +-{scale['vmax']:.0%}")
    what = f"{_label(a)} x {_label(b)}" if b else _label(a)
    versus = "the paper's model (analytic)" if value == "rel" else \
        f"the rung below ({_previous(df, target)})"
    fig.suptitle(f"{target} vs {versus}: {what}", fontsize=10)

    save_figure(fig, path, 110)


def _previous(df, target) -> str:
    prev = df.loc[df["target"] == target, "previous"].dropna()
    return str(prev.iloc[0]) if len(prev) else "none"


def _validity_caption(target, a, b, tolerance, value="rel") -> str:
    tol = "per-metric tolerances" if isinstance(tolerance, dict) else \
        f"|rel| = {_tolerance_of(tolerance, '')*100:.3g} %"
    na = ("Grey: no value (no ref: the paper's model has none, as for a force; failed: the "
          "run failed; n/a: the run gave none).")
    if value == "step":
        return (f"Relative step of {target} from the rung below it over {_label(a)}"
                + (f" and {_label(b)}" if b else "") + f" (worst case over any other swept "
                f"parameter), in %. Black outline: within {tol}. " + na)
    if b is None:
        return (f"Relative discrepancy of {target} from the paper's model over {_label(a)}, "
                f"in %; grey band: {tol}.")
    return (f"Relative discrepancy of {target} from the paper's model over {_label(a)} and "
            f"{_label(b)} (worst case over any other swept parameter), in %. Black outline: "
            f"within {tol}. Letters: the rung whose step dominates (see the legend above). "
            + na)


def _summaries(dt, ms, tolerance) -> list[dict]:
    rows = []
    for m in ms:
        sub = dt[(dt["metric"] == m) & dt["rel"].notna()]
        tol = _tolerance_of(tolerance, m)
        if sub.empty:
            continue
        worst = sub.loc[sub["rel"].abs().idxmax()]
        counts = sub["dominant"].dropna().value_counts()
        rows.append({"metric": m, "tolerance": tol, "cells": int(len(sub)),
                     "within": float((sub["rel"].abs() <= tol).mean()),
                     "worst_rel": float(worst["rel"]), "worst_point": worst["point"],
                     "dominant": {str(k): int(v) for k, v in counts.items()}})
    return rows
