"""The sensitivity study's figure: which unmeasured input moves each answer, as Morris mu*
with SALib's 95 % interval per input, one panel per tree (compare.studies.sensitivity).
"""

from __future__ import annotations

from pathlib import Path

from treeimpact.analytic.model.registry import BY_NAME
from treeimpact.compare.runs.figure_text import save_figure

#: Short labels of the sensitivity study's inputs and outputs on its figure: an input's is
#: the registry's label on two lines (analytic.model.registry).
INPUT_LABELS = {n: "\n".join(BY_NAME[n].label.rsplit(" ", 1))
                for n in ("clamp_mass", "e_over_g", "log10_pad_duration", "restitution",
                          "root_share", "density", "damping_ratio", "youngs_modulus")}
OUTPUT_LABELS = {"gap.x_max": "x_max gap", "gap.energy_delivered": "energy gap",
                  "gap.crown_peak": "crown peak gap",
                  "gap.crown_peak_acceleration": "crown accel. gap",
                  "gap.peak_force": "force gap", "crossing.x_max": "crossing, x_max",
                  "crossing.energy_delivered": "crossing, energy"}
#: The bars' colours, one per unmeasured input of :data:`INPUT_LABELS`, in its order (the
#: damping ratio's and E's only on a tree from its geometry, compare.studies.sensitivity).
_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown",
            "tab:pink", "tab:olive")


def sensitivity_figure(trees: dict, path: Path) -> Path | None:
    """One panel per tree of ``trees`` (name -> :func:`compare.studies.sensitivity.analyse`; a
    second row for the crossing durations): each output's Morris
    mu* per unmeasured input as a bar, its 95 % interval (SALib's mu_star_conf) as a
    whisker, the inputs that decide it outlined; a held (measured) input has no bar.
    Written to ``path``; returns it, or None when no tree has an output."""
    # lazy: +279 ms at import otherwise (matplotlib, numpy),
    # which this module's other callers do not need
    from matplotlib.figure import Figure

    # lazy: +129 ms at import otherwise (matplotlib, numpy),
    # which this module's other callers do not need
    from matplotlib.patches import Patch

    trees = {n: t for n, t in trees.items() if t.get("outputs")}
    if not trees:
        return None
    names = list(trees)
    outputs = list(dict.fromkeys(o for t in trees.values() for o in t["outputs"]))
    groups = [g for g in ([o for o in outputs if o.startswith("gap.")],
                          [o for o in outputs if o.startswith("crossing.")]) if g]
    inputs = [i for i in INPUT_LABELS  # those some tree varies or holds
              if any(i in o["indices"] for t in trees.values() for o in t["outputs"].values())
              or any(i in t.get("held", {}) for t in trees.values())]
    colours = {i: c for i, c in zip(INPUT_LABELS, _COLOURS) if i in inputs}
    fig = Figure(figsize=(3.4 * len(names) + 2.4, 0.85 * len(outputs) + 1.9),
                 layout="constrained")
    axes = fig.subplots(len(groups), len(names), squeeze=False, sharex="row", sharey="row",
                        gridspec_kw={"height_ratios": [len(g) for g in groups]})
    for col, name in enumerate(names):
        for row, group in enumerate(groups):
            _panel(axes[row][col], trees[name]["outputs"], group, colours,
                   name if row == 0 else None)
    handles = [Patch(color=colours[i], label=INPUT_LABELS[i].replace("\n", " "))
               for i in inputs]
    handles.append(Patch(facecolor="white", edgecolor="k", label="outlined: decides it\n"
                         "(several: not separable)"))
    fig.legend(handles=handles, loc="outside right center", fontsize=8.5, frameon=False)
    first = next(iter(trees.values()))
    short = [f"{n} {t['trajectories_used']}" for n, t in trees.items()
             if t.get("trajectories_used", t.get("trajectories")) != t.get("trajectories")]
    fig.suptitle(f"Which unmeasured input moves each answer: Morris mu* with its "
                 f"{100 * first.get('conf_level', 0.95):.0f} % interval (whiskers), "
                 f"{first.get('trajectories', '?')} trajectories per tree"
                 + (f" (complete, with no failed point: {', '.join(short)})" if short else ""),
                 fontsize=10)
    path = Path(path)

    save_figure(fig, path, 100)
    return path


def _panel(ax, outputs: dict, group: list[str], colours: dict, title: str | None) -> None:
    """One tree's panel on ``ax``: for each output of ``group`` (gaps in percentage points,
    or crossing durations in decades) in the tree's ``outputs``, a bar of mu* per input in
    its ``colours``, its interval as a whisker, the deciding inputs outlined; ``title``: the
    tree's name on the top row."""
    inputs = list(colours)
    h = 0.8 / len(inputs)
    scale = 100.0 if group[0].startswith("gap.") else 1.0
    for j, o in enumerate(group):
        out = outputs.get(o)
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
    if title is not None:
        ax.set_title(title, fontsize=10)
    ax.set_xlabel("mu* (percentage points of the gap)" if scale == 100.0 else
                  "mu* (decades of the crossing duration)", fontsize=8.5)
