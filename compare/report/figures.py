"""Figures of the report (matplotlib, Agg backend), returned as base64 PNG data URIs.

Every axis carries its quantity and unit. Rungs keep one colour and line style across all
figures of a scenario (:func:`rung_style`).
"""

from __future__ import annotations

import base64
import io
import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from compare.backends import BACKENDS  # noqa: E402

DPI = 110
plt.rcParams.update({"font.size": 10, "axes.titlesize": 11, "axes.labelsize": 10,
                     "legend.fontsize": 8.5, "axes.grid": True, "grid.alpha": 0.3})

#: shades of an engine without its own (:attr:`compare.backends.Backend.shades`)
_DEFAULT_SHADES = ("#2ca02c", "#5fd35f", "#98df8a")


def rung_style(rung) -> dict:
    """Colour and line style of a rung (by its kind and engine)."""
    if rung.kind == "newton":
        return {"color": "black", "ls": "-", "lw": 1.8}
    if rung.kind == "contact":
        return {"color": "#7f7f7f", "ls": "--", "lw": 1.6}
    backend = BACKENDS.get(rung.backend)
    shades = (backend.shades if backend is not None else ()) or _DEFAULT_SHADES
    i = {"engine": 0, "trunk": 1, "pendulum": 2}[rung.kind]
    return {"color": shades[i], "ls": ("-", "-.", ":")[i], "lw": 1.4}


def to_data_uri(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI, bbox_inches="tight")
    plt.close(fig)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


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


def displacement_figure(ladder) -> str:
    """x(t) of the impact point and y(t) of the pendulum for every rung (Figs 4, 5)."""
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10.5, 3.8))
    t_hi = _window_end(ladder)
    for r in _ok_rungs(ladder):
        tr = r.result.trajectory
        sel = tr.t <= t_hi
        st = rung_style(r.rung)
        ax1.plot(tr.t[sel] * 1e3, tr.x[sel] * 1e3, label=r.rung.id, **st)
        ax2.plot(tr.t[sel] * 1e3, tr.y[sel] * 1e3, label=r.rung.id, **st)
    ax1.set(title="impact point of the trunk", xlabel="time t (ms)", ylabel="displacement (mm)")
    ax2.set(title="pendulum at the contact point", xlabel="time t (ms)", ylabel="displacement (mm)")
    ax1.legend(loc="best")
    fig.suptitle(f"{ladder.name}: displacement-time, every rung", y=1.02)
    return to_data_uri(fig)


def force_figure(ladder) -> str:
    """Contact force (kN) of the soft-contact rungs; Newton impulses (N s) as stems."""
    fig, ax = plt.subplots(figsize=(10.5, 3.6))
    t_hi = _impact_window(ladder)
    twin = None
    for r in [r for r in ladder.rungs if r.ok]:
        st = rung_style(r.rung)
        if r.rung.kind == "newton":
            sol = r.result.extra.get("solution")
            if sol is None or not sol.impacts:
                continue
            imp = [(i.t, r.result.model["m"] * (i.u - i.v)) for i in sol.impacts if i.t <= t_hi]
            if imp:
                twin = ax.twinx()
                t, j = np.array(imp).T
                twin.vlines(t * 1e3, 0, j, color="black", lw=1.2)
                twin.plot(t * 1e3, j, "ko", ms=4, label=f"{r.rung.id}: impulses")
                twin.set_ylabel("Newton impulse (N s)")
                twin.set_ylim(bottom=0)
                twin.grid(False)
                twin.legend(loc="center right")
            continue
        tr = r.result.trajectory
        if tr is None or tr.force is None:
            continue
        sel = tr.t <= t_hi
        ax.plot(tr.t[sel] * 1e3, tr.force[sel] / 1e3, label=r.rung.id, **st)
    peaks = [float(np.nanmax(ln.get_ydata())) for ln in ax.get_lines() if len(ln.get_ydata())]
    if peaks and max(peaks) > 0:  # the first collision peaks ~100 times the later force
        ax.set_yscale("log")
        ax.set_ylim(max(peaks) * 1e-5, max(peaks) * 2)
    ax.set(title=f"{ladder.name}: contact force during the impact process (log scale)",
           xlabel="time t (ms)", ylabel="contact force on the trunk (kN)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=4)
    return to_data_uri(fig)


def sequence_figure(ladder) -> str:
    """The impact sequence: velocities of trunk (vx) and pendulum (vy) over the impact
    process, Newton impacts marked, T0 of each rung as a tick."""
    fig, ax = plt.subplots(figsize=(10.5, 3.8))
    t_hi = _impact_window(ladder)
    for r in _ok_rungs(ladder):
        st = rung_style(r.rung)
        tr = r.result.trajectory
        if r.rung.kind == "newton" and "solution" in r.result.extra:
            sol = r.result.extra["solution"]
            t = np.linspace(0.0, t_hi, 3000)
            _, vx, _, vy = sol.state(t)
        else:
            sel = tr.t <= t_hi
            t, vx, vy = tr.t[sel], tr.vx[sel], tr.vy[sel]
        ax.plot(t * 1e3, vx, label=f"{r.rung.id}: trunk", **st)
        ax.plot(t * 1e3, vy, alpha=0.55, **{**st, "lw": st["lw"] * 0.8})
        T0 = r.values.get("T0", math.nan)
        if math.isfinite(T0) and T0 <= t_hi:
            ax.plot([T0 * 1e3], [r.values["V"]], marker="v", color=st["color"], ms=7)
    ax.set(title=f"{ladder.name}: impact sequence (thick: trunk vx, faint: pendulum vy; "
                 "triangles: T0, V)", xlabel="time t (ms)", ylabel="velocity (m/s)")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    return to_data_uri(fig)


LEDGER_TERMS = ("kinetic", "potential", "damping", "impact loss", "energy transferred")


def energy_figure(ledgers: dict, initial_energy: float, name: str) -> str:
    """Energy ledger bars (J) per rung: at T0, kinetic, potential, damping work and impact
    loss sum to the initial energy; the energy transferred (eq 58) is shown beside them."""
    rungs = list(ledgers)
    fig, ax = plt.subplots(figsize=(10.5, 3.8))
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
    ax.annotate(f"initial energy {initial_energy:.0f} J", (n - 0.5, initial_energy),
                ha="right", va="bottom", fontsize=8.5)
    ax.set_xticks(x, [f"{k}\n(at T0)" if k != "energy transferred" else "energy transferred\n(eq 58)"
                      for k in LEDGER_TERMS])
    ax.set(title=f"{name}: energy ledger at T0", ylabel="energy (J)")
    ax.legend(loc="upper left", ncol=2)
    return to_data_uri(fig)


def identification_figure(sweep: list[dict], name: str, tolerances: dict) -> str:
    """Identification error against e (exact solver records), with the procedure's floor."""
    fig, ax = plt.subplots(figsize=(10.5, 3.6))
    es = [s["e"] for s in sweep]
    for key, st in (("M_T", "o-"), ("K_T", "s-"), ("xi", "^-")):
        ax.plot(es, [100 * s["errors"].get(key, math.nan) for s in sweep], st, label=key)
        tol = tolerances.get("identification", {}).get(key, {}).get("rel")
        if tol:
            ax.axhspan(-100 * tol, 100 * tol, alpha=0.06, color=ax.lines[-1].get_color())
    ax.axhline(0, color="black", lw=0.8)
    ax.set(title=f"{name}: identification (eqs 39-48, paper reading) on exact records vs e "
                 "(bands: tolerances)",
           xlabel="coefficient of restitution e (1)", ylabel="error (identified - true) (%)")
    ax.legend(loc="best")
    return to_data_uri(fig)


def image_figure(path) -> str:
    """A study's own PNG or SVG figure, embedded as it is."""
    from pathlib import Path

    p = Path(path)
    mime = "image/svg+xml" if p.suffix.lower() == ".svg" else "image/png"
    return f"data:{mime};base64," + base64.b64encode(p.read_bytes()).decode("ascii")
