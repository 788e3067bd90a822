"""Identification maps of a sweep: per target, the relative error of M_T, K_T and the pair's
damping ratio that the paper's procedure (eqs 39-48) recovers from the target's own record,
on the study's colour scale; the caption counts the cells without a value by reason.
Design notes: docs/sweeps.md.
"""

from __future__ import annotations

from pathlib import Path

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
    last clause of the procedure's message), for the caption."""
    import re

    errors = sub.loc[sub["rel"].isna(), "id_error"] if "id_error" in sub else []
    counts: dict = {}
    for text in errors:
        if isinstance(text, str) and text:  # the clause without its numbers: one reason
            key = re.sub(r"\s*=\s*[-+]?[\d.]+(?:e[-+]?\d+)?(?:\s*(?:m/s|1/s|rad/s|m|s))?",
                         "", text.rsplit(": ", 1)[-1].strip())
            counts[key] = counts.get(key, 0) + 1
    return "; ".join(f"{why} ({n})" for why, n in sorted(counts.items(), key=lambda kv: -kv[1]))


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
    num = numeric_axes(df)
    e_ax = next((n for n in _E_NAMES if n in num), None)
    c_ax = next((n for n in _CROWN_NAMES if n in num), None)
    if e_ax and c_ax:
        a, b = e_ax, c_ax
    elif len(num) >= 2:
        a, b = num[0], num[1]
    elif num:
        a, b = num[0], None
    else:
        return []
    scale = colour_scale(DEFAULT_TOLERANCE)
    out = []
    for target, dt in _in_order(ide.groupby("target", sort=False), order):
        if target in skip:  # drawn from another sweep of the study
            continue
        if dt["rel"].notna().sum() == 0:
            continue
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
        keys = [k for k in MAPPED_IDENT_KEYS
                if dt[dt["parameter"] == k]["rel"].notna().any()]
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
        path = figdir / f"{prefix}-{_safe(target)}.png"
        fig.savefig(path, dpi=110)
        first = dt[dt["parameter"] == keys[0]]
        missing = int(first["rel"].isna().sum())
        why = _why_not_identified(first)
        out.append({"path": path, "target": target, "axes": [a, b] if b else [a],
                    "caption": (f"Relative error (%) of the parameters the paper's "
                                f"identification procedure recovers from the {target} record, "
                                f"over {_label(a)}{' and ' + _label(b) if b else ''}; black "
                                f"outline: within {DEFAULT_TOLERANCE:.0%}. E is not drawn: "
                                f"its error is K_T's (eq 47)."
                                + (f" {missing} of {len(first)} cells have no value (grey; "
                                   f"n/i: not identifiable, the record breaks the procedure's "
                                   f"premises; failed: the procedure stopped)"
                                   + (f"; cells by reason: {why}." if why else ".")
                                   if missing else "")),
                    "summary": summary, "scale": scale if b else None})
    return out
