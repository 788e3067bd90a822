"""Figures of the report (matplotlib, Agg backend), written as PNG files beside the page.

Every figure function returns a matplotlib ``Figure``; :class:`FigureFiles` writes it and
gives the path the page links to. Every axis carries its quantity and unit, legends sit
outside the data, and rungs keep one colour and line style across all figures of a
scenario (:func:`rung_style`). Where rungs nearly coincide, the figures show each rung's
difference from the paper's model (or one panel per rung) instead of overlaid curves.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import matplotlib
from matplotlib.lines import Line2D

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from treeimpact.compare.runs.backends import BACKENDS  # noqa: E402
from treeimpact.compare.runs.figure_text import save_figure  # noqa: E402
from treeimpact.compare.runs.rungs import ENGINE_KINDS, RungKind  # noqa: E402

DPI = 110
plt.rcParams.update({"font.size": 10, "axes.titlesize": 11, "axes.labelsize": 10,
                     "legend.fontsize": 9, "axes.grid": True, "grid.alpha": 0.3})

#: shades of an engine without its own (:attr:`compare.runs.backends.Backend.shades`)
_DEFAULT_SHADES = ("#2ca02c", "#5fd35f", "#98df8a", "#145a14")
#: an engine's rungs in the order of its shades and line styles: the kinds every engine
#: runs, then its own elastic rod
_ENGINE_ORDER = (*ENGINE_KINDS, RungKind.ROD)
#: the analytic rungs' colour and line style
_REFERENCE_STYLES = {RungKind.NEWTON: {"color": "black", "ls": "-", "lw": 1.8},
                     RungKind.CONTACT: {"color": "#7f7f7f", "ls": "--", "lw": 1.6},
                     RungKind.BEAM: {"color": "#9467bd", "ls": "-", "lw": 1.6},
                     RungKind.BEAM_THEORY: {"color": "#8c564b", "ls": "-.", "lw": 1.4},
                     RungKind.CONVENTION: {"color": "#c5b0d5", "ls": "--", "lw": 1.4}}


def rung_style(rung) -> dict:
    """Colour and line style of a rung (by its kind and engine)."""
    if rung.kind in _REFERENCE_STYLES:
        return dict(_REFERENCE_STYLES[rung.kind])
    backend = BACKENDS.get(rung.backend)
    shades = (backend.shades if backend is not None else ()) or _DEFAULT_SHADES
    i = _ENGINE_ORDER.index(rung.kind)
    if i >= len(shades):
        shades = _DEFAULT_SHADES
    return {"color": shades[i], "ls": ("-", "-.", ":", "--")[i], "lw": 1.4}


class FigureFiles:
    """Writes figures as ``<directory>/<stem>.png`` and returns their path relative to the
    page (``prefix``): the page and report.md link to the same files."""

    def __init__(self, directory, prefix: str = "figures"):
        self.directory = Path(directory)
        self.prefix = prefix

    def __call__(self, fig, stem: str) -> str:
        name = re.sub(r"[^A-Za-z0-9._-]+", "-", stem) + ".png"
        self.directory.mkdir(parents=True, exist_ok=True)
        # every figure lays itself out (constrained layout, legends in its margins): no
        # tight bounding box, which draws the figure twice
        save_figure(fig, self.directory / name, DPI, format="png")  # titles fitted first
        plt.close(fig)
        return f"{self.prefix}/{name}"


def legend_right(target, handles=None, labels=None):
    """One legend to the right of the axes or figure ``target``, never on the data: of its
    own artists, or of ``handles`` with their ``labels`` when given."""
    if handles is None:
        handles, labels = target.get_legend_handles_labels()
    if not handles:
        return
    if isinstance(target, Figure):  # in the right margin constrained layout keeps for it
        target.legend(handles, labels, loc="outside right center", frameon=False)
    else:
        target.legend(handles, labels, loc="upper left", bbox_to_anchor=(1.01, 1.0),
                      borderaxespad=0, frameon=False)


def _ok_rungs(ladder):
    return [r for r in ladder.rungs if r.ok and r.result.trajectory is not None]


def _window_end(ladder, factor: float = 1.15) -> float:
    """Show the motion up to the separation (s), as the paper's Figs 4 and 5."""
    ref = ladder.rungs[0]
    t_sep = ref.values.get("t_sep", math.nan) if ref.ok else math.nan
    t_end = ladder.scenario.t_end
    return min(t_end, factor * t_sep) if math.isfinite(t_sep) else t_end


def _impact_window(ladder) -> float:
    """The impact process (s): up to 1.6 T0 of the slowest rung, at least 3 ms."""
    t0 = [r.values.get("T0", math.nan) for r in ladder.rungs if r.ok]
    t0 = [v for v in t0 if math.isfinite(v)]
    return max(3e-3, 1.6 * max(t0)) if t0 else 5e-3


def _reference(ladder):
    """The paper's model (rung 1) if it ran, else None."""
    ref = ladder.rungs[0]
    return ref if ref.ok and ref.result.trajectory is not None else None


def _family(rung) -> str:
    """'sdof' for a rung whose trunk is one degree of freedom (the pad on M_T: soft, the
    engines' slide joint), 'flexible' for the continuum and the hinged chains."""
    return "sdof" if rung.kind in (RungKind.NEWTON, RungKind.CONTACT, RungKind.ENGINE) \
        else "flexible"


def _panel_grid(subfig, n: int, ncol: int, **kw) -> list:
    """``n`` axes on a grid of ``ncol`` columns in ``subfig``, row by row; no unused axes."""
    return _family_grid(subfig, [n], ncol, **kw)[0]


def _family_grid(subfig, counts: list, ncol: int, **kw) -> tuple[list, list]:
    """Axes for groups of ``counts`` panels on a grid of ``ncol`` columns, each group
    starting a row of its own; returns (axes in order, the free cells (row, column) of the
    grid). ``kw``: sharex/sharey=True shares the first axes'."""
    rows = [math.ceil(n / ncol) for n in counts]
    grid = subfig.add_gridspec(max(1, sum(rows)), ncol)
    axes, free, row = [], [], 0
    for n, nr in zip(counts, rows):
        for i in range(n):
            share = {k: axes[0] for k, v in kw.items() if v and axes}
            axes.append(subfig.add_subplot(grid[row + i // ncol, i % ncol], **share))
        free += [(row + nr - 1, c) for c in range(n - (nr - 1) * ncol, ncol)] if n else []
        row += nr
    return axes, [(grid, r, c) for r, c in free]


def _same_ylim(axes, pad: float = 0.08, floor: float | None = None) -> None:
    """One y range over ``axes`` (their data's), padded by ``pad`` of the span."""
    lo = min(ax.dataLim.y0 for ax in axes)
    hi = max(ax.dataLim.y1 for ax in axes)
    if floor is not None:
        lo = min(lo, floor)
    span = (hi - lo) or max(abs(hi), 1e-9)
    for ax in axes:
        ax.set_ylim(lo - (0 if floor is not None and lo == floor else pad * span),
                    hi + pad * span)


def displacement_figure(ladder) -> Figure:
    """x(t) of the impact point and y(t) of the pendulum for every rung of ``ladder`` (Figs
    4, 5), then
    one small panel per rung with its difference from the paper's model (rung 1), in mm:
    x solid, y dashed; the 1-DOF trunks on one row and one scale, the flexible ones on
    others and their own scale (the continuum's x difference in grey behind each flexible
    rung, for comparison)."""
    t_hi = _window_end(ladder)
    ref = _reference(ladder)
    rungs = _ok_rungs(ladder)
    others = [r for r in rungs if r is not ref] if ref is not None else []
    groups = [[r for r in others if _family(r.rung) == f] for f in ("sdof", "flexible")]
    groups = [g for g in groups if g]
    ncol = 4
    nrow = sum(math.ceil(len(g) / ncol) for g in groups)
    fig = Figure(figsize=(11, 3.4 + 1.9 * nrow + (0.4 if nrow else 0)), layout="constrained")
    if nrow:
        top, low = fig.subfigures(2, 1, height_ratios=(3.4, 1.9 * nrow + 0.4))
    else:
        top, low = fig, None
    _displacements(top, ladder.name, rungs, t_hi)
    if low is None:
        return fig
    beam = next((r for r in rungs if r.rung.kind == RungKind.BEAM), None)
    axes, free = _family_grid(low, [len(g) for g in groups], ncol, sharex=True)
    panels = [r for g in groups for r in g]
    for ax, r in zip(axes, panels):
        _difference_panel(ax, r, ref.result.trajectory, beam, t_hi)
    start = 0
    for g in groups:  # one y scale per family
        _same_ylim(axes[start:start + len(g)])
        start += len(g)
    _difference_labels(axes)
    _difference_key(low, free, ref.rung.id)
    low.suptitle(f"Difference from the paper's model ({ref.rung.id}), one panel per rung",
                 fontsize=10)
    return fig


def _displacements(top, name: str, rungs: list, t_hi: float) -> None:
    """The top of :func:`displacement_figure` on the (sub)figure ``top``: x(t) and y(t) of
    every rung of ``rungs`` up to ``t_hi`` (s), in mm and ms, titled with the ladder's
    ``name`` and keyed by rung."""
    ax_x, ax_y = top.subplots(1, 2, sharex=True)
    for r in rungs:
        tr = r.result.trajectory
        sel = tr.t <= t_hi
        st = rung_style(r.rung)
        ax_x.plot(tr.t[sel] * 1e3, tr.x[sel] * 1e3, label=r.rung.id, **st)
        ax_y.plot(tr.t[sel] * 1e3, tr.y[sel] * 1e3, **st)
    ax_x.set(title="impact point of the trunk, x", ylabel="displacement x (mm)",
             xlabel="time t (ms)")
    ax_y.set(title="pendulum at the contact point, y", ylabel="displacement y (mm)",
             xlabel="time t (ms)")
    top.suptitle(f"{name}: displacement-time of every rung (the paper's Figs 4 and 5)",
                 fontsize=11)
    top.legend(*ax_x.get_legend_handles_labels(), loc="outside right upper", frameon=False,
               fontsize=8.5)


def _difference_panel(ax, r, rt, beam, t_hi: float) -> None:
    """Rung ``r``'s difference from the reference trajectory ``rt`` on ``ax`` up to
    ``t_hi`` (s), in mm: x solid, y dashed, the ``beam`` rung's x difference in grey behind
    a flexible rung (None: no beam rung)."""
    tr = r.result.trajectory
    sel = tr.t <= t_hi
    st = rung_style(r.rung)
    t_ms = tr.t[sel] * 1e3
    dx = (tr.x[sel] - np.interp(tr.t[sel], rt.t, rt.x)) * 1e3
    dy = (tr.y[sel] - np.interp(tr.t[sel], rt.t, rt.y)) * 1e3
    if _family(r.rung) == "flexible" and beam is not None and r is not beam:
        bt = beam.result.trajectory
        bs = bt.t <= t_hi
        ax.plot(bt.t[bs] * 1e3, (bt.x[bs] - np.interp(bt.t[bs], rt.t, rt.x)) * 1e3,
                color="0.72", lw=3.2, zorder=1)
    ax.axhline(0.0, color="black", lw=0.6)
    ax.plot(t_ms, dx, color=st["color"], lw=1.4, zorder=3)
    ax.plot(t_ms, dy, color=st["color"], lw=1.1, ls="--", zorder=3)
    big = max(float(np.max(np.abs(dx))), float(np.max(np.abs(dy)))) if sel.any() else 0
    ax.set_title(f"{r.rung.id}: up to {big:.2g} mm", fontsize=9)
    ax.tick_params(labelsize=8)


def _difference_labels(axes) -> None:
    """The difference panels' axis labels: y on the first column, time under the lowest
    panel of each column."""
    bottom = {}
    for ax in axes:
        ss = ax.get_subplotspec()
        bottom[ss.colspan.start] = ax
        if ss.colspan.start == 0:
            ax.set_ylabel("difference (mm)", fontsize=9)
    for ax in bottom.values():
        ax.set_xlabel("time t (ms)", fontsize=9)


def _difference_key(low, free: list, ref_id: str) -> None:
    """The difference panels' key on the subfigure ``low``: in its first ``free`` grid
    slot, else below; ``ref_id``: the reference rung's id."""
    key = [Line2D([], [], color="0.3", lw=1.4, label=f"x - x[{ref_id}], trunk"),
           Line2D([], [], color="0.3", lw=1.1, ls="--", label=f"y - y[{ref_id}], pendulum"),
           Line2D([], [], color="0.72", lw=3.2, label="x - x[analytic] of the beam rung")]
    if free:
        grid, r, c = free[0]
        kax = low.add_subplot(grid[r, c:])
        kax.set_axis_off()
        kax.legend(handles=key, loc="center left", frameon=False, fontsize=8.5,
                   title="y scales: one for the 1-DOF trunks (first row),\n"
                         "one for the flexible trunks (the rows below)",
                   title_fontsize=8.5)
    else:
        low.legend(handles=key, loc="outside lower center", ncol=3, frameon=False,
                   fontsize=8.5)


def force_figure(ladder) -> Figure:
    """The impact process of ``ladder``'s rungs over one time span for every panel: the
    paper's model's Newton
    impulses (N s) in the first panel, then the contact force (kN, linear: it goes to zero
    between the contacts) of each soft-contact rung in a panel of its own, the 1-DOF
    trunks on the first row and one scale, the flexible ones on the next rows and another;
    each panel names its peak and its number of contacts."""
    t_hi = _impact_window(ladder)
    newton = [r for r in ladder.rungs if r.ok and r.rung.kind == RungKind.NEWTON]
    soft = [r for r in ladder.rungs if r.ok and r.rung.kind != RungKind.NEWTON
            and r.result.trajectory is not None and r.result.trajectory.force is not None]
    groups = [newton + [r for r in soft if _family(r.rung) == "sdof"],
              [r for r in soft if _family(r.rung) == "flexible"]]
    groups = [g for g in groups if g] or [[]]
    ncol = 4
    nrow = sum(max(1, math.ceil(len(g) / ncol)) for g in groups)
    fig = Figure(figsize=(11, 2.2 * nrow + 0.6), layout="constrained")
    axes, _ = _family_grid(fig, [max(1, len(g)) for g in groups], ncol, sharex=True)
    families: dict = {}
    for ax, r in zip(axes, [r for g in groups for r in g]):
        if r.rung.kind == RungKind.NEWTON:
            _impulse_panel(ax, r, t_hi)
        else:
            _force_panel(ax, r, t_hi)
            families.setdefault(_family(r.rung), []).append(ax)
    for group in families.values():
        _same_ylim(group, floor=0.0)
    bottom = {}
    for ax in axes:  # from a little before t = 0: the first contact off the axis line
        ax.set_xlim(-0.03 * t_hi * 1e3, t_hi * 1e3)
        ax.tick_params(labelsize=8)
        bottom[ax.get_subplotspec().colspan.start] = ax
        first = ax.get_subplotspec().colspan.start == 0
        if not ax.get_ylabel() and (first or (newton and ax is axes[1])):
            ax.set_ylabel("contact force (kN)", fontsize=9)
    for ax in bottom.values():
        ax.set_xlabel("time t (ms)", fontsize=9)
    fig.suptitle(f"{ladder.name}: the impact process over its first {t_hi * 1e3:.3g} ms, one "
                 "panel per rung (force on a linear axis; one scale for the 1-DOF trunks, "
                 "one for the flexible ones)", fontsize=10)
    return fig


def _impulse_panel(ax, r, t_hi: float) -> None:
    """The paper's model's Newton impulses (N s) of rung result ``r`` up to ``t_hi`` s, with
    the first one's value and the count (those later than the window said)."""
    st = rung_style(r.rung)
    sol = r.result.solution
    imp = [(k.t, r.result.model["m"] * (k.u - k.v)) for k in (sol.impacts if sol else ())]
    shown = [(t, j) for t, j in imp if t <= t_hi]
    if shown:
        t, j = np.array(shown).T
        ax.vlines(t * 1e3, 0, j, color=st["color"], lw=1.4)
        ax.plot(t * 1e3, j, "o", color=st["color"], ms=4)
        ax.set_ylim(0, 1.25 * float(np.max(j)))  # every marker inside the axes
        ax.annotate(f"{j[0]:.3g} N s", (t[0] * 1e3, j[0]), xytext=(6, -2),
                    textcoords="offset points", fontsize=8, va="top")
    after = len(imp) - len(shown)
    ax.set_title(f"{r.rung.id}: Newton impulses", fontsize=9)
    ax.text(0.97, 0.95, f"{len(imp)} impulses" + (f"\n({after} later)" if after else ""),
            transform=ax.transAxes, ha="right", va="top", fontsize=8)
    ax.set_ylabel("impulse (N s)", fontsize=9)


def _force_panel(ax, r, t_hi: float) -> None:
    """Rung result ``r``'s contact force (kN) up to ``t_hi`` s, its peak and its contacts."""
    st = rung_style(r.rung)
    tr = r.result.trajectory
    sel = tr.t <= t_hi
    f_kn = tr.force[sel] / 1e3
    ax.fill_between(tr.t[sel] * 1e3, 0, f_kn, color=st["color"], alpha=0.25, lw=0)
    ax.plot(tr.t[sel] * 1e3, f_kn, color=st["color"], lw=1.0)
    peak = float(np.nanmax(f_kn)) if sel.any() else math.nan
    episodes = r.values.get("contact_episodes", math.nan)
    words = f"\n{episodes:.0f} contacts" if math.isfinite(episodes) else ""
    ax.set_title(r.rung.id, fontsize=9)
    ax.text(0.97, 0.95, f"peak {peak:.0f} kN{words}", transform=ax.transAxes,
            ha="right", va="top", fontsize=8)


def sequence_figure(ladder) -> Figure:
    """The impact sequence, one panel per rung of ``ladder`` (shared axes): trunk velocity vx
    and
    pendulum velocity vy over the impact process, T0 and V marked."""
    rungs = _ok_rungs(ladder)
    n = max(1, len(rungs))
    ncol = min(4, n)
    nrow = math.ceil(n / ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(11, 2.5 * nrow + 0.6), sharex=True,
                             sharey=True, squeeze=False, layout="constrained")
    t_hi = _impact_window(ladder)
    for ax, r in zip(axes.flat, rungs):
        st = rung_style(r.rung)
        tr = r.result.trajectory
        if r.rung.kind == RungKind.NEWTON and r.result.solution is not None:
            t = np.linspace(0.0, t_hi, 3000)
            _, vx, _, vy = r.result.solution.state(t)
        else:
            sel = tr.t <= t_hi
            t, vx, vy = tr.t[sel], tr.vx[sel], tr.vy[sel]
        ax.plot(t * 1e3, vx, color=st["color"], lw=1.5, label="trunk vx")
        ax.plot(t * 1e3, vy, color="0.45", lw=1.0, ls="--", label="pendulum vy")
        T0 = r.values.get("T0", math.nan)
        if math.isfinite(T0) and T0 <= t_hi:
            ax.plot([T0 * 1e3], [r.values["V"]], marker="v", color="black", ms=6,
                    ls="none", label="T0, V")
        ax.set_title(r.rung.id, fontsize=9.5)
    for ax in axes.flat[len(rungs):]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("time t (ms)")
    for ax in axes[:, 0]:
        ax.set_ylabel("velocity (m/s)")
    fig.suptitle(f"{ladder.name}: impact sequence, one panel per rung")
    legend_right(fig, *axes.flat[0].get_legend_handles_labels())
    return fig
