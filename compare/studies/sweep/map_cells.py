"""What every map of a sweep shares: the one colour scale of a study, the axes read in the
text's units, a heatmap whose cells print their values and say why one has none, a line
plot with the tolerance band for one swept parameter, and a figure of panels sized by their
cells. Design notes: docs/sweeps.md.
"""

from __future__ import annotations

import math

import numpy as np

from treeimpact.analytic.model.registry import PARAMETERS
from treeimpact.compare.runs.rungs import RungKind
from treeimpact.compare.runs.verdicts import validity_tolerance

#: A study's validity criterion (5 %), not a test tolerance: tolerances.toml [study] validity
#: with its reason, the one tolerance source. Override with ``tolerance=`` / ``--tolerance``.
DEFAULT_TOLERANCE = validity_tolerance()


def _letter(kind) -> str:
    """The map letter of a rung kind (:attr:`compare.runs.rungs.RungKind.letter`); ? if unknown."""
    try:
        return RungKind(kind).letter
    except ValueError:
        return "?"


def _worst(sub, value_col: str, a: str, b: str):
    """Per (a, b) cell the row with the largest |value| (sign kept), over other axes."""
    sub = sub.assign(_mag=np.abs(sub[value_col].to_numpy(float)))
    sub = sub.sort_values("_mag", ascending=False, na_position="last")
    return sub.drop_duplicates(subset=[a, b], keep="first")


def _tolerance_of(tolerance, metric: str) -> float:
    if isinstance(tolerance, dict):
        return float(tolerance.get(metric, DEFAULT_TOLERANCE))
    return float(DEFAULT_TOLERANCE if tolerance is None else tolerance)


#: How a swept parameter reads on a map and in the study's text: (name, display scale, unit),
#: from the registry (analytic.model.registry): a contact duration is swept in s and read in
#: ms, as the report's text gives it; engine options (segments, dt) are not physical inputs.
_AXES = {p.sweep: (p.axis, p.shown[0], p.shown_unit) for p in PARAMETERS
         if p.sweep is not None} | {"segments": ("segments", 1.0, ""), "dt": ("dt", 1.0, "s")}
#: The units a figure's label leaves out: a dimensionless number's.
_NO_UNIT = ("", "1")


def _label(name: str) -> str:
    """A swept parameter as a caption's prose names it, with its display unit if it has
    one: 'contact duration (ms)', 'e'."""
    text, _, unit = _AXES.get(name, (name, 1.0, ""))
    return f"{text} ({unit})" if unit not in _NO_UNIT else text


def axis_label(name: str) -> str:
    """A swept parameter's figure axis: its words and display unit, '(1)' for a
    dimensionless number ('e (1)', 'contact duration (ms)'), as every axis of the report's
    and the studies' figures states its unit; an engine option without a unit (segments)
    is its name."""
    text, _, unit = _AXES.get(name, (name, 1.0, ""))
    return f"{text} ({unit})" if unit else text


def _shown(name: str, value) -> float:
    """A swept parameter's value in its display unit (a contact duration in ms)."""
    return float(value) * _AXES.get(name, (name, 1.0, ""))[1]


def point_text(pairs) -> str:
    """A grid point (name, value) pairs as the text reads it: 'contact duration = 0.2 ms,
    m_f / m_trunk = 4'."""
    out = []
    for k, v in pairs:
        text, _, unit = _AXES.get(k, (k, 1.0, ""))
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            shown = f"{_shown(k, v):.3g}" + (f" {unit}" if unit not in _NO_UNIT else "")
        else:
            shown = str(v)
        out.append(f"{text} = {shown}")
    return ", ".join(out)


#: One colour scale for every map of a study (validity and identification): symmetric log
#: colours from -MAP_VMAX to +MAP_VMAX (relative, 1 = 100 %), linear within LINEAR_FRACTION
#: of the tolerance, so that a 1 % and a 100 % cell both read and two maps compare.
MAP_VMAX = 1.0
LINEAR_FRACTION = 0.2


def colour_scale(tol: float) -> dict:
    """The maps' colour scale at tolerance ``tol`` (relative): vmin, vmax, linthresh."""
    return {"vmin": -MAP_VMAX, "vmax": MAP_VMAX, "linthresh": LINEAR_FRACTION * tol}


def _norm(scale: dict):
    # lazy: +84 ms at import otherwise (matplotlib, numpy),
    # which this module's other callers do not need
    from matplotlib.colors import SymLogNorm

    return SymLogNorm(linthresh=scale["linthresh"], linscale=0.5, vmin=scale["vmin"],
                      vmax=scale["vmax"])


def _percent_colorbar(cb, scale: dict, label: str) -> None:
    """The colour bar's ticks in %, as the cells print their values."""
    top = scale["vmax"]
    ticks = [t for t in (-1.0, -0.1, -0.01, 0.0, 0.01, 0.1, 1.0)
             if abs(t) <= top and (t == 0 or abs(t) >= 0.999 * scale["linthresh"])]
    cb.set_ticks(ticks, labels=["0" if t == 0 else f"{100 * t:+.0f} %" for t in ticks])
    cb.ax.tick_params(labelsize=8)
    cb.set_label(label, fontsize=8)


#: Why a map cell has no value, as few letters as fit in a cell; the caption spells them out.
NO_VALUE = {"not identifiable": "n/i", "failed": "failed", "paper model: no value": "no ref",
            "no value": "n/a", "": "n/a"}


def _heat(ax, cell, a, b, value_col, tol, title, letters=None, vmax=None, annotate=False,
          scale=None):
    """One heatmap on ax: rows b, columns a (index grid, values as tick labels in their
    display unit). Every cell prints its value in % (the colours saturate at the scale's
    ends, the text does not) and, with ``letters``, the dominant rung's letter; a cell within
    ``tol`` is outlined in black; a cell without a value says why in a word
    (:data:`NO_VALUE`). ``scale``: :func:`colour_scale` (default: at ``tol``, ``vmax``
    overriding its ends); ``annotate`` is kept for callers: values always show."""
    # lazy: +83 ms at import otherwise (matplotlib, numpy),
    # which this module's other callers do not need
    import matplotlib

    # lazy: +140 ms at import otherwise (matplotlib, numpy),
    # which this module's other callers do not need
    from matplotlib.patches import Rectangle

    scale = dict(scale or colour_scale(tol))
    if vmax is not None:
        scale.update(vmin=-vmax, vmax=vmax)
    xs, ys, Z, L, why = _cell_grid(cell, a, b, value_col, letters)
    finite = np.isfinite(Z)
    masked = np.ma.masked_invalid(np.clip(Z, scale["vmin"], scale["vmax"]))
    cmap = matplotlib.colormaps["RdBu_r"].with_extremes(bad="0.88")
    norm = _norm(scale)
    im = ax.pcolormesh(np.arange(len(xs) + 1) - 0.5, np.arange(len(ys) + 1) - 0.5, masked,
                       cmap=cmap, norm=norm, shading="flat")
    small = len(xs) <= 12 and len(ys) <= 12
    size = 9 if len(xs) <= 6 else 7.5
    for j in range(len(ys)):
        for i in range(len(xs)):
            if not finite[j, i]:
                if small:
                    ax.text(i, j, NO_VALUE.get(why[j, i], "n/a"), ha="center", va="center",
                            fontsize=size - 0.5, color="0.3")
                continue
            if abs(Z[j, i]) <= tol:  # within the tolerance: outlined on the real grid
                ax.add_patch(Rectangle((i - 0.5, j - 0.5), 1, 1, fill=False, ec="k", lw=2.0))
            if small:
                v = Z[j, i]
                text = f"{v:+.0%}" if abs(v) < 100 else f"{v:+.1e}"
                if L[j, i]:
                    text = f"{L[j, i]} {text}"
                ax.text(i, j, text, ha="center", va="center", fontsize=size,
                        color=_ink(cmap, norm, np.clip(v, scale["vmin"], scale["vmax"])))
    xt = [f"{_shown(a, v):.3g}" for v in xs]
    ax.set_xticks(range(len(xs)), xt, fontsize=9,
                  rotation=45 if len(xs) > 6 and max(map(len, xt)) > 5 else 0)
    ax.set_yticks(range(len(ys)), [f"{_shown(b, v):.3g}" for v in ys], fontsize=9)
    ax.set_xlabel(axis_label(a), fontsize=10)
    ax.set_ylabel(axis_label(b), fontsize=10)
    ax.set_title(title, fontsize=10)
    ax.grid(False)
    return im


def _cell_grid(cell, a: str, b: str, value_col: str, letters):
    """The rows of ``cell`` on their grid: (xs, ys, values, letters, why) with xs the sorted
    values of column ``a``, ys those of ``b``, and per grid cell its ``value_col``, the
    letter of its rung in column ``letters`` (if given) and why it has no value."""
    xs = sorted(cell[a].unique())
    ys = sorted(cell[b].unique())
    Z = np.full((len(ys), len(xs)), np.nan)
    L = np.full((len(ys), len(xs)), "", dtype=object)
    why = np.full((len(ys), len(xs)), "", dtype=object)
    xi = {v: i for i, v in enumerate(xs)}
    yi = {v: i for i, v in enumerate(ys)}
    for _, r in cell.iterrows():
        j, i = yi[r[b]], xi[r[a]]
        Z[j, i] = r[value_col]
        if letters is not None and isinstance(r.get(letters), str):
            L[j, i] = _letter(r[letters])
        why[j, i] = _why_missing(r)
    return xs, ys, Z, L, why


def _ink(cmap, norm, value) -> str:
    """Black or white text, whichever reads on the cell's colour."""
    r, g, b, _ = cmap(norm(value))
    return "w" if 0.299 * r + 0.587 * g + 0.114 * b < 0.5 else "k"


def _why_missing(row) -> str:
    """Why a map cell has no value, in a few words (the row's own error first): a key of
    :data:`NO_VALUE`."""
    for col in ("id_error", "error"):
        text = row.get(col)
        if isinstance(text, str) and text:
            return "not identifiable" if text.startswith("not identifiable") else "failed"
    value, ref = row.get("value"), row.get("analytic")
    if isinstance(ref, float) and not math.isfinite(ref):
        return "paper model: no value"
    if isinstance(value, float) and not math.isfinite(value):
        return "no value"
    return ""


def _extend(values, vmax) -> str:
    """The colour bar's arrows: which ends the values pass (clipped colours, never silent)."""
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    lo, hi = bool(v.size and v.min() < -vmax), bool(v.size and v.max() > vmax)
    return {(True, True): "both", (True, False): "min", (False, True): "max"}.get((lo, hi),
                                                                                "neither")

def _line(ax, sub, a, value_col, tol, title):
    sub = sub.sort_values(a)
    ax.axhspan(-100 * tol, 100 * tol, color="0.9", zorder=0)
    ax.plot(sub[a].map(lambda v: _shown(a, v)), 100 * sub[value_col], "o-", ms=3)
    ax.axhline(0.0, color="0.5", lw=0.5)
    ax.set_xlabel(axis_label(a), fontsize=9)
    ax.set_ylabel("relative (%)", fontsize=9)
    ax.set_title(title, fontsize=9)
    ax.tick_params(labelsize=8)


#: The widest a study figure is drawn (in): the page (1200 px) shows it at 0.9 scale or more.
MAX_FIGURE_WIDTH = 12.0


def _grid_figure(n_panels: int, columns: int = 6, rows: int = 6):
    """A figure of heatmap panels sized by their cells (about 0.5 in a printed column,
    0.33 in a row, so a 2 x 2 map stays small and an 8 x 6 one stays legible), as many
    panels a row as fit :data:`MAX_FIGURE_WIDTH`; no unused axes."""
    # lazy: +301 ms at import otherwise (matplotlib, numpy),
    # which this module's other callers do not need
    from matplotlib.figure import Figure

    width = max(2.2, 0.5 * columns + 0.9)
    height = max(1.9, 0.33 * rows + 1.1)
    ncol = max(1, min(n_panels, int((MAX_FIGURE_WIDTH - 1.2) // width)))
    nrow = math.ceil(n_panels / ncol)
    fig = Figure(figsize=(width * ncol + 1.2, height * nrow + 0.5), layout="constrained")
    axes = [fig.add_subplot(nrow, ncol, i + 1) for i in range(n_panels)]
    return fig, axes


def _pairs(axes: list[str], pairs=None) -> list[tuple]:
    if pairs is not None:
        return [tuple(p) for p in pairs]
    return [(axes[i], axes[j]) for i in range(len(axes)) for j in range(i + 1, len(axes))]


def _safe(name: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in name)


def _in_order(groups, order):
    """(target, frame) pairs of a groupby, targets listed in ``order`` first, in that order
    (the sweep's own target order: soft, then each engine's rungs), then the rest by name."""
    groups = dict(list(groups))
    rank = {t: i for i, t in enumerate(order or ())}
    return sorted(groups.items(), key=lambda kv: (rank.get(kv[0], len(rank)), kv[0]))
