"""The identification study's maps: each method's errors of M_T, K_T and b over e x crown
ratio, one row of panels per rung, on the study's one colour scale (compare.studies.sweep.maps).
docs/identification.md."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from treeimpact.compare.runs.figure_text import save_figure

from .ident_records import NOISE, PARAMETERS, RATE


def identification_error_map(rows: list[dict], method: str, path: Path) -> Path:
    """One figure per method (``fit`` or ``paper``): M_T, K_T and b errors (%) over e x
    crown ratio, one row of panels per rung; cells print the value, grey cells say why
    there is none. ``rows``: the study's cases (compare.studies.ident_records); returns
    ``path``, the PNG written."""
    # lazy: +288 ms at import otherwise (matplotlib, numpy),
    # which this module's other callers do not need
    from matplotlib.figure import Figure

    # lazy: +51 ms at import otherwise (treeimpact.compare.studies.sweep.map_cells),
    # which this module's other callers do not need
    from treeimpact.compare.studies.sweep.map_cells import (
        DEFAULT_TOLERANCE,
        _norm,
        _percent_colorbar,
        axis_label,
        colour_scale,
    )

    rungs = list(dict.fromkeys(r["rung"] for r in rows))
    es = sorted({r["restitution"] for r in rows})
    cs = sorted({r["crown_ratio"] for r in rows})
    fig = Figure(figsize=(3.4 * len(PARAMETERS) + 1.2, 2.6 * len(rungs) + 0.6),
                 layout="constrained")
    axes = fig.subplots(len(rungs), len(PARAMETERS), squeeze=False)
    scale = colour_scale(DEFAULT_TOLERANCE)  # the study's maps' one colour scale
    norm = _norm(scale)
    im = None
    for i, rung in enumerate(rungs):
        for j, k in enumerate(PARAMETERS):
            ax = axes[i][j]
            im = _panel(ax, [r for r in rows if r["rung"] == rung], method, k, es, cs, scale,
                        norm)
            ax.set_title(f"{rung}: {k}", fontsize=10)
            if i == len(rungs) - 1:
                ax.set_xlabel(axis_label("restitution"), fontsize=9)
            if j == 0:
                ax.set_ylabel(axis_label("crown_ratio"), fontsize=9)
    label = "full-record fit" if method == "fit" else "paper's procedure (eqs 39-48)"
    cb = fig.colorbar(im, ax=axes, shrink=0.6, extend="both")
    _percent_colorbar(cb, scale, "(identified - true) / true (%)\n"
                                 f"saturates at +-{scale['vmax']:.0%}")
    fig.suptitle(f"Identification error, {label}: {RATE / 1e3:g} kHz records with "
                 f"{100 * NOISE:g} % noise", fontsize=10)

    save_figure(fig, path, 100)
    return path


def _why(r: dict, method: str, k: str) -> str:
    """Why a case has no error of parameter ``k`` by ``method``: the text of its grey cell."""
    if method in r:  # the record does not fix this one (its interval wide)
        return "not fixed"
    if r.get(f"{method}_not_fixed"):
        known = r.get("fit_known_e", {}).get(k, math.nan)
        return ("one impact:\nrange;\ne given\n" + (f"{known:+.1%}" if math.isfinite(known)
                                                     else "no value"))
    return "not\nidentifiable" if "not identifiable" in str(
        r.get(f"{method}_error", r.get("error", ""))) else "failed"


def _panel(ax, rows: list[dict], method: str, k: str, es: list, cs: list, scale: dict,
           norm):
    """One rung's panel of parameter ``k``: the errors over e (``es``) x crown ratio
    (``cs``) on the study's colour scale, each cell's value or why it has none; returns
    the mesh (for the colour bar)."""
    # lazy: +51 ms at import otherwise (treeimpact.compare.studies.sweep.map_cells),
    # which this module's other callers do not need
    from treeimpact.compare.studies.sweep.map_cells import _ink

    Z = np.full((len(cs), len(es)), np.nan)
    why = {}
    for r in rows:
        a, b = es.index(r["restitution"]), cs.index(r["crown_ratio"])
        if method in r and k in r[method]:
            Z[b, a] = r[method][k]
        else:
            why[(b, a)] = _why(r, method, k)
    cmap = __import__("matplotlib").colormaps["RdBu_r"].with_extremes(bad="0.88")
    im = ax.pcolormesh(np.arange(len(es) + 1) - 0.5, np.arange(len(cs) + 1) - 0.5,
                       np.ma.masked_invalid(np.clip(Z, scale["vmin"], scale["vmax"])),
                       cmap=cmap, norm=norm)
    for b in range(len(cs)):
        for a in range(len(es)):
            if np.isfinite(Z[b, a]):
                v = Z[b, a]
                ax.text(a, b, f"{v:+.0%}" if abs(v) >= 0.1 else f"{v:+.1%}",
                        ha="center", va="center", fontsize=8,
                        color=_ink(cmap, norm, np.clip(v, scale["vmin"], scale["vmax"])))
            else:
                ax.text(a, b, why.get((b, a), "n/a"), ha="center", va="center",
                        fontsize=7, color="0.3")
    ax.set_xticks(range(len(es)), [f"{e:g}" for e in es], fontsize=9)
    ax.set_yticks(range(len(cs)), [f"{c:g}" for c in cs], fontsize=9)
    return im
