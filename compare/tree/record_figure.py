"""The figure of a pendulum-test record's identification (``treeimpact identify --plot``,
:func:`treeimpact.identify`'s ``plot``): the record, the exact 1-DOF model fitted to it
(eqs 12-35), the paper's procedure's reading drawn as the same model, and the residuals."""

from __future__ import annotations

from treeimpact.analytic.identify.fit_model import model_x_of_trunk

from ..runs.figure_text import save_figure

#: The figure formats it writes (by the file's suffix).
PLOT_FORMATS = (".png", ".pdf", ".svg")
#: Milliseconds and millimetres per second and metre: the axes' units.
MS = 1e3


def _draw_reading(ax, axr, record, fit, reading: dict, test) -> None:
    """The paper's procedure's ``reading`` (M_T, K_T, the trunk's damping ratio) drawn as
    the exact model with the fit's contact, e and sensor terms, and its residual; nothing
    for a reading that did not run or whose damping ratio is not positive (the model's own
    range; its M_T and K_T are positive, or the procedure refused the record)."""
    if "M_T" not in reading or not reading["trunk_damping_ratio"] > 0:
        return
    xp = model_x_of_trunk(fit.point, test, record.t, dynamic_mass=reading["M_T"],
                          equivalent_stiffness=reading["K_T"],
                          trunk_damping_ratio=reading["trunk_damping_ratio"])
    ax.plot(record.t * MS, xp * MS, "--", color="C3", lw=1.4,
            label=f"the paper's procedure (M_T {reading['M_T']:.4g} kg, K_T "
                  f"{reading['K_T']:.4g} N/m)")
    axr.plot(record.t * MS, (record.x - xp) * MS, "--", color="C3", lw=1,
             label="x, the paper's procedure")


def _fit_label(fit) -> str:
    """The legend's text of the full-record fit: M_T and K_T, or their ranges when the
    record does not fix them."""
    if fit.determined["M_T"]:
        return f"M_T {fit.values['M_T']:.4g} kg, K_T {fit.values['K_T']:.4g} N/m"
    (m_lo, m_hi), (k_lo, k_hi) = fit.intervals["M_T"], fit.intervals["K_T"]
    return (f"M_T {m_lo:.4g}-{m_hi:.4g} kg, K_T {k_lo:.4g}-{k_hi:.4g} N/m:\n"
            "the record does not fix M_T and e apart")


def _draw_pendulum(axy, axr, record, fit) -> None:
    """The pendulum's record y and its fit, and its residual."""
    t = record.t * MS
    axy.plot(t, record.y * MS, ".", ms=2, color="0.5", label="record")
    axy.plot(t, fit.model_y * MS, "-", color="C2", lw=1.4, label="full-record fit")
    axy.set(ylabel="pendulum displacement y (mm)")
    axy.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    axr.plot(t, (record.y - fit.model_y) * MS, "-", color="C2", lw=1,
             label="y, full-record fit")


def draw_record_fit(path, record, fit, procedure: dict, test) -> None:
    """Write the figure to ``path`` (PNG, PDF or SVG by its suffix).

    Args:
        path: the file written.
        record: the record (``analytic.identify.pendulum_record.Record``: t s, x and y m).
        fit: its full-record fit (``analytic.identify.record_fit.FitResult``).
        procedure: the paper's procedure's readings (``procedure_readings``); its "paper"
            reading is drawn when it has numbers.
        test: the pendulum test (``analytic.identify.procedure.PendulumTest``).
    """
    # lazy: +86 ms at import otherwise (matplotlib, numpy),
    # which this module's other callers do not need
    import matplotlib

    matplotlib.use("Agg")
    # lazy: +314 ms at import otherwise (matplotlib, numpy),
    # which this module's other callers do not need
    from matplotlib.figure import Figure

    pendulum = record.y is not None
    fig = Figure(figsize=(10, 8.5 if pendulum else 6), layout="constrained")
    axes = fig.subplots(3 if pendulum else 2, 1, sharex=True, gridspec_kw={
        "height_ratios": (3, 2, 1.2) if pendulum else (3, 1.2)})
    ax, axr = axes[0], axes[-1]
    t = record.t * MS
    ax.plot(t, record.x * MS, ".", ms=2, color="0.5", label="record")
    if fit.flagged.size:
        ax.plot(t[fit.flagged], record.x[fit.flagged] * MS, "x", color="C3",
                label="outliers, left out")
    ax.plot(t, fit.model_x * MS, "-", color="C0", lw=1.6,
            label=f"full-record fit ({_fit_label(fit)})")
    axr.plot(t, (record.x - fit.model_x) * MS, "-", color="C0", lw=1, zorder=3,
             label="x, full-record fit")
    if pendulum:
        _draw_pendulum(axes[1], axr, record, fit)
    _draw_reading(ax, axr, record, fit, procedure.get("paper", {}), test)
    ax.set(ylabel="trunk displacement x (mm)",
           title="pendulum test: the record and the exact 1-DOF model fitted to it")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    axr.axhline(0.0, color="k", lw=0.6)
    axr.set(xlabel="time t (ms)", ylabel="residual (mm)")
    axr.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    save_figure(fig, path, 110)
