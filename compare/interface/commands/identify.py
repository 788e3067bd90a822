"""``treeimpact identify RECORD.csv``: tree properties from a user's own pendulum-test record,
by the full-record fit (:mod:`analytic.identify.record_fit`) and the paper's procedure side by
side."""

from __future__ import annotations

import argparse
import hashlib
import math
import sys
from pathlib import Path

import numpy as np

from treeimpact.analytic.errors import NotAchieved, ParameterError
from treeimpact.analytic.identify.fit_parameters import Slot
from treeimpact.analytic.identify.intervals import DAMPING_RATIO_FORMULAS, UNITS
from treeimpact.analytic.identify.pendulum_record import LENGTH_UNITS, TIME_UNITS
from treeimpact.analytic.identify.procedure import READINGS, identify_from_record
from treeimpact.analytic.model.parameters import Pendulum, check_range
from treeimpact.analytic.model.registry import BY_NAME
from treeimpact.analytic.results import json_text
from treeimpact.compare.runs.backends import worded_c_output
from treeimpact.compare.runs.figure_text import save_figure
from treeimpact.compare.runs.provenance import provenance

from ...runs.exits import ExitCode
from ...runs.names import show
from ._common import add_parameter_flag, unit_text

NAME = "identify"
#: Removed spellings -> their names now (compare.runs.names).
RENAMED = {"release_angle": "release_angle_deg", "mass": "impactor_mass"}
#: The pendulum test's flags (registry names, analytic.model.registry): all required.
TEST_FLAGS = ("impactor_mass", "equivalent_length", "release_angle_deg", "clamp_height",
              "diameter")



def add_arguments(sp: argparse.ArgumentParser) -> None:
    """The command's flags, added to its subparser ``sp``: the record, the test's pendulum
    and trunk, the units."""
    sp.add_argument("record", help="CSV with columns t, x (and y, the pendulum's), in any "
                                   "order, units in the header ('t [ms]', 'x (mm)') or below")
    for name in TEST_FLAGS:
        add_parameter_flag(sp, name, required=True)
    add_parameter_flag(sp, "restitution",
                       note="if known: held fixed in the fit; a record the pendulum leaves "
                            "after one impact needs it to fix M_T")
    sp.add_argument("--time-unit", choices=tuple(TIME_UNITS),
                    help="unit of the time column when its header names none (default s)")
    sp.add_argument("--length-unit", choices=tuple(LENGTH_UNITS),
                    help="unit of the x and y columns when their headers name none "
                         "(default m)")
    sp.add_argument("--json", action="store_true", help="machine-readable output")
    sp.add_argument("--plot", help="write a figure of the record, both fits and the residuals "
                                   "(PNG) to this file")


def _test(args):
    """The PendulumTest of the flags (:func:`compare.interface.api_records.pendulum_test`, as the API's
    identify), each flag checked as typed first (an error names the flag)."""
    # lazy: +53 ms at import otherwise (numpy), which this module's other callers do not need
    from treeimpact.compare.interface.api_records import pendulum_test

    for name in TEST_FLAGS:  # each flag as typed, before anything is built
        p = BY_NAME[name]
        check_range(show(name), getattr(args, name), low=p.low, high=p.high, unit=p.unit)
    pend = Pendulum(mass=args.impactor_mass, equivalent_length=args.equivalent_length,
                    release_angle_deg=args.release_angle_deg)
    if args.restitution is not None:
        check_range("--restitution", args.restitution, low=0.0, high=1.0)
    return pendulum_test(pend, args.clamp_height, args.diameter)


def _paper(record, test, fit=None) -> dict:
    """The paper's procedure (eqs 39-48) in each of its readings, or why it cannot run: not
    at all on a record the ``fit`` refused for its units (every method refuses it)."""
    if fit is not None and not fit.conclusion.fitted:
        why = "; ".join(d.message for d in fit.diagnoses) or str(fit.conclusion)
        return {reading: {"error": f"not read: {why}"} for reading in READINGS}
    out = {}
    for reading in READINGS:
        try:
            ident, _ = identify_from_record(record.t, record.x, test, y=record.y,
                                            reading=reading)
        except (ParameterError, ValueError, FloatingPointError) as exc:
            out[reading] = {"error": " ".join(str(exc).split())}
            continue
        equivalent_damping = 2.0 * ident.b * (ident.dynamic_mass + test.impactor_mass)
        trunk = (equivalent_damping
                 / (2.0 * math.sqrt(ident.equivalent_stiffness * ident.dynamic_mass))) if (
            ident.equivalent_stiffness > 0 and ident.dynamic_mass > 0) else math.nan
        out[reading] = {"M_T": ident.dynamic_mass, "K_T": ident.equivalent_stiffness,
                        "C_T": equivalent_damping, "E": ident.E,
                        "pair_damping_ratio": ident.pair_damping_ratio,  # the paper's xi
                        "trunk_damping_ratio": trunk}
    return out


#: The figure formats --plot writes (by the file's suffix).
PLOT_FORMATS = (".png", ".pdf", ".svg")


def _check_plot_path(path: str) -> None:
    """--plot names a file of a format it writes, not a directory (one line, before the fit)."""
    p = Path(path)
    if p.is_dir():
        raise ParameterError(f"--plot {path!r} is a directory: name a file in it, e.g. "
                             f"{str(p / 'fit.png')!r}")
    if p.suffix.lower() not in PLOT_FORMATS:
        raise ParameterError(f"--plot {path!r}: allowed a file ending in "
                             f"{', '.join(PLOT_FORMATS)}")


def _provenance(args, record) -> dict:
    """Where the result came from: the code and environment, the record file (name, size,
    SHA-1 of its bytes, samples, units read) and the test's flags as given."""
    data = Path(args.record).read_bytes()
    test = {k: getattr(args, k) for k in (*TEST_FLAGS, "restitution")}
    return provenance(record={"file": str(args.record), "bytes": len(data),
                              "sha1": hashlib.sha1(data).hexdigest(),
                              "samples": int(record.t.size), "time_unit": record.time_unit,
                              "length_unit": record.length_unit},
                      test=test, fit="analytic.identify.record_fit (full-record fit, eqs 12-35)")


def run(args) -> int:
    """Fit the record of the parsed command line ``args`` and print the result (text or
    ``--json``); exit code 0 (explained or not, the verdict says), or NotAchieved (exit 4,
    after the output) for a record not fitted, its one line saying why: the unit flags to
    pass, or no impact in the record (the tree's free vibration)."""
    # lazy: +616 ms at import otherwise (scipy, numpy),
    # which this module's other callers do not need
    from treeimpact.analytic.identify.record_fit import fit_record, read_record

    test = _test(args)
    if args.plot:
        _check_plot_path(args.plot)
    with worded_c_output("LAPACK", "numpy's linear algebra on this record; the fit checks "
                         "its own results"):  # LAPACK prints its errors on fd 1
        record = read_record(args.record, time_unit=args.time_unit,
                             length_unit=args.length_unit)
        fit = fit_record(record, test, restitution=args.restitution)
        with np.errstate(all="ignore"):  # its readings are checked, and fail in one line
            paper = _paper(record, test, fit)
        if args.plot and math.isfinite(fit.residual_rms):
            _plot(args.plot, record, fit, paper, test)
    refusal = _not_fitted(fit)
    if args.json:
        print(json_text(_json(args, record, fit, paper), indent=2))
        if refusal:
            raise refusal
        return ExitCode.OK
    for line in fit.warnings:
        if not (refusal and line in str(refusal)):  # said once, in the not-achieved line
            print(f"treeimpact: warning: {line}", file=sys.stderr)
    print(f"{args.record}: {record.t.size} samples over {record.t[-1] - record.t[0]:.4g} s "
          f"(read in {record.time_unit} and {record.length_unit})")
    if math.isfinite(fit.residual_rms):  # else not fitted (units): the conclusion says why
        _print_values(fit, paper.get("paper", {}))
    _print_conclusion(fit)
    if refusal:
        raise refusal
    return ExitCode.OK


def _not_fitted(fit):
    """A NotAchieved for a record that was not fitted (its numbers look like another unit, or
    it holds no impact), its diagnosis as the message (the unit flags to pass, or why it is
    the tree's free vibration), or None for a fitted one."""
    if fit.conclusion.fitted:
        return None
    why = "; ".join(d.message for d in fit.diagnoses) or str(fit.conclusion)
    return NotAchieved(f"the record was not fitted: {why}")


def _json(args, record, fit, paper) -> dict:
    """identify --json: the fit's values, the paper's readings, the conclusion and what it
    rests on, the provenance (kinds and sources as their names)."""
    # lazy: +51 ms at import otherwise (numpy), which this module's other callers do not need
    from treeimpact.analytic.identify.intervals import DAMPING_RATIO_FORMULAS

    return {"fit": _quantities(fit), "paper": paper, "definitions": DAMPING_RATIO_FORMULAS,
            "residual_rms": fit.residual_rms, "residual_rms_y": fit.residual_rms_y,
            "explained": fit.explained, "note": fit.note, "held": fit.held,
            "verdict": str(fit.conclusion),
            "diagnoses": [d.to_json() for d in fit.diagnoses], "noise": fit.noise,
            "noise_source": fit.noise_source.value if fit.noise_source else "",
            "misfit_ratio": fit.misfit_ratio,
            "flagged_rows": [record.row(int(i)) for i in fit.flagged],
            "warnings": list(fit.warnings), "provenance": _provenance(args, record)}


def _quantities(fit) -> dict:
    """The fit's quantities as JSON (:meth:`FitResult.to_json`), each with ``held`` (the
    table's "given" or "held at 0", else None); a quantity held at 0 (the sensor's offset or
    drift, not fitted) is not ``determined``: the record did not fix it, the table says so."""
    out = fit.to_json()
    for name, q in out.items():
        q["held"] = fit.held.get(name)
        if q["held"] == "held at 0":
            q["determined"] = False
    return out


def _print_values(fit, reading: dict) -> None:
    """The table of the fit's values and intervals beside the paper's procedure's (a value
    the record does not determine "not fixed", its range; a held one "given" or "held at
    0"), the damping ratios' formulas, what is not fixed, the residual."""
    if not fit.explained:
        print("  the 1-DOF model does NOT explain this record: the numbers below are the "
              "model's best fit, NOT the tree's properties")
    print(f"  {'quantity':<20}{'value':>13}{'95 % low':>13}{'95 % high':>13}  {'unit':<6}"
          f"{'paper (eqs 39-48)':>19}")
    for k, v in fit.values.items():
        lo, hi = fit.intervals[k]
        pv = reading.get(k)
        ptext = f"{pv:.5g}" if isinstance(pv, float) and math.isfinite(pv) else ""
        vtext = f"{v:>13.5g}" if fit.determined[k] else f"{'not fixed':>13}"
        itext = (f"{fit.held[k]:>13}{'':>13}" if k in fit.held
                 else f"{lo:>13.5g}{hi:>13.5g}")
        print(f"  {k:<20}{vtext}{itext}  {unit_text(UNITS[k]):<6}{ptext:>19}")
    for name, formula in DAMPING_RATIO_FORMULAS.items():
        print(f"  {name} = {formula}")
    if fit.note:
        print(f"  not fixed: {fit.note}")
    if "error" in reading:
        print(f"  paper's procedure: {reading['error']}")
    y_text = ("" if fit.residual_rms_y is None else
              f", pendulum's record (y, fitted too) {fit.residual_rms_y:.3g} m")
    print(f"fit: full-record least squares of the exact model (eqs 12-35); residual RMS "
          f"{fit.residual_rms:.3g} m = {fit.misfit_ratio:.3g} x the noise {fit.noise:.3g} m "
          f"({fit.residual_rms / fit.peak:.2%} of the peak){y_text}")


def _print_conclusion(fit) -> None:
    print(f"verdict: {fit.conclusion}")
    for d in fit.diagnoses:
        print(f"  {d.kind}: {d.message}")


def _plot_paper(ax, axr, record, fit, reading: dict, test) -> None:
    """The paper's procedure's ``reading`` (M_T, K_T, the trunk's damping ratio) drawn as
    the exact model with the fit's contact, e and sensor terms, and its residual."""
    # lazy: +616 ms at import otherwise (scipy, numpy),
    # which this module's other callers do not need
    from treeimpact.analytic.identify.record_fit import model_x

    if not ("M_T" in reading and reading["M_T"] > 0 and reading["K_T"] > 0
            and 0 < reading["trunk_damping_ratio"]):  # the fit's parameter: the trunk's own
        return
    ms = 1e3
    p = np.array(fit.point, float)  # the fit's contact, e and sensor terms
    p[Slot.LN_DYNAMIC_MASS], p[Slot.LN_EQUIVALENT_STIFFNESS] = (math.log(reading["M_T"]),
                                                               math.log(reading["K_T"]))
    p[Slot.TRUNK_DAMPING_RATIO] = reading["trunk_damping_ratio"]
    xp = model_x(p, test, record.t)
    ax.plot(record.t * ms, xp * ms, "--", color="C3", lw=1.4,
            label=f"the paper's procedure (M_T {reading['M_T']:.4g} kg, K_T "
                  f"{reading['K_T']:.4g} N/m)")
    axr.plot(record.t * ms, (record.x - xp) * ms, "--", color="C3", lw=1,
             label="x, the paper's procedure")


def _plot(path, record, fit, paper, test) -> None:
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
    ms = 1e3
    ax.plot(record.t * ms, record.x * ms, ".", ms=2, color="0.5", label="record")
    if fit.flagged.size:
        ax.plot(record.t[fit.flagged] * ms, record.x[fit.flagged] * ms, "x", color="C3",
                label="outliers, left out")
    if fit.determined["M_T"]:
        label = f"M_T {fit.values['M_T']:.4g} kg, K_T {fit.values['K_T']:.4g} N/m"
    else:
        (m_lo, m_hi), (k_lo, k_hi) = fit.intervals["M_T"], fit.intervals["K_T"]
        label = (f"M_T {m_lo:.4g}-{m_hi:.4g} kg, K_T {k_lo:.4g}-{k_hi:.4g} N/m:\n"
                 "the record does not fix M_T and e apart")
    ax.plot(record.t * ms, fit.model_x * ms, "-", color="C0", lw=1.6,
            label=f"full-record fit ({label})")
    axr.plot(record.t * ms, (record.x - fit.model_x) * ms, "-", color="C0", lw=1, zorder=3,
             label="x, full-record fit")
    if pendulum:
        axy = axes[1]
        axy.plot(record.t * ms, record.y * ms, ".", ms=2, color="0.5", label="record")
        axy.plot(record.t * ms, fit.model_y * ms, "-", color="C2", lw=1.4,
                 label="full-record fit")
        axy.set(ylabel="pendulum displacement y (mm)")
        axy.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
        axr.plot(record.t * ms, (record.y - fit.model_y) * ms, "-", color="C2", lw=1,
                 label="y, full-record fit")
    _plot_paper(ax, axr, record, fit, paper.get("paper", {}), test)
    ax.set(ylabel="trunk displacement x (mm)",
           title="pendulum test: the record and the exact 1-DOF model fitted to it")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    axr.axhline(0.0, color="k", lw=0.6)
    axr.set(xlabel="time t (ms)", ylabel="residual (mm)")
    axr.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)

    save_figure(fig, path, 110)
