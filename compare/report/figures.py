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

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from treeimpact.compare.backends import BACKENDS  # noqa: E402
from treeimpact.compare.rungs import ENGINE_KINDS, RungKind  # noqa: E402

DPI = 110
plt.rcParams.update({"font.size": 10, "axes.titlesize": 11, "axes.labelsize": 10,
                     "legend.fontsize": 9, "axes.grid": True, "grid.alpha": 0.3})

#: shades of an engine without its own (:attr:`compare.backends.Backend.shades`)
_DEFAULT_SHADES = ("#2ca02c", "#5fd35f", "#98df8a")
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
    i = ENGINE_KINDS.index(rung.kind)
    return {"color": shades[i], "ls": ("-", "-.", ":")[i], "lw": 1.4}


class FigureFiles:
    """Writes figures as ``<directory>/<stem>.png`` and returns their path relative to the
    page (``prefix``): the page and report.md link to the same files."""

    def __init__(self, directory, prefix: str = "figures"):
        self.directory = Path(directory)
        self.prefix = prefix

    def __call__(self, fig, stem: str) -> str:
        name = re.sub(r"[^A-Za-z0-9._-]+", "-", stem) + ".png"
        self.directory.mkdir(parents=True, exist_ok=True)
        fig.savefig(self.directory / name, format="png", dpi=DPI, bbox_inches="tight")
        plt.close(fig)
        return f"{self.prefix}/{name}"


def _legend_right(target, handles=None, labels=None):
    """One legend to the right of the axes or figure ``target``, never on the data."""
    if handles is None:
        handles, labels = target.get_legend_handles_labels()
    if not handles:
        return
    if isinstance(target, Figure):
        target.legend(handles, labels, loc="center left", bbox_to_anchor=(1.0, 0.5),
                      frameon=False)
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


def displacement_figure(ladder) -> Figure:
    """x(t) of the impact point and y(t) of the pendulum for every rung (Figs 4, 5), and
    below each the rung's difference from the paper's model (rung 1), in mm."""
    fig, axes = plt.subplots(2, 2, figsize=(11, 6.2), sharex=True,
                             gridspec_kw={"height_ratios": (3, 2)})
    t_hi = _window_end(ladder)
    ref = _reference(ladder)
    for r in _ok_rungs(ladder):
        tr = r.result.trajectory
        sel = tr.t <= t_hi
        st = rung_style(r.rung)
        t_ms = tr.t[sel] * 1e3
        for col, (z, zref) in enumerate(((tr.x, "x"), (tr.y, "y"))):
            axes[0, col].plot(t_ms, z[sel] * 1e3, label=r.rung.id, **st)
            if ref is not None and r is not ref:
                rt = ref.result.trajectory
                base = np.interp(tr.t[sel], rt.t, getattr(rt, zref))
                axes[1, col].plot(t_ms, (z[sel] - base) * 1e3, **st)
    axes[0, 0].set(title="impact point of the trunk, x", ylabel="displacement x (mm)")
    axes[0, 1].set(title="pendulum at the contact point, y", ylabel="displacement y (mm)")
    ref_id = ref.rung.id if ref is not None else "rung 1"
    axes[1, 0].set(xlabel="time t (ms)", ylabel=f"x - x[{ref_id}] (mm)")
    axes[1, 1].set(xlabel="time t (ms)", ylabel=f"y - y[{ref_id}] (mm)")
    for ax in axes[1]:
        ax.axhline(0.0, color="black", lw=0.8)
    fig.suptitle(f"{ladder.name}: displacement-time of every rung (top) and its difference "
                 f"from the paper's model (bottom)", y=1.0)
    _legend_right(fig, *axes[0, 0].get_legend_handles_labels())
    fig.tight_layout()
    return fig


def force_figure(ladder) -> Figure:
    """Contact force (kN, log axis) of the soft-contact rungs over the impact process; the
    paper's model's Newton impulses (N s) in a panel of their own."""
    fig, (ax, ax_imp) = plt.subplots(1, 2, figsize=(11, 3.8),
                                     gridspec_kw={"width_ratios": (3, 1.2)})
    t_hi = _impact_window(ladder)
    peak = 0.0
    for r in [r for r in ladder.rungs if r.ok]:
        st = rung_style(r.rung)
        if r.rung.kind == RungKind.NEWTON:
            sol = r.result.solution
            imp = [(i.t, r.result.model["m"] * (i.u - i.v)) for i in (sol.impacts if sol else ())
                   if i.t <= t_hi]
            if imp:
                t, j = np.array(imp).T
                ax_imp.vlines(t * 1e3, 0, j, color=st["color"], lw=1.2)
                ax_imp.plot(t * 1e3, j, "o", color=st["color"], ms=4,
                            label=f"{r.rung.id}: impulses")
            continue
        tr = r.result.trajectory
        if tr is None or tr.force is None:
            continue
        sel = tr.t <= t_hi
        ax.plot(tr.t[sel] * 1e3, tr.force[sel] / 1e3, label=r.rung.id, **st)
        peak = max(peak, float(np.nanmax(tr.force[sel] / 1e3)) if sel.any() else 0.0)
    if peak > 0:  # the first collision peaks ~100 times the later force: log axis
        ax.set_yscale("log")
        ax.set_ylim(peak * 1e-5, peak * 2)
    ax.set(title="contact force, soft-contact rungs (log axis)", xlabel="time t (ms)",
           ylabel="contact force on the trunk (kN)")
    ax_imp.set(title="Newton impulses, the paper's model", xlabel="time t (ms)",
               ylabel="impulse (N s)")
    ax_imp.set_ylim(bottom=0)
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = ax_imp.get_legend_handles_labels()
    fig.suptitle(f"{ladder.name}: the impact process", y=1.0)
    fig.tight_layout()
    _legend_right(fig, h1 + h2, l1 + l2)
    return fig


def sequence_figure(ladder) -> Figure:
    """The impact sequence, one panel per rung (shared axes): trunk velocity vx and
    pendulum velocity vy over the impact process, T0 and V marked."""
    rungs = _ok_rungs(ladder)
    n = max(1, len(rungs))
    ncol = min(4, n)
    nrow = math.ceil(n / ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(11, 2.5 * nrow + 0.6), sharex=True,
                             sharey=True, squeeze=False)
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
    fig.suptitle(f"{ladder.name}: impact sequence, one panel per rung", y=1.0)
    fig.tight_layout()
    _legend_right(fig, *axes.flat[0].get_legend_handles_labels())
    return fig


LEDGER_TERMS = ("kinetic", "potential", "damping", "impact loss", "energy transferred")


def energy_figure(ledgers: dict, initial_energy: float, name: str) -> Figure:
    """Energy ledger bars (J) per rung: at T0, kinetic, potential, damping work and impact
    loss sum to the initial energy; the energy transferred (eq 58) is shown beside them."""
    rungs = list(ledgers)
    fig, ax = plt.subplots(figsize=(11, 3.8))
    n = len(LEDGER_TERMS)
    width = 0.8 / max(1, len(rungs))
    x = np.arange(n)
    for i, rid in enumerate(rungs):
        vals = [ledgers[rid]["terms"].get(k, math.nan) for k in LEDGER_TERMS]
        st = ledgers[rid]["style"]
        ax.bar(x + (i - (len(rungs) - 1) / 2) * width, vals, width, label=rid,
               color=st["color"], edgecolor="black", lw=0.4,
               hatch={"-": None, "--": "//", "-.": "..", ":": "xx"}[st["ls"]])
    ax.axhline(initial_energy, color="black", lw=0.8, ls="--")
    ax.set_ylim(top=1.12 * max(initial_energy, ax.get_ylim()[1]))  # room for the label
    ax.annotate(f"initial energy {initial_energy:.0f} J", (n - 0.5, initial_energy),
                ha="right", va="bottom", fontsize=9)
    ax.set_xticks(x, [f"{k}\n(at T0)" if k != "energy transferred" else "energy transferred\n(eq 58)"
                      for k in LEDGER_TERMS])
    ax.set(title=f"{name}: energy ledger at T0", ylabel="energy (J)")
    _legend_right(ax)
    return fig


def identification_figure(sweep: list[dict], name: str, tolerances: dict) -> Figure:
    """Identification error against e (exact solver records), with the procedure's floor."""
    fig, ax = plt.subplots(figsize=(11, 3.6))
    es = [s["restitution"] for s in sweep]
    for key, st in (("M_T", "o-"), ("K_T", "s-"), ("xi", "^-")):
        ax.plot(es, [100 * s["errors"].get(key, math.nan) for s in sweep], st, label=key)
        tol = tolerances.get("identification", {}).get(key, {}).get("rel")
        if tol:
            ax.axhspan(-100 * tol, 100 * tol, alpha=0.06, color=ax.lines[-1].get_color())
    ax.axhline(0, color="black", lw=0.8)
    ax.set(title=f"{name}: identification (eqs 39-48, paper reading) on exact records vs e "
                 "(bands: tolerances)",
           xlabel="coefficient of restitution e (1)", ylabel="error (identified - true) (%)")
    _legend_right(ax)
    return fig


def contact_scan_figure(scans: dict) -> Figure:
    """Per scenario, the continuum's gap to the 1-DOF model (%, beam vs soft SDOF, same pad)
    against the contact duration (ms, log), with the +-tolerance band: where the 1-DOF model
    is good enough. Symmetric-log y so that +200 % and -3 % both read."""
    names = list(scans)
    fig, axes = plt.subplots(2, len(names), figsize=(4.2 * len(names) + 1.6, 6.2),
                             sharey="row", sharex=True, squeeze=False,
                             gridspec_kw={"height_ratios": [3, 2]})
    styles = {"x_max": ("o-", "tab:blue", "x_max"),
              "energy_delivered": ("s-", "tab:red", "energy delivered"),
              "crown_peak_acceleration": ("^-", "tab:green", "crown accel. (mean over t_c)")}
    for ax, name in zip(axes[0], names):
        s = scans[name]
        d = 1e3 * np.asarray(s["durations"])
        tol = 100 * s["tolerance"]
        ax.axhspan(-tol, tol, color="0.85", lw=0)
        for metric, gaps in s["gaps"].items():
            mk, colour, label = styles.get(metric, (".-", None, metric))
            ax.plot(d, 100 * np.asarray(gaps, float), mk, color=colour, ms=4, label=label)
            if s["shortest"].get(metric) is not None:
                ax.axvline(1e3 * s["shortest"][metric], color=colour, lw=0.8, ls=":")
        ax.set_xscale("log")
        ax.set_yscale("symlog", linthresh=10)
        ticks = [-100, -30, -10, -5, 0, 5, 10, 30, 100, 300]
        ax.set_yticks(ticks, [f"{t:+d}" if t else "0" for t in ticks])
        ax.set(title=name)
        ax.grid(True, which="major", lw=0.3)
        low = axes[1][list(names).index(name)]  # what the pad does against each clamp
        for rung, mk, label in (("soft", "o--", "1-DOF (M_T)"), ("beam", "s-", "continuum")):
            c = s.get("contact", {}).get(rung)
            if c:
                low.plot(d, 1e3 * np.asarray(c["first_contact_duration"], float), mk,
                         color="0.3" if rung == "soft" else "tab:purple", ms=3,
                         label=f"first contact, {label}")
        low.plot(d, d, ":", color="0.6", lw=0.8, label="= the pad's 1-DOF time")
        low.set_xscale("log")
        low.set_yscale("log")
        low.set(xlabel="the pad: its collision time on the 1-DOF pair (ms)")
        low.grid(True, which="major", lw=0.3)
    axes[0][0].set_ylabel("continuum vs 1-DOF (%)")
    axes[1][0].set_ylabel("first contact, touch to\nrelease (ms)")
    _legend_right(axes[0][-1])
    _legend_right(axes[1][-1])
    fig.suptitle(f"Where the 1-DOF model holds: grey band +-{tol:.0f} %, dotted lines the "
                 "shortest pad from which it stays inside; below, how long the first contact "
                 "really lasts", fontsize=10)
    fig.tight_layout()
    return fig
