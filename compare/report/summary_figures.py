"""The report's summary figures (matplotlib, Agg backend, as :mod:`.figures`): the energy
ledger at T0 per rung, and the contact scan (the continuum's gap to the 1-DOF model against
the pad's contact duration, per tree).
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure

from .figures import legend_right, plt

#: The energy ledger's terms (J) in the order the bars are drawn.
LEDGER_TERMS = ("kinetic", "potential", "damping", "impact loss", "energy transferred")


def energy_figure(ledgers: dict, initial_energy: float, name: str) -> Figure:
    """Energy ledger bars (J) per rung of ``ledgers`` (rung id -> {terms, style}) of the
    scenario ``name``: at T0, kinetic, potential, damping work and impact loss sum to the
    ``initial_energy`` (J, a dashed line); the energy transferred (eq 58) is shown beside
    them."""
    rungs = list(ledgers)
    fig, ax = plt.subplots(figsize=(11, 3.8), layout="constrained")
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
    ax.set_xticks(x, [f"{k}\n(at T0)" if k != "energy transferred"
                      else "energy transferred\n(eq 58)" for k in LEDGER_TERMS])
    ax.set(title=f"{name}: energy ledger at T0", ylabel="energy (J)")
    legend_right(ax)
    return fig


def contact_scan_figure(scans: dict, shipped: dict | None = None) -> Figure:
    """Per scenario of ``scans`` (name -> :func:`compare.studies.contact_scan.scan_result`), the
    continuum's gap to the 1-DOF model (%, beam vs soft SDOF, same pad)
    against the contact duration (ms, log), with the +-tolerance band: where the 1-DOF model
    is good enough; ``shipped``: the scenario's own pad ({name: duration in s}), marked.
    Symmetric-log y so that +200 % and -3 % both read."""
    names = list(scans)
    fig, axes = plt.subplots(2, len(names), figsize=(4.2 * len(names) + 1.6, 6.2),
                             sharey="row", sharex=True, squeeze=False,
                             gridspec_kw={"height_ratios": [3, 2]}, layout="constrained")
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
        own = (shipped or {}).get(name)
        if own:
            for a in (ax, axes[1][list(names).index(name)]):
                a.axvline(1e3 * own, color="k", lw=1.6, alpha=0.55)
            ax.annotate(f"this tree's\npad, {1e3 * own:g} ms", (1e3 * own, 0.0),
                        xytext=(4, 0), textcoords="offset points", fontsize=8,
                        va="center")
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
    legend_right(axes[0][-1])
    legend_right(axes[1][-1])
    fig.suptitle(f"Where the 1-DOF model holds: grey band +-{tol:.0f} %, dotted lines the "
                 "shortest pad from which it stays inside, solid grey the tree's own pad; "
                 "below, how long the first contact really lasts", fontsize=10)
    return fig
