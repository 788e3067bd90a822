"""``treeimpact``: the command line (SI units throughout; keys documented in the README).

Exit codes: 0 success; 2 bad input (one line on stderr naming the field and its range,
no traceback); 3 a simulation diverged (reported as such, never as numbers).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path

from treeimpact.analytic.errors import ParameterError, SimulationDiverged, one_line
from treeimpact.analytic.results import METRIC_UNITS, to_jsonable

EXIT_BAD_INPUT = 2
EXIT_DIVERGED = 3


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2 (argparse prints usage by default)
        raise ParameterError(message)


def _number(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None


def _count(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="treeimpact", description="The fruit-tree trunk impact model of the paper "
                "and its cross-checks against MuJoCo and PyBullet (SI units; exit codes: 0 "
                "success, 2 bad input, 3 the simulation diverged).")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    sp = sub.add_parser("paper", help="reproduce Table 1 and list the paper's discrepancies")
    sp.add_argument("--json", action="store_true", help="machine-readable output")
    sp.add_argument("--fit-contact", action="store_true", dest="fit_contact",
                    help="also fit the contact duration and e to each tree's measured x_max "
                         "and tau, on the 1-DOF (soft) and continuum (beam) models (about 20 s)")

    ss = sub.add_parser("simulate", help="simulate one scenario")
    ss.add_argument("scenario", help="shipped scenario name or TOML path")
    ss.add_argument("--backend", default="analytic",
                    help="analytic, soft, beam, mujoco or bullet")
    ss.add_argument("--e", type=_number, dest="restitution", help="restitution e in [0, 1]")
    ss.add_argument("--t-end", type=_number, dest="t_end", help="end time, s")
    ss.add_argument("--trunk", choices=("sdof", "chain"), help="engine trunk model")
    ss.add_argument("--segments", type=_count, help="segments of the hinged trunk")
    ss.add_argument("--pendulum", choices=("linear", "full"), help="engine pendulum model")
    ss.add_argument("--contact", choices=("soft", "newton"), help="Bullet contact mode")
    ss.add_argument("--contact-stiffness", type=_number, dest="contact_stiffness",
                    help="contact stiffness, N/m")
    ss.add_argument("--dt", type=_number, help="time step, s")
    ss.add_argument("--elements", type=_count, help="beam backend: elements of the trunk mesh")
    ss.add_argument("--calibration", choices=("pad", "effective"),
                    help="beam, mujoco, bullet: the contact damping of the SDOF's pad (default) "
                         "or recalibrated so that e holds on the trunk's effective mass")
    ss.add_argument("--damping", choices=("distributed", "joint"),
                    help="engine trunk damping: the paper's distributed C, or joint damping")
    ss.add_argument("--integrator", choices=("Euler", "implicit", "implicitfast", "RK4"),
                    help="MuJoCo integrator (default Euler)")
    ss.add_argument("--json", action="store_true", help="machine-readable output")
    from .identify_cmd import add_record_arguments

    add_record_arguments(ss, _number, _count)

    sm = sub.add_parser("modes", help="static stiffness at a and natural frequencies")
    sm.add_argument("scenario", help="shipped scenario name or TOML path")
    sm.add_argument("--backend", default="analytic",
                    help="analytic (the SDOF trunk), beam (its mesh), mujoco or bullet (their "
                         "hinged trunks)")
    sm.add_argument("--segments", type=_count, help="segments of the hinged trunk")
    sm.add_argument("--elements", type=_count, help="beam backend: elements of the trunk mesh")
    sm.add_argument("--json", action="store_true", help="machine-readable output")
    sr = sub.add_parser("report", help="write the discrepancy report (html, md, json)")
    sr.add_argument("--out", default="reports", help="output directory (default: reports)")
    sr.add_argument("--scenario", action="append", dest="scenarios",
                    help="shipped scenario name or TOML path (repeatable; default: all shipped)")
    sr.add_argument("--study", action="append", dest="studies", default=[],
                    help="directory of a finished study to include (repeatable)")

    from .identify_cmd import add_arguments as add_identify_arguments
    from .scenario_cmd import add_arguments as add_scenario_arguments

    add_identify_arguments(sub.add_parser(
        "identify", help="tree properties (M_T, K_T, C_T, e, E) from your own pendulum-test "
                         "record, with 95 %% intervals"), _number)

    add_scenario_arguments(sub.add_parser(
        "scenario", help="write a scenario file for your own tree from measured M_T, K_T, b"),
        _number)

    try:
        from .sweep.cli_support import add_sweep_arguments
    except ImportError:  # pragma: no cover - the sweep package is optional at import time
        add_sweep_arguments = None
    if add_sweep_arguments is not None:
        sw = sub.add_parser("sweep", help="run a parameter sweep: validity maps and studies")
        add_sweep_arguments(sw)
    return p


def _fmt(v) -> str:
    if isinstance(v, float):
        return "n/a" if not math.isfinite(v) else f"{v:.6g}"
    return str(v)


def _print_contact_fit(fits: dict) -> None:
    print("Contact fitted to the measured x_max and tau (Table 1, Figs 4-5 regression): "
          "residual = model / measured - 1; V, x0, T0 shown, not fitted (moving-together "
          "point)")
    for name, row in fits.items():
        print(f"  {name}: measured x_max {1e3 * row['measured']['x_max']:.3f} mm, "
              f"tau {1e3 * row['measured']['t_xmax']:.2f} ms")
        for model, f in row["fits"].items():
            label = "1-DOF (soft)" if model == "soft" else "continuum (beam)"
            cells = "  ".join(f"{k} {v:+.1%}" if math.isfinite(v) else f"{k} n/a (no "
                              "moving-together contact)" for k, v in f["residuals"].items())
            print(f"    {label:<17} contact {1e3 * f['duration']:7.3f} ms  e {f['restitution']:.3f}"
                  f"  rms(x_max, tau) {f['rms']:.1%}   {cells}")
        if "one_dof_cost" in row:
            c = row["one_dof_cost"]
            print(f"    at the continuum's contact the 1-DOF model is off by x_max "
                  f"{-c['x_max'] / (1 + c['x_max']):+.1%}, energy delivered "
                  f"{-c['energy_delivered'] / (1 + c['energy_delivered']):+.1%}")
    print()


def cmd_paper(args) -> int:
    from treeimpact.analytic.paper.reproduction import reproduce

    res = reproduce()
    if getattr(args, "fit_contact", False):
        from treeimpact.analytic.paper.contact_fit import fit_paper_trees

        res["contact_fit"] = fit_paper_trees()
    if args.json:
        print(json.dumps(to_jsonable(res), indent=2))
        return 0
    if "contact_fit" in res:
        _print_contact_fit(res["contact_fit"])
    for name, quantities in res["trees"].items():
        print(f"Table 1, {name} tree (SI units)")
        print(f"  {'quantity':<16}{'printed':>14}{'recomputed':>14}{'rel diff':>10}  how")
        for q, row in quantities.items():
            print(f"  {q:<16}{_fmt(row['printed']):>14}{_fmt(row['recomputed']):>14}"
                  f"{row['rel_diff']:>+10.3%}  {row['how']}")
        print()
    print("Restitution e reproducing each measured quantity (exact solver, Table 1 parameters)")
    for name, rows in res["restitution_estimates"].items():
        cells = ", ".join(f"{r['quantity']}: {_fmt(r['restitution'])}" for r in rows)
        print(f"  {name}: {cells}")
    print()
    print("Discrepancies between the printed equations and the printed numbers")
    for d in res["discrepancies"]:
        print(f"- {d['equation']}: printed {d['printed']}")
        print(f"    reproduces the table: {d['reproduces_table']}")
        print(f"    evidence: {d['evidence']}")
    return 0


def _options(args, names) -> dict:
    return {n: getattr(args, n) for n in names if getattr(args, n, None) is not None}


#: Units of the ``model`` keys every backend reports (README); others print without one.
MODEL_UNITS = {"M_T": "kg", "C_T": "N s/m", "K_T": "N/m", "m": "kg", "k": "N/m", "e": "1",
               "u1": "m/s", "dt": "s", "contact_stiffness": "N/m", "contact_damping": "N s/m",
               "law_stiffness": "N/m", "law_damping": "N s/m", "effective_mass": "kg",
               "collision_duration": "s", "omega_max": "rad/s"}


#: Metrics printed without a relative difference: a count and a numerical residual.
_NO_DIFFERENCE = ("n_impacts", "ledger_residual")


def _unit(u: str) -> str:
    return "-" if u in ("1", "") else u  # a dimensionless 1 read as a second number


def _rel(value, reference) -> str:
    """:func:`compare.ladder.relative_step` as text ('' where it has no value)."""
    from .ladder import relative_step

    rel = relative_step(value, reference)
    return f"{rel:+.1%}" if math.isfinite(rel) else ""


def _print_simulation(scenario, result, reference) -> None:
    """One key per line, units in their own column; beside a backend's value the paper's
    model (the analytic backend) and the relative difference, when ``reference`` is given."""
    print(f"{scenario.name} ({result.backend})")
    print("model:")
    for key, value in result.model.items():
        text = _fmt(value) if not isinstance(value, (list, tuple)) else " ".join(
            _fmt(v) for v in value)
        print(f"  {key:<22}{text:>14}  {_unit(MODEL_UNITS.get(key, ''))}")
    head = f"  {'metric':<22}{result.backend:>14}  {'unit':<7}"
    if reference is not None:
        head += f"{'paper model':>14}{'difference':>12}"
    print("metrics:" if reference is None else "metrics (paper model: the analytic backend, "
          "eqs 12-35):")
    print(head + "  meaning")
    for key, value in result.metrics.items():
        unit, meaning = METRIC_UNITS[key]
        line = f"  {key:<22}{_fmt(value):>14}  {_unit(unit):<7}"
        if reference is not None:
            ref = reference.metrics.get(key)
            diff = "" if key in _NO_DIFFERENCE else _rel(value, ref)
            line += f"{_fmt(ref):>14}{diff:>12}"
        print(line + f"  {meaning}")


#: Flag -> (attribute, the field whose plausible range it takes, analytic.model.parameters.LIMITS).
_FLAG_LIMITS = {"--e": ("restitution", "contact.restitution"), "--t-end": ("t_end", "t_end"),
                "--contact-stiffness": ("contact_stiffness", "contact.stiffness")}


def _check_flags(args) -> None:
    """One-line errors that name the flag the user typed, with its allowed range."""
    from treeimpact.analytic.continuum.chain import MAX_SEGMENTS
    from treeimpact.analytic.model.parameters import LIMITS, check_range

    for flag, (attr, field) in _FLAG_LIMITS.items():
        value = getattr(args, attr, None)
        if value is not None:
            low, high, unit = LIMITS[field]
            check_range(flag, value, low=low, high=high, unit="" if unit == "1" else unit)
    dt = getattr(args, "dt", None)
    if dt is not None:
        check_range("--dt", dt, low=0.0, low_open=True, high=1e-3, unit="s")
    segments = getattr(args, "segments", None)
    if segments is not None and not 1 <= segments <= MAX_SEGMENTS:
        raise ParameterError(f"--segments = {segments}: allowed 1 to {MAX_SEGMENTS}")


def cmd_simulate(args) -> int:
    from treeimpact.analytic.model.scenario import load_scenario

    from .backends import get_backend

    backend = get_backend(args.backend)
    scenario = load_scenario(args.scenario)
    _check_flags(args)
    opts = _options(args, ("restitution", "t_end", "trunk", "segments", "pendulum", "contact",
                           "contact_stiffness", "dt", "damping", "integrator", "elements",
                           "calibration"))
    if args.record:
        from .identify_cmd import check_record_arguments, write_record

        check_record_arguments(args)
    result = backend.simulate(scenario, **opts)
    written = write_record(args, scenario, result) if args.record else None
    if args.json:
        print(json.dumps(result.to_json(), indent=2))
        return 0
    reference = None
    if args.backend != "analytic":  # the paper's model beside it (a few ms)
        opts = _options(args, ("restitution", "t_end"))
        reference = get_backend("analytic").simulate(scenario, **opts)
    _print_simulation(scenario, result, reference)
    if written:
        print(written)
    return 0


def cmd_modes(args) -> int:
    from treeimpact.analytic.model.scenario import load_scenario

    from .backends import get_backend

    backend = get_backend(args.backend)
    scenario = load_scenario(args.scenario)
    res = backend.modes(scenario, **_options(args, ("segments", "elements")))
    if args.json:
        print(json.dumps(to_jsonable(res), indent=2))
        return 0
    model, beam = res["model"], res["beam"]
    print(f"{scenario.name} ({args.backend} trunk against the continuous Euler-Bernoulli beam)")
    print(f"  {'quantity':<26}{'model':>14}{'beam':>14}{'difference':>12}  unit")
    rows = [("static stiffness at a", model["static_stiffness"], beam["static_stiffness"],
             "N/m")]
    rows += [(f"natural frequency {i + 1}", w, wb, "rad/s")
             for i, (w, wb) in enumerate(zip(model["omegas"], beam["omegas"]))]
    for name, v, vb, unit in rows:
        print(f"  {name:<26}{_fmt(v):>14}{_fmt(vb):>14}{_rel(v, vb):>12}  {unit}")
    return 0


def cmd_report(args) -> int:
    from treeimpact.analytic.model.scenario import load_scenario

    from .report import write_report

    scenarios = [load_scenario(n) for n in args.scenarios] if args.scenarios else None
    for study in args.studies:  # checked before an hour of runs, not after
        if not Path(study).is_dir():
            raise ParameterError(f"--study {study!r}: not a directory (a finished study, "
                                 "treeimpact sweep --out DIR)")
    _writable_dir("--out", args.out)
    paths = write_report(args.out, scenarios=scenarios, study_dirs=tuple(args.studies),
                         progress=True)
    for kind, path in paths.items():
        print(f"{kind}: {path}")
    return 0


def _writable_dir(flag: str, path: str) -> None:
    """Create ``path`` (a directory) now, or raise a one-line error naming ``flag``."""
    try:
        Path(path).mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ParameterError(f"{flag} {path!r}: cannot create the directory "
                             f"({exc.strerror or type(exc).__name__})") from None
    if not os.access(path, os.W_OK):
        raise ParameterError(f"{flag} {path!r}: the directory is not writable")


def cmd_sweep(args) -> int:
    from .sweep.cli_support import run_sweep_command

    return run_sweep_command(args)


def cmd_identify(args) -> int:
    from .identify_cmd import run

    return run(args)


def cmd_scenario(args) -> int:
    from .scenario_cmd import run

    return run(args)


COMMANDS = {"paper": cmd_paper, "simulate": cmd_simulate, "modes": cmd_modes,
            "report": cmd_report, "sweep": cmd_sweep, "scenario": cmd_scenario,
            "identify": cmd_identify}


def main(argv=None) -> int:
    try:
        args = build_parser().parse_args(argv)
        return COMMANDS[args.command](args)
    except ParameterError as exc:
        print(f"treeimpact: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except SimulationDiverged as exc:
        print(f"treeimpact: simulation diverged: {exc}", file=sys.stderr)
        return EXIT_DIVERGED
    except BrokenPipeError:  # output piped into head & co.
        sys.stderr.close()
        return 0
    except MemoryError:
        print("treeimpact: error: the run needs more memory than this machine has: a shorter "
              "--t-end or a softer contact", file=sys.stderr)
        return EXIT_BAD_INPUT
    except ArithmeticError as exc:  # overflow or division by zero: no numbers to report
        print(f"treeimpact: simulation diverged: {type(exc).__name__} ({one_line(exc)})",
              file=sys.stderr)
        return EXIT_DIVERGED
    except OSError as exc:  # a path that cannot be read or written
        where = f" {exc.filename!r}" if exc.filename else ""
        print(f"treeimpact: error:{where} {exc.strerror or one_line(exc)}", file=sys.stderr)
        return EXIT_BAD_INPUT


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
