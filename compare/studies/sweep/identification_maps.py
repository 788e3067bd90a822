"""Identification maps of a sweep: per target, the relative error of M_T, K_T and the pair's
damping ratio that the paper's procedure (eqs 39-48) recovers from the target's own record,
on the study's colour scale; the caption counts the cells without a value by reason.
Design notes: docs/sweeps.md.
"""

from __future__ import annotations

import re
from pathlib import Path

from treeimpact.compare.runs.figure_text import save_figure

from .discrepancy import identification_errors, numeric_axes
from .execute import IDENT_KEYS
from .map_cells import (
    DEFAULT_TOLERANCE,
    _extend,
    _grid_figure,
    _heat,
    _in_order,
    _label,
    _line,
    _percent_colorbar,
    _safe,
    _worst,
    colour_scale,
)

_E_NAMES = ("restitution",)
_CROWN_NAMES = ("crown_ratio", "trunk.crown_mass")
#: The parameters the identification maps draw: E is K_T a^3 / (3 I) (eq 47) with a and I
#: known, so its relative error is K_T's; the summary tables list it.
MAPPED_IDENT_KEYS = ("M_T", "K_T", "pair_damping_ratio")


def _why_not_identified(sub) -> str:
    """The cells of one identification map without a value, counted by their reason (the
    last clause of the procedure's message, without its numbers and the parenthesised
    details that carry them), most frequent first, then alphabetically: the same caption
    whatever order the sweep's rows finished in."""
    errors = sub.loc[sub["rel"].isna(), "id_error"] if "id_error" in sub else []
    counts: dict = {}
    for text in errors:
        if isinstance(text, str) and text:  # the clause without its numbers: one reason
            clause = re.sub(r"\s*\([^()]*\d[^()]*\)", "", text.rsplit(": ", 1)[-1].strip())
            key = re.sub(r"\s*=\s*[-+]?[\d.]+(?:e[-+]?\d+)?(?:\s*(?:m/s|1/s|rad/s|m|s))?",
                         "", clause)
            counts[key] = counts.get(key, 0) + 1
    return "; ".join(f"{why} ({n})" for why, n in sorted(counts.items(),
                                                          key=lambda kv: (-kv[1], kv[0])))


def identification_maps(df, figdir, *, prefix: str = "identification",
                        order=None, skip=()) -> list[dict]:
    """Draw the identification maps (see the module docstring) of the sweep table ``df``
    into ``figdir`` (files named ``prefix``-TARGET, targets in ``order``, those of ``skip``
    left out): one figure
    per target, a panel per parameter of :data:`MAPPED_IDENT_KEYS` that has a value
    somewhere (a panel without any is dropped), every map on one colour scale
    (:func:`colour_scale`); the caption counts the cells without a value and says why."""
    figdir = Path(figdir)
    figdir.mkdir(parents=True, exist_ok=True)
    ide = identification_errors(df)
    if ide.empty or ide["rel"].notna().sum() == 0:
        return []
    axis_pair = _map_axes(numeric_axes(df))
    if axis_pair is None:
        return []
    a, b = axis_pair
    scale = colour_scale(DEFAULT_TOLERANCE)
    out = []
    for target, dt in _in_order(ide.groupby("target", sort=False), order):
        if target in skip:  # drawn from another sweep of the study
            continue
        if dt["rel"].notna().sum() == 0:
            continue
        summary = _summary(dt)
        keys = [k for k in MAPPED_IDENT_KEYS
                if dt[dt["parameter"] == k]["rel"].notna().any()]
        path = figdir / f"{prefix}-{_safe(target)}.png"
        _draw_target(dt, target, axis_pair, keys, scale, path)
        out.append({"path": path, "target": target, "axes": [a, b] if b else [a],
                    "caption": _caption(target, axis_pair, dt[dt["parameter"] == keys[0]]),
                    "summary": summary, "scale": scale if b else None})
    return out


def _map_axes(num: list[str]) -> tuple | None:
    """The axes (a, b) of the identification maps among the numeric swept parameters
    ``num``: e and the crown mass when both are swept, else the first two (b None: one
    swept parameter, a line plot); None without any."""
    e_ax = next((n for n in _E_NAMES if n in num), None)
    c_ax = next((n for n in _CROWN_NAMES if n in num), None)
    if e_ax and c_ax:
        return e_ax, c_ax
    if len(num) >= 2:
        return num[0], num[1]
    if num:
        return num[0], None
    return None


def _summary(dt) -> list[dict]:
    """Per parameter of IDENT_KEYS with a value somewhere in one target's errors ``dt``:
    its cells, failures, best |rel| and worst rel with where."""
    summary = []
    for k in IDENT_KEYS:
        sub = dt[dt["parameter"] == k]
        fin = sub[sub["rel"].notna()]
        if len(fin):
            w = fin.loc[fin["rel"].abs().idxmax()]
            summary.append({"parameter": k, "cells": int(len(fin)),
                            "failed": int(sub["rel"].isna().sum()),
                            "best_abs_rel": float(fin["rel"].abs().min()),
                            "worst_rel": float(w["rel"]), "worst_point": w["point"]})
    return summary


def _draw_target(dt, target: str, axis_pair: tuple, keys: list[str], scale: dict,
                 path: Path) -> None:
    """One figure of ``target``'s identification errors ``dt`` over ``axis_pair`` (a, b;
    b None: a line plot), a panel per parameter of ``keys`` on the study's colour
    ``scale``, saved to ``path``."""
    a, b = axis_pair
    fig, axes = _grid_figure(len(keys), dt[a].nunique(), dt[b].nunique() if b else 3)
    im = None
    for ax, k in zip(axes, keys):
        sub = dt[dt["parameter"] == k]
        if b is None:
            _line(ax, _worst(sub, "rel", a, a), a, "rel", DEFAULT_TOLERANCE,
                  f"{k}: identified vs true")
        else:
            im = _heat(ax, _worst(sub, "rel", a, b), a, b, "rel", DEFAULT_TOLERANCE,
                       f"{k}: (identified - true) / true", scale=scale)
    if im is not None:
        cb = fig.colorbar(im, ax=axes, shrink=0.8, aspect=25,
                          extend=_extend(dt["rel"], scale["vmax"]))
        _percent_colorbar(cb, scale, "(identified - true) / true (%)\n"
                                     f"saturates at +-{scale['vmax']:.0%}")
    fig.suptitle(f"Identification (eqs 39-48) on the {target} record", fontsize=10)

    save_figure(fig, path, 110)


def _caption(target: str, axis_pair: tuple, first) -> str:
    """The caption of ``target``'s map over ``axis_pair``; ``first``: the errors of its
    first panel's parameter, whose cells without a value it counts by reason."""
    a, b = axis_pair
    missing = int(first["rel"].isna().sum())
    why = _why_not_identified(first)
    return (f"Relative error (%) of the parameters the paper's "
            f"identification procedure recovers from the {target} record, "
            f"over {_label(a)}{' and ' + _label(b) if b else ''}; black "
            f"outline: within {DEFAULT_TOLERANCE:.0%}. E is not drawn: "
            f"its error is K_T's (eq 47)."
            + (f" {missing} of {len(first)} cells have no value (grey; "
               f"n/i: not identifiable, the record breaks the procedure's "
               f"premises; failed: the procedure stopped)"
               + (f"; cells by reason: {why}." if why else ".")
               if missing else ""))
