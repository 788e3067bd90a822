"""The answer's figure of the small-e half: each approximation's error against e, one panel
per tree (compare.studies.small_e; the report's first section)."""

from __future__ import annotations

import math

import numpy as np

from .figures import legend_right, plt

#: Line styles of the approximations (compare.studies.small_e.APPROXIMATIONS), in its order.
_STYLES = {"eq57_energy_loss": ("o-", "tab:red"),
           "eq58_energy_transferred": ("s-", "tab:orange"),
           "identification_M_T": ("^-", "tab:blue"),
           "identification_K_T": ("v-", "tab:cyan"),
           "identification_pair_damping_ratio": ("D-", "tab:green"),
           "eq45_area": ("P-", "tab:purple"),
           "one_dof_x_max": ("x--", "black"),
           "one_dof_energy_delivered": ("*--", "0.45")}


def small_e_figure(trees: dict, tolerance: float):
    """Per tree of ``trees`` (tree -> its small-e answers,
    :func:`compare.studies.small_e.small_e_answer`), every approximation's relative error (%)
    against e on the grid, the
    +-``tolerance`` band, the tree's own e (dotted) and where each holds up to (a tick on
    the band's edge); symmetric-log y so that -3 % and +300 % both read. An e where an
    approximation has no value (the procedure refused the record, the bodies never moved
    together) is a gap in its line."""
    names = list(trees)
    fig, axes = plt.subplots(1, len(names), figsize=(4.3 * len(names) + 2.4, 4.6),
                             sharey=True, squeeze=False, layout="constrained")
    tol = 100 * tolerance
    for ax, name in zip(axes[0], names):
        answers = trees[name]
        ax.axhspan(-tol, tol, color="0.85", lw=0)
        e_tree = None
        for key, a in answers.items():
            mk, colour = _STYLES.get(key, (".-", None))
            e = np.asarray(a["e_grid"], float)
            y = 100 * np.array([v if v is not None else math.nan for v in a["errors"]], float)
            ax.plot(e, y, mk, color=colour, ms=3.5, lw=1.1, label=a["label"])
            if a["bracket"] is not None:  # on the side it leaves by
                out = next((v for v in y if not abs(v) <= tol), tol)
                ax.plot([a["holds_up_to_e"]], [-tol if out < 0 else tol], "|", ms=14,
                        mew=2.2, color=colour)
            e_tree = a["e"]
        if e_tree is not None:
            ax.axvline(e_tree, color="k", lw=0.9, ls=":")
            ax.annotate(f"this tree's e = {e_tree:g}", (e_tree, 0.98),
                        xycoords=("data", "axes fraction"), ha="left", va="top",
                        fontsize=8, xytext=(3, 0), textcoords="offset points")
        ax.set_yscale("symlog", linthresh=10)
        ticks = [-100, -30, -10, -5, 0, 5, 10, 30, 100, 300]
        ax.set_yticks(ticks, [f"{t:+d}" if t else "0" for t in ticks])
        ax.set_ylim(-110, 500)
        ax.set(title=name, xlabel="coefficient of restitution e (1)", xlim=(-0.02, 0.92))
    axes[0][0].set_ylabel("error against the exact result (%)")
    legend_right(axes[0][-1])
    fig.suptitle(f"Does 'e is small' hold? Grey band +-{tol:.0f} %; a tick on its edge: the "
                 "largest e up to which a line stays inside; dashed: the 1-DOF trunk's own "
                 "gap, which e does not remove", fontsize=10)
    return fig
