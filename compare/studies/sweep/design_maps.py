"""The design study's contour maps (matplotlib, PNG): one row of panels per pair of inputs,
one panel per quantity, the signed gap in % as filled contours, the |gap| = 5 % line solid
and the 20 % line dashed, the trees' operating points marked (the user's tree a star).
Drawing only: the numbers come from compare.studies.design. Design notes:
docs/design-map.md."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...runs.figure_text import save_figure

#: The colour scale's end (%, clipped beyond) and the lines drawn (|gap|, %).
CLIP_PCT = 100.0
LINES_PCT = (5.0, 20.0)


@dataclass(frozen=True)
class Axis:
    """One axis of a map: values (display unit), label with unit, log spacing."""

    values: tuple
    label: str
    log: bool = False


@dataclass(frozen=True)
class Point:
    """An operating point: its label, x and y (display units), whether it is the user's."""

    label: str
    x: float
    y: float
    own: bool = False


def draw_pair(path, x: Axis, y: Axis, panels: dict, points, title: str) -> None:
    """Write the contour maps of ``panels`` ({title: Z in relative units, Z[j, i] at
    y[j], x[i]}) over ``x`` and ``y`` to ``path``, with ``points`` (:class:`Point`) marked
    and the figure's ``title``."""
    # lazy: +77 ms at import otherwise (matplotlib, numpy),
    # which this module's other callers do not need
    import matplotlib

    matplotlib.use("Agg")
    # lazy: +287 ms at import otherwise (matplotlib, numpy),
    # which this module's other callers do not need
    import matplotlib.pyplot as plt

    # lazy: +85 ms at import otherwise (matplotlib, numpy),
    # which this module's other callers do not need
    from matplotlib.lines import Line2D

    n = len(panels)
    cols = 2 if n == 4 else n
    rows = -(-n // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.9 * cols + 1.4, 3.3 * rows + 1.0),
                             layout="constrained", squeeze=False)
    levels = np.linspace(-CLIP_PCT, CLIP_PCT, 21)
    X, Y = np.meshgrid(x.values, y.values)
    filled = None
    for ax, (name, z) in zip(axes.flat, panels.items()):
        pct = np.clip(100.0 * np.asarray(z, dtype=float), -CLIP_PCT, CLIP_PCT)
        filled = ax.contourf(X, Y, pct, levels=levels, cmap="RdBu_r", extend="neither")
        mag = np.abs(100.0 * np.asarray(z, dtype=float))
        if np.isfinite(mag).any() and mag[np.isfinite(mag)].min() < max(LINES_PCT):
            ax.contour(X, Y, mag, levels=list(LINES_PCT), colors="k",
                       linestyles=["solid", "dashed"], linewidths=[1.6, 1.0])
        _mark(ax, points)
        _scale(ax.xaxis, ax.set_xscale, x)
        _scale(ax.yaxis, ax.set_yscale, y)
        ax.set_xlabel(x.label)
        ax.set_ylabel(y.label)
        ax.set_title(name, fontsize=10)
    cb = fig.colorbar(filled, ax=axes.ravel().tolist(), shrink=0.9)
    cb.set_label("gap (%)")
    own = [p for p in points if p.own]
    handles = [Line2D([], [], color="k", lw=1.6, label="|gap| = 5 %"),
               Line2D([], [], color="k", lw=1.0, ls="--", label="|gap| = 20 %"),
               Line2D([], [], marker="o", mfc="white", mec="k", ls="none",
                      label="shipped trees")]
    if own:
        handles.append(Line2D([], [], marker="*", ms=12, mfc="gold", mec="k", ls="none",
                              label=own[0].label))
    fig.legend(handles=handles, loc="outside lower center", ncol=len(handles), fontsize=8)
    fig.suptitle(title, fontsize=11)
    save_figure(fig, path, dpi=110)
    plt.close(fig)


def _mark(ax, points) -> None:
    """The operating points: circles labelled (one label per place, the user's star
    unlabelled: the legend names it), labels stacked where points share a place."""
    own = [(p.x, p.y) for p in points if p.own]
    placed: dict = {}
    for p in points:
        ax.plot(p.x, p.y, marker="*" if p.own else "o", ms=13 if p.own else 6,
                mfc="gold" if p.own else "white", mec="k", ls="none", zorder=5)
        if p.own:
            continue
        key = (round(p.x, 3), round(p.y, 3))
        k = placed.get(key, 0) + (1 if key in {(round(a, 3), round(b, 3)) for a, b in own}
                                   and key not in placed else 0)
        placed[key] = k + 1
        ax.annotate(p.label, (p.x, p.y), xytext=(5, 4 + 9 * k), textcoords="offset points",
                    fontsize=7, zorder=6)


def _scale(axis, set_scale, spec: Axis) -> None:
    """A log axis with ticks at 1, 2, 5 x 10^k inside its range, read as plain numbers."""
    # lazy: +80 ms at import otherwise (matplotlib, numpy),
    # which this module's other callers do not need
    from matplotlib.ticker import FuncFormatter, NullFormatter

    if not spec.log:
        return
    set_scale("log")
    lo, hi = min(spec.values), max(spec.values)
    ticks = [m * 10.0 ** k for k in range(-6, 6) for m in (1, 2, 5)
             if lo * 0.999 <= m * 10.0 ** k <= hi * 1.001]
    axis.set_ticks(ticks)
    axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    axis.set_minor_formatter(NullFormatter())
