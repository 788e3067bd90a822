"""Validity maps and identification maps of a sweep (matplotlib, PNG).

Design notes and measured figures: docs/sweeps.md.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from treeimpact.analytic.errors import ParameterError

# the ladder's metrics and tolerance file, so a study and the report speak of the same things
from treeimpact.compare.ladder import LADDER_METRICS
from treeimpact.compare.rungs import RungKind
from treeimpact.compare.runs import OK
from treeimpact.compare.verdicts import validity_tolerance

from .execute import IDENT_KEYS

#: A study's validity criterion (5 %), not a test tolerance: tolerances.toml [study] validity
#: with its reason, the one tolerance source. Override with ``tolerance=`` / ``--tolerance``.
DEFAULT_TOLERANCE = validity_tolerance()

def _letter(kind) -> str:
    """The map letter of a rung kind (:attr:`compare.rungs.RungKind.letter`); ? if unknown."""
    try:
        return RungKind(kind).letter
    except ValueError:
        return "?"


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
    from treeimpact.analytic.results import METRIC_KEYS

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


def _worst(sub, value_col: str, a: str, b: str):
    """Per (a, b) cell the row with the largest |value| (sign kept), over other axes."""
    sub = sub.assign(_mag=np.abs(sub[value_col].to_numpy(float)))
    sub = sub.sort_values("_mag", ascending=False, na_position="last")
    return sub.drop_duplicates(subset=[a, b], keep="first")


def _tolerance_of(tolerance, metric: str) -> float:
    if isinstance(tolerance, dict):
        return float(tolerance.get(metric, DEFAULT_TOLERANCE))
    return float(DEFAULT_TOLERANCE if tolerance is None else tolerance)


#: How a swept parameter reads on a map and in the study's text: (name, display scale, unit);
#: a contact duration is swept in s and read in ms, as the report's text gives it.
_AXES = {"restitution": ("e", 1.0, "1"), "segments": ("segments", 1.0, ""),
         "trunk.crown_mass": ("m_f", 1.0, "kg"), "impactor.mass": ("m", 1.0, "kg"),
         "dt": ("dt", 1.0, "s"), "contact_stiffness": ("k_c", 1.0, "N/m"),
         "trunk.clamp_height": ("a", 1.0, "m"), "t_end": ("t_end", 1.0, "s"),
         "contact_duration": ("contact duration", 1e3, "ms"), "a_over_l": ("a / l", 1.0, ""),
         "crown_ratio": ("m_f / m_trunk", 1.0, ""), "mass_ratio": ("m / M_T", 1.0, "")}


def _label(name: str) -> str:
    """A swept parameter's axis label with its display unit: 'contact duration (ms)'."""
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
            shown = f"{_shown(k, v):.3g}" + (f" {unit}" if unit not in ("", "1") else "")
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
    import matplotlib
    from matplotlib.patches import Rectangle

    scale = dict(scale or colour_scale(tol))
    if vmax is not None:
        scale.update(vmin=-vmax, vmax=vmax)
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
    ax.set_xlabel(_label(a), fontsize=10)
    ax.set_ylabel(_label(b), fontsize=10)
    ax.set_title(title, fontsize=10)
    ax.grid(False)
    return im


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


def _vmax(values, tol) -> float:
    """Colour range of a figure of its own: the largest |value|, at least twice the
    tolerance, at most 100 % (a study's maps share :func:`colour_scale` instead)."""
    v = np.abs(np.asarray(values, float))
    v = v[np.isfinite(v)]
    return min(1.0, max(2.0 * tol, float(v.max()) if v.size else 1.0))


def _line(ax, sub, a, value_col, tol, title):
    sub = sub.sort_values(a)
    ax.axhspan(-100 * tol, 100 * tol, color="0.9", zorder=0)
    ax.plot(sub[a].map(lambda v: _shown(a, v)), 100 * sub[value_col], "o-", ms=3)
    ax.axhline(0.0, color="0.5", lw=0.5)
    ax.set_xlabel(_label(a), fontsize=9)
    ax.set_ylabel("relative (%)", fontsize=9)
    ax.set_title(title, fontsize=9)
    ax.tick_params(labelsize=8)


#: The widest a study figure is drawn (in): the page (1200 px) shows it at 0.9 scale or more.
MAX_FIGURE_WIDTH = 12.0


def _grid_figure(n_panels: int, columns: int = 6, rows: int = 6):
    """A figure of heatmap panels sized by their cells (about 0.5 in a printed column,
    0.33 in a row, so a 2 x 2 map stays small and an 8 x 6 one stays legible), as many
    panels a row as fit :data:`MAX_FIGURE_WIDTH`; no unused axes."""
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
        rel_axes = relevant_axes(df, target, num)
        if pairs is not None:
            plot_pairs = _pairs(num, pairs)
        elif len(rel_axes) >= 2:
            plot_pairs = _pairs(rel_axes)
        elif len(rel_axes) == 1:
            plot_pairs = [(rel_axes[0], None)]
        else:
            plot_pairs = []
        for a, b in plot_pairs:
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
            path = figdir / f"{prefix}-{_safe(target)}-{_safe(a)}{'-' + _safe(b) if b else ''}.png"
            fig.savefig(path, dpi=110)
            out.append({"path": path, "target": target, "axes": [a, b] if b else [a],
                        "caption": _validity_caption(target, a, b, tolerance, value),
                        "summary": summary, "scale": scale if b else None})
        if not plot_pairs:
            out.append({"path": None, "target": target, "axes": [], "caption": "",
                        "summary": summary, "scale": None})
    return out


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


def identification_errors(df):
    """Long table of identification errors of the sweep table ``df``: point, target,
    parameter, identified, truth, rel."""
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


#: Short labels of the sensitivity study's inputs and outputs on its figure.
INPUT_LABELS = {"clamp_mass": "clamp\nmass", "e_over_g": "E / G\n(shear)",
                 "log10_pad_duration": "pad\nstiffness", "restitution": "pad e",
                 "root_share": "root\ncompliance", "density": "wood\ndensity"}
OUTPUT_LABELS = {"gap.x_max": "x_max gap", "gap.energy_delivered": "energy gap",
                  "gap.crown_peak": "crown peak gap",
                  "gap.crown_peak_acceleration": "crown accel. gap",
                  "gap.peak_force": "force gap", "crossing.x_max": "crossing, x_max",
                  "crossing.energy_delivered": "crossing, energy"}


def sensitivity_figure(trees: dict, path: Path) -> Path | None:
    """One panel per tree of ``trees`` (name -> :func:`compare.studies.sensitivity.analyse`; a
    second row for the crossing durations): each output's Morris
    mu* per unmeasured input as a bar, its 95 % interval (SALib's mu_star_conf) as a
    whisker, the inputs that decide it outlined; a held (measured) input has no bar.
    Written to ``path``; returns it, or None when no tree has an output."""
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    trees = {n: t for n, t in trees.items() if t.get("outputs")}
    if not trees:
        return None
    names = list(trees)
    outputs = list(dict.fromkeys(o for t in trees.values() for o in t["outputs"]))
    groups = [g for g in ([o for o in outputs if o.startswith("gap.")],
                          [o for o in outputs if o.startswith("crossing.")]) if g]
    inputs = list(INPUT_LABELS)
    colours = dict(zip(inputs, ("tab:blue", "tab:orange", "tab:green", "tab:red",
                                "tab:purple", "tab:brown")))
    fig = Figure(figsize=(3.4 * len(names) + 2.4, 0.85 * len(outputs) + 1.9),
                 layout="constrained")
    axes = fig.subplots(len(groups), len(names), squeeze=False, sharex="row", sharey="row",
                        gridspec_kw={"height_ratios": [len(g) for g in groups]})
    h = 0.8 / len(inputs)
    for col, name in enumerate(names):
        for row, group in enumerate(groups):
            ax = axes[row][col]
            scale = 100.0 if group[0].startswith("gap.") else 1.0
            for j, o in enumerate(group):
                out = trees[name]["outputs"].get(o)
                if out is None:
                    continue
                for k, i in enumerate(inputs):
                    v = out["indices"].get(i)
                    if v is None:
                        continue
                    y = j + (k - (len(inputs) - 1) / 2) * h
                    ax.barh(y, scale * v["mu_star"], height=0.9 * h, color=colours[i],
                            edgecolor="k" if i in out["deciding"] else "none", lw=1.2,
                            xerr=scale * v["mu_star_conf"],
                            error_kw={"lw": 0.8, "capsize": 1.5, "ecolor": "0.25"})
            ax.set_yticks(range(len(group)), [OUTPUT_LABELS.get(o, o) for o in group],
                          fontsize=9)
            ax.set_ylim(len(group) - 0.5, -0.5)
            ax.grid(True, axis="x", lw=0.3)
            ax.tick_params(axis="x", labelsize=8)
            if row == 0:
                ax.set_title(name, fontsize=10)
            ax.set_xlabel("mu* (percentage points of the gap)" if scale == 100.0 else
                          "mu* (decades of the crossing duration)", fontsize=8.5)
    handles = [Patch(color=colours[i], label=INPUT_LABELS[i].replace("\n", " "))
               for i in inputs]
    handles.append(Patch(facecolor="white", edgecolor="k", label="outlined: decides it\n"
                         "(several: not separable)"))
    fig.legend(handles=handles, loc="outside right center", fontsize=8.5, frameon=False)
    first = next(iter(trees.values()))
    fig.suptitle(f"Which unmeasured input moves each answer: Morris mu* with its "
                 f"{100 * first.get('conf_level', 0.95):.0f} % interval (whiskers), "
                 f"{first.get('trajectories', '?')} trajectories per tree", fontsize=10)
    path = Path(path)
    fig.savefig(path, dpi=100)
    return path
