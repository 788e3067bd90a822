"""``treeimpact paper``: Table 1 of the paper recomputed beside the printed values, the
restitution reproducing each measured quantity, the discrepancies between the printed
equations and the printed numbers, and (``--fit-contact``) each model held against every
measured number (SI units)."""

from __future__ import annotations

import math

from treeimpact.analytic.results import json_text
from treeimpact.compare.runs.provenance import provenance

from ...runs.exits import ExitCode
from ._common import fmt

NAME = "paper"


def add_arguments(sp) -> None:
    """The command's flags, added to its subparser ``sp``."""
    sp.add_argument("--json", action="store_true", help="machine-readable output")
    sp.add_argument("--fit-contact", action="store_true", dest="fit_contact",
                    help="also fit each model (the paper's, the 1-DOF soft, the continuum, the "
                         "continuum with the clamp mass free) to every measured number of each "
                         "tree: which model explains which, with the degrees of freedom left")


#: How the contact fit prints each target: (scale, unit).
_FIT_DISPLAY = {"V": (1.0, "m/s"), "x0": (1e3, "mm"), "T0": (1e3, "ms"), "x_max": (1e3, "mm"),
                "tau": (1e3, "ms"), "theta_b": (180.0 / math.pi, "deg")}
_FREE_DISPLAY = {"contact_duration": ("contact", 1e3, "ms"), "restitution": ("e", 1.0, ""),
                 "clamp_mass": ("clamp", 1.0, "kg")}


def _fit_cell(target: dict) -> str:
    rel = target["residual"]
    return (f"{rel:+.0%}" if math.isfinite(rel) else "n/a") + ("*" if target["explained"]
                                                                else " ")


def _print_contact_fit(trees: dict) -> None:
    # lazy: +321 ms at import otherwise (scipy, numpy),
    # which this module's other callers do not need
    from treeimpact.analytic.paper.contact_fit import RECORD_RATE

    print("Models held against every measured number (Table 1, Figs 4-5, the text): each "
          "model's record read by the paper's own procedure (sampled at "
          f"{RECORD_RATE / 1e3:g} kHz, tau from the extrapolated origin); residual = model / "
          "measured - 1; * = explained (within 5 % or half the printed digit); parameters "
          "marked ! sit on a bound of their range")
    for name, tree in trees.items():
        measured = ", ".join(f"{k} {v * _FIT_DISPLAY[k][0]:.5g} {_FIT_DISPLAY[k][1]}"
                             for k, v in tree["measured"].items())
        print(f"  {name}: measured {measured}")
        print(f"    {'model':<11}{'free parameters (fitted)':<38}{'dof':>4}"
              + "".join(f"{k:>9}" for k in tree["measured"]) + f"{'rms':>8}")
        for model, f in tree["fits"].items():
            params = ", ".join(
                f"{_FREE_DISPLAY[k][0]} {p['value'] * _FREE_DISPLAY[k][1]:.3g}"
                f"{' ' + _FREE_DISPLAY[k][2] if _FREE_DISPLAY[k][2] else ''}"
                f"{'!' if p['on_bound'] else ''}" for k, p in f["parameters"].items())
            cells = "".join(f"{_fit_cell(t):>9}" for t in f["targets"].values())
            print(f"    {model:<11}{params:<38}{f['dof']:>4}{cells}{f['rms']:>8.1%}")
        none = tree["explained_by_none"]
        print(f"    explained by no model: {', '.join(none) if none else 'none left'}")
    print()


def _print_tables(res: dict) -> None:
    for name, quantities in res["trees"].items():
        print(f"Table 1, {name} tree (SI units)")
        print(f"  {'quantity':<16}{'printed':>14}{'recomputed':>14}{'rel diff':>10}  how")
        for q, row in quantities.items():
            print(f"  {q:<16}{fmt(row['printed']):>14}{fmt(row['recomputed']):>14}"
                  f"{row['rel_diff']:>+10.3%}  {row['how']}")
        print()
    print("Restitution e reproducing each measured quantity (exact solver, Table 1 parameters)")
    for name, rows in res["restitution_estimates"].items():
        cells = ", ".join(f"{r['quantity']}: {fmt(r['restitution'])}" for r in rows)
        print(f"  {name}: {cells}")
    print()
    print("Discrepancies between the printed equations and the printed numbers")
    for d in res["discrepancies"]:
        print(f"- {d['equation']}: printed {d['printed']}")
        print(f"    reproduces the table: {d['reproduces_table']}")
        print(f"    evidence: {d['evidence']}")


def run(args) -> int:
    """Print the reproduction for the parsed command line ``args`` (the API's
    :func:`~treeimpact.compare.interface.api.paper`, as text or ``--json``; with
    ``--fit-contact`` the models fitted to the measurements); exit code 0."""
    # lazy: +290 ms at import otherwise (the API's modules, numpy), which --help does not need
    from treeimpact.compare.interface.api import paper

    res = paper(fit_contact=getattr(args, "fit_contact", False))
    if args.json:
        print(json_text(res | {"provenance": provenance()}, indent=2))
        return ExitCode.OK
    if "contact_fit" in res:
        _print_contact_fit(res["contact_fit"])
    _print_tables(res)
    return ExitCode.OK
