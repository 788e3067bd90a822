"""``treeimpact identify RECORD.csv``: tree properties from a user's own pendulum-test record,
by the full-record fit (:mod:`analytic.identify.record_fit`) and the paper's procedure side by
side."""

from __future__ import annotations

import argparse
import hashlib
import math
import sys
from pathlib import Path

from treeimpact.analytic.errors import NotAchieved
from treeimpact.analytic.identify.intervals import DAMPING_RATIO_FORMULAS, UNITS
from treeimpact.analytic.identify.pendulum_record import LENGTH_UNITS, TIME_UNITS
from treeimpact.analytic.model.parameters import Pendulum
from treeimpact.analytic.results import json_text
from treeimpact.compare.runs.backends import worded_c_output
from treeimpact.compare.runs.provenance import provenance

from ...runs.exits import ExitCode
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


def _pendulum(args) -> Pendulum:
    """The test's Pendulum of the flags, each checked as typed first (an error names the
    flag and its range); the API checks the trunk's flags and --restitution (one check
    each, where it enters)."""
    # lazy: +53 ms at import otherwise (numpy), which this module's other callers do not need
    from treeimpact.compare.interface.api_records import checked_input

    for name in TEST_FLAGS[:3]:  # the pendulum's, before it is built
        checked_input(name, getattr(args, name))
    return Pendulum(mass=args.impactor_mass, equivalent_length=args.equivalent_length,
                    release_angle_deg=args.release_angle_deg)


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
    from treeimpact.compare.interface.api_records import identify

    pendulum = _pendulum(args)
    with worded_c_output("LAPACK", "numpy's linear algebra on this record; the fit checks "
                         "its own results"):  # LAPACK prints its errors on fd 1
        ident = identify(args.record, pendulum, clamp_height=args.clamp_height,
                         diameter=args.diameter, restitution=args.restitution,
                         time_unit=args.time_unit, length_unit=args.length_unit,
                         plot=args.plot)
    fit, record = ident.fit, ident.record
    refusal = _not_fitted(fit)
    if args.json:
        print(json_text(_json(args, ident), indent=2))
        if refusal:
            raise refusal
        return ExitCode.OK
    for line in fit.warnings:
        if not (refusal and line in str(refusal)):  # said once, in the not-achieved line
            print(f"treeimpact: warning: {line}", file=sys.stderr)
    print(f"{args.record}: {record.t.size} samples over {record.t[-1] - record.t[0]:.4g} s "
          f"(read in {record.time_unit} and {record.length_unit})")
    if math.isfinite(fit.residual_rms):  # else not fitted (units): the conclusion says why
        _print_values(fit, ident.procedure.get("paper", {}))
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
    return NotAchieved(f"the record was not fitted: {fit.findings()}")


def _json(args, ident) -> dict:
    """identify --json: the fit's values, the paper's readings, the conclusion and what it
    rests on, the provenance (kinds and sources as their names) of the API's
    Identification ``ident``."""
    fit, record = ident.fit, ident.record
    return {"fit": _quantities(fit), "paper": ident.procedure,
            "definitions": DAMPING_RATIO_FORMULAS,
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
