"""Speed-accuracy curves per engine (after Erez, Tassa and Todorov 2015).

For each engine and each of its variants (MuJoCo integrators, Bullet contact modes; from
:attr:`compare.runs.backends.Backend.variants`) the scenario's engine-numerics model (SDOF trunk, linear pendulum: :data:`SPEED_ENGINE_OPTIONS`)
is run over a range of time steps ``dt`` (s) and contact stiffnesses ``k_c``
(N/m). Each run gives a point:

* cost: wall time of the backend call per simulated second (s/s), measured in this process,
  one run after the other after a warm-up run, so that runs do not compete for cores and
  the first one does not pay the imports;
* error vs the reference of the same model: max over :data:`SPEED_METRICS` of
  |engine - soft| / |soft|, with the analytic soft-contact solution (``soft``, DOP853 at
  rtol 1e-11) at the same k_c: the integration error of the engine;
* error vs the paper: the same against the exact Newton solution (``analytic``), which
  also contains the contact model's error and shrinks as k_c grows.

Curves connect the time steps of one (variant, k_c). A variant whose option the engine does
not have (yet) is not run: it is listed in ``skipped`` with the reason; an engine that is
not installed likewise. The sweep behind a curve is an ordinary sweep directory (resumable).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from treeimpact.analytic.contact.law import stiffness_for_duration
from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.two_body import two_body_model
from treeimpact.compare.runs.backends import ENGINES, get_backend
from treeimpact.compare.runs.cache import resolve_scenario
from treeimpact.compare.runs.figure_text import save_figure

from ..runs.cache import OK
from .sweep.grid import OPTION, Axis, Grid, GridTarget, resolve_parameter
from .sweep.journal import read_table
from .sweep.run import run_sweep

#: Metrics of the error: those the contact model itself changes by at most b t_c
#: (tolerances.toml [step.contact]), so the error against the paper can go to zero as the
#: contact stiffens; T0, x0 and V depend on where each model puts "moving together".
SPEED_METRICS = ("x_max", "t_xmax", "t_sep", "impact_loss", "energy_transferred", "theta_b")

#: The engine model of the curves: the engine-numerics rung (SDOF trunk, linear pendulum),
#: whose exact reference is the analytic soft-contact solution.
SPEED_ENGINE_OPTIONS = {"trunk": "sdof", "pendulum": "linear"}

def rounded_stiffness(scenario, duration: float) -> float:
    """k_c (N/m, 3 digits) whose undamped two-body collision lasts ``duration`` s
    (:func:`analytic.contact.law.stiffness_for_duration` on the scenario's reduced mass)."""
    return float(f"{stiffness_for_duration(two_body_model(scenario).reduced_mass, duration):.3g}")


def engine_variants(engine: str) -> tuple[str | None, tuple, str | None, bool]:
    """(option name or None, values, reason when the variants cannot be run, whether the
    engine runs at all)."""
    try:
        backend = get_backend(engine)
        accepted = backend.options()
    except ParameterError as exc:
        return None, (), str(exc), False
    name, values = backend.variants or (None, ())
    if name is None:
        return None, (), None, True
    if name not in accepted:
        return None, (), (f"{engine}: its simulate() has no {name!r} option yet, so the "
                          f"{', '.join(values)} curves are not run (one default curve "
                          f"instead)"), True
    return name, values, None, True


def speed_sweep(scenario, out, *, engines=ENGINES, dts=(1e-4, 3e-5, 1e-5),
                stiffnesses=None, durations=(1e-3, 5e-4), workers: int = 1, scheduler=None,
                progress=None) -> dict:
    """Run the speed-accuracy sweeps of ``scenario`` (one sweep directory per engine of
    ``engines`` under ``out``): every time step of ``dts`` (s) with every contact stiffness.
    ``workers`` and ``scheduler`` are not used (each engine's sweep runs in this process,
    on its engine's own threads); ``progress`` is passed on.

    ``stiffnesses`` (N/m) or, when None, ``durations`` (s) converted with
    :func:`rounded_stiffness`. Returns {"engines": {engine: sweep dir}, "skipped":
    [{"engine", "reason"}], "stiffnesses": [...], "dts": [...]}.
    """
    scen = resolve_scenario(scenario)
    out = Path(out)
    if stiffnesses is None:
        stiffnesses = tuple(rounded_stiffness(scen, d) for d in durations)
    result = {"engines": {}, "skipped": [], "stiffnesses": [float(k) for k in stiffnesses],
              "dts": [float(d) for d in dts]}
    for eng in engines:
        name, values, reason, runnable = engine_variants(eng)
        if reason is not None:
            result["skipped"].append({"engine": eng, "reason": reason})
        if not runnable:
            continue
        axes = [Axis(resolve_parameter("dt"), tuple(float(d) for d in dts)),
                Axis(resolve_parameter("contact_stiffness"), tuple(float(k) for k in
                                                                     stiffnesses))]
        if name is not None:
            axes.append(Axis(GridTarget(f"option.{name}", OPTION, name), tuple(values)))
        d = out / f"speed-{eng}"
        _warm_up(eng, scen, max(dts))
        run_sweep(scen, Grid(tuple(axes)), d, backends=("soft", eng),
                  options={eng: dict(SPEED_ENGINE_OPTIONS)}, workers=0,
                  identify=False, progress=progress)
        result["engines"][eng] = d
    return result


def _warm_up(engine: str, scenario, dt: float) -> None:
    """One short run first, so that the first timed run does not pay the imports."""
    try:
        get_backend(engine).simulate(dataclasses.replace(scenario, t_end=0.01),
                                     **SPEED_ENGINE_OPTIONS, dt=dt)
    except Exception:  # noqa: BLE001 - the timed runs record any error themselves
        pass


def speed_points(df, engine: str, metrics=SPEED_METRICS):
    """One row per ``engine`` run of the sweep table ``df``: variant, dt, k_c, cost (s per
    simulated s), error vs soft, error vs analytic (the largest over ``metrics``), status
    and error text."""
    # lazy: +207 ms at import otherwise (pandas, numpy, pyarrow),
    # which this module's other callers do not need
    import pandas as pd

    variant_col = next((c for c in df.columns if c.startswith("option.")), None)
    eng = df[df["target"] == engine]
    ok = df[df["status"] == OK]
    ref = {t: ok[ok["target"] == t].set_index("point") for t in ("soft", "analytic")}
    rows = []
    for _, r in eng.iterrows():
        row = {"engine": engine, "variant": r[variant_col] if variant_col else "default",
               "dt": float(r["dt"]), "contact_stiffness": float(r["contact_stiffness"]),
               "status": r["status"], "error": r["error"] if isinstance(r["error"], str) else "",
               "cost": float(r["wall_s"]) / float(r["t_end"]) if r["status"] == OK else np.nan}
        for t, col in (("soft", "err_soft"), ("analytic", "err_paper")):
            row[col] = np.nan
            if r["status"] == OK and r["point"] in ref[t].index:
                rr = ref[t].loc[r["point"]]
                rels = [abs(float(r[m]) - float(rr[m])) / abs(float(rr[m])) for m in metrics
                        if m in r and np.isfinite(float(r[m])) and np.isfinite(float(rr[m]))
                        and float(rr[m]) != 0]
                row[col] = max(rels) if rels else np.nan
        rows.append(row)
    return pd.DataFrame(rows, columns=["engine", "variant", "dt", "contact_stiffness", "status",
                                       "error", "cost", "err_soft", "err_paper"])


def speed_figure(points, path, engine: str) -> Path | None:
    """Error against cost of ``engine``'s runs (``points``, :func:`speed_points`), one curve
    per (variant, k_c), written to ``path``; None when no run succeeded."""
    # lazy: +310 ms at import otherwise (matplotlib, numpy),
    # which this module's other callers do not need
    from matplotlib.figure import Figure

    ok = points[points["status"] == OK]
    if ok.empty:
        return None
    fig = Figure(figsize=(9.0, 3.6), layout="constrained")
    axes = [fig.add_subplot(1, 2, i + 1) for i in range(2)]
    markers = "osD^v<>"
    for i, ((variant, k), g) in enumerate(ok.groupby(["variant", "contact_stiffness"])):
        g = g.sort_values("dt", ascending=False)
        label = f"{variant}, k_c = {k:.3g} N/m"
        for ax, col in zip(axes, ("err_soft", "err_paper")):
            y = np.maximum(g[col].to_numpy(float), 1e-12)  # log axis: exact zero drawn at 1e-12
            ax.loglog(g["cost"], y, marker=markers[i % len(markers)], ms=4, label=label)
    axes[0].set_title("vs analytic soft contact, same k_c (integration error)", fontsize=8)
    axes[1].set_title("vs the paper's Newton solution (eqs 12-35)", fontsize=8)
    for ax in axes:
        ax.set_xlabel("wall time per simulated second (s/s)", fontsize=8)
        ax.set_ylabel("max relative error of x_max, t_xmax, t_sep,\n"
                      "impact loss, energy transferred, theta_b (1)", fontsize=7)
        ax.tick_params(which="both", labelsize=6)  # log axes label minor ticks too
        ax.grid(True, which="both", lw=0.3)
    axes[1].legend(fontsize=6)
    fig.suptitle(f"{engine}: speed-accuracy (points along a curve: dt decreasing)", fontsize=9)

    save_figure(fig, path, 110)
    return Path(path)


def speed_curves(result: dict, figdir) -> list[dict]:
    """Figures (into ``figdir``) and tables of :func:`speed_sweep`'s ``result``."""
    figdir = Path(figdir)
    figdir.mkdir(parents=True, exist_ok=True)
    out = []
    for eng, d in result["engines"].items():
        pts = speed_points(read_table(d), eng)
        fig = speed_figure(pts, figdir / f"speed-{eng}.png", eng)
        out.append({"engine": eng, "path": fig, "points": pts,
                    "caption": (f"{eng}: error against wall time per simulated second over "
                                f"dt = {', '.join(f'{x:g}' for x in result['dts'])} s and "
                                f"k_c = {', '.join(f'{x:.3g}' for x in result['stiffnesses'])}"
                                f" N/m; one curve per variant and k_c. Error: max relative error over "
                                f"{', '.join(SPEED_METRICS)}.")})
    return out
