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


#: The options of ``treeimpact modes`` (the backends' modes() take these of their OPTIONS).
MODES_OPTIONS = ("segments", "elements", "beam_theory", "trunk")


def backend_options() -> dict:
    """option name -> (its Option, the backends that take it), over every backend's
    ``OPTIONS`` (read without loading an engine)."""
    from .backends import BACKENDS

    out: dict = {}
    for name, backend in BACKENDS.items():
        try:
            table = backend.options()
        except ParameterError:  # a backend that is not installed offers no flags
            continue
        for key, option in table.items():
            out.setdefault(key, (option, []))[1].append(name)
    return out


def _add_option_flags(parser, names=None) -> None:
    """One flag per backend option (``--contact-stiffness``), its type or choices and help
    from the backends' OPTIONS, the backends that take it named."""
    for key, (option, takers) in sorted(backend_options().items()):
        if not option.cli or (names is not None and key not in names):
            continue
        unit = f", {option.unit}" if option.unit not in ("", "1") else ""
        kind = {"type": _count} if option.kind is int else {"type": _number} \
            if option.choices is None else {"choices": option.choices}
        parser.add_argument("--" + key.replace("_", "-"), dest=key, **kind,
                            help=f"{option.help}{unit} ({', '.join(takers)})".replace("%", "%%"))


def _add_budget_flag(parser) -> None:
    from treeimpact.analytic.budget import MAX_SECONDS, VARIABLES

    parser.add_argument(
        "--max-seconds", type=_number, dest="max_seconds",
        help=f"refuse any single run estimated longer than this, s (default {MAX_SECONDS:g}, "
             f"or {VARIABLES['seconds']}); the estimate is printed with the refusal")


def build_parser() -> argparse.ArgumentParser:
    from .backends import BACKENDS

    p = _Parser(prog="treeimpact", description="The fruit-tree trunk impact model of the paper "
                "and its cross-checks against MuJoCo and PyBullet (SI units; exit codes: 0 "
                "success, 2 bad input, 3 the simulation diverged).")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    sp = sub.add_parser("paper", help="reproduce Table 1 and list the paper's discrepancies")
    sp.add_argument("--json", action="store_true", help="machine-readable output")
    sp.add_argument("--fit-contact", action="store_true", dest="fit_contact",
                    help="also fit each model (the paper's, the 1-DOF soft, the continuum, the "
                         "continuum with the clamp mass free) to every measured number of each "
                         "tree: which model explains which, with the degrees of freedom left")

    ss = sub.add_parser("simulate", help="simulate one scenario")
    ss.add_argument("scenario", help="shipped scenario name or TOML path")
    ss.add_argument("--backend", default="analytic", choices=tuple(BACKENDS),
                    help="the model to run (default: analytic, the paper's)")
    _add_option_flags(ss)
    _add_budget_flag(ss)
    ss.add_argument("--json", action="store_true", help="machine-readable output")
    from .identify_cmd import add_record_arguments

    add_record_arguments(ss, _number, _count)

    sm = sub.add_parser("modes", help="static stiffness at a and natural frequencies")
    sm.add_argument("scenario", help="shipped scenario name or TOML path")
    sm.add_argument("--backend", default="analytic", choices=tuple(BACKENDS),
                    help="analytic (the SDOF trunk), beam (its mesh), mujoco or bullet (their "
                         "hinged trunks)")
    _add_option_flags(sm, MODES_OPTIONS)
    sm.add_argument("--json", action="store_true", help="machine-readable output")
    sr = sub.add_parser("report", help="write the discrepancy report (html, md, json)")
    sr.add_argument("--out", default="reports", help="output directory (default: reports)")
    sr.add_argument("--scenario", action="append", dest="scenarios",
                    help="shipped scenario name or TOML path (repeatable; default: all shipped)")
    sr.add_argument("--study", action="append", dest="studies", default=[],
                    help="directory of a finished study to include (repeatable)")
    sr.add_argument("--with-study", dest="with_study", metavar="PRESET",
                    help="also run the study PRESET (treeimpact sweep --preset PRESET) into "
                         "OUT/study beside the report's own runs, and include it (resumes a "
                         "study already there)")
    _add_budget_flag(sr)

    from .contact_cmd import add_arguments as add_contact_arguments
    from .identify_cmd import add_arguments as add_identify_arguments

    add_contact_arguments(sub.add_parser(
        "contact", help="MuJoCo's solref/solimp and Bullet's contactStiffness/Damping for a "
                        "target e and contact duration, checked in both engines"), _number)
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
        _add_budget_flag(sw)
    return p


def _fmt(v) -> str:
    if isinstance(v, float):
        return "n/a" if not math.isfinite(v) else f"{v:.6g}"
    return str(v)


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


def cmd_paper(args) -> int:
    from treeimpact.analytic.paper.reproduction import reproduce

    res = reproduce()
    if getattr(args, "fit_contact", False):
        from treeimpact.analytic.paper.contact_fit import fit_paper_trees

        res["contact_fit"] = fit_paper_trees()
    if args.json:
        from .provenance import provenance

        print(json.dumps(to_jsonable(res | {"provenance": provenance()}), indent=2))
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
MODEL_UNITS = {"M_T": "kg", "C_T": "N s/m", "K_T": "N/m", "m": "kg", "k": "N/m", "restitution": "1",
               "u1": "m/s", "dt": "s", "contact_stiffness": "N/m", "contact_damping": "N s/m",
               "law_stiffness": "N/m", "law_damping": "N s/m", "effective_mass": "kg",
               "contact_reduced_mass": "kg", "pad_damping_ratio": "1",
               "collision_duration": "s", "omega_max": "rad/s"}


#: Metrics printed without a relative difference: a count and a numerical residual.
_NO_DIFFERENCE = ("n_impacts", "ledger_residual")


def _unit(u: str) -> str:
    return "-" if u in ("1", "") else u  # a dimensionless 1 read as a second number


def _rel(value, reference) -> str:
    """:func:`compare.ladder.relative_step` as text ('' where it has no value)."""
    from .verdicts import relative_step

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


def cmd_simulate(args) -> int:
    from treeimpact.analytic.model.scenario import load_scenario

    from .backends import get_backend

    backend = get_backend(args.backend)
    scenario = load_scenario(args.scenario)
    opts = _options(args, backend_options())
    if args.record:
        from .identify_cmd import check_record_arguments, write_record

        check_record_arguments(args)
    result = backend.simulate(scenario, **opts)
    written = write_record(args, scenario, result) if args.record else None
    if args.json:
        from .provenance import provenance

        out = result.to_json() | {"provenance": provenance(scenario, result, options=opts)}
        print(json.dumps(to_jsonable(out), indent=2))
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
    opts = _options(args, MODES_OPTIONS)
    res = backend.modes(scenario, **opts)
    if args.json:
        from .provenance import provenance

        res = res | {"provenance": provenance(scenario, backend=args.backend, options=opts)}
        print(json.dumps(to_jsonable(res), indent=2))
        return 0
    model, beam = res["model"], res["beam"]
    theory = "Timoshenko" if getattr(args, "beam_theory", None) == "timoshenko" \
        else "Euler-Bernoulli"
    print(f"{scenario.name} ({args.backend} trunk against the continuous {theory} beam)")
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
    jobs = []
    if args.with_study:
        from .sweep.study_job import StudyJob

        jobs.append(StudyJob(args.with_study, Path(args.out) / "study",
                             scenarios=args.scenarios))
    try:
        for job in jobs:
            job.start()
        paths = write_report(args.out, scenarios=scenarios, study_dirs=tuple(args.studies),
                             progress=True, study_jobs=tuple(jobs))
    finally:
        for job in jobs:
            job.stop()
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


def cmd_contact(args) -> int:
    from .contact_cmd import run

    return run(args)


def cmd_identify(args) -> int:
    from .identify_cmd import run

    return run(args)


def cmd_scenario(args) -> int:
    from .scenario_cmd import run

    return run(args)


COMMANDS = {"paper": cmd_paper, "simulate": cmd_simulate, "modes": cmd_modes,
            "report": cmd_report, "sweep": cmd_sweep, "scenario": cmd_scenario,
            "identify": cmd_identify, "contact": cmd_contact}


#: Exit code of an interrupted command (Ctrl-C or SIGTERM): 128 + SIGINT, as a shell says.
EXIT_INTERRUPTED = 130


def main(argv=None) -> int:
    import signal

    from .pool import STOP, on_stop_signal

    STOP.clear()
    previous = signal.signal(signal.SIGTERM, on_stop_signal)
    restore = {}
    try:
        args = build_parser().parse_args(argv)
        restore = _install_budget(getattr(args, "max_seconds", None))
        code = COMMANDS[args.command](args)
        if STOP.is_set() and code != EXIT_INTERRUPTED:  # asked after the last look
            raise KeyboardInterrupt
        return code
    except KeyboardInterrupt:
        print("treeimpact: interrupted (Ctrl-C or SIGTERM); nothing more was written",
              file=sys.stderr)
        return EXIT_INTERRUPTED
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
    finally:
        signal.signal(signal.SIGTERM, previous)
        _restore_budget(restore)


def _install_budget(max_seconds) -> dict:
    """For this command: ``--max-seconds`` as TREEIMPACT_MAX_SECONDS (its workers inherit it)
    and long runs' progress on stderr; what to restore afterwards (main() may be called from
    Python)."""
    import os
    import warnings

    from treeimpact.analytic import budget

    from .progress import Progress

    name = budget.VARIABLES["seconds"]
    restore = {"environment": (name, os.environ.get(name)), "reporter": budget._REPORTER,
               "showwarning": warnings.showwarning}
    warnings.showwarning = _one_line_warning
    if max_seconds is not None:
        if not (math.isfinite(max_seconds) and max_seconds > 0):
            raise ParameterError(f"--max-seconds = {max_seconds!r} s is out of range: allowed "
                                 "(0, inf) s")
        os.environ[name] = repr(float(max_seconds))
    budget.set_progress_reporter(lambda desc, total: Progress(total, desc, unit="step"))
    return restore


def _one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """A Python warning (numpy's, an engine's) as one stderr line, not a source excerpt."""
    text = " ".join(str(message).split())
    where = f"{Path(filename).name}:{lineno}"
    print(f"treeimpact: warning: {text} ({category.__name__}, {where})",
          file=file if file is not None else sys.stderr)


def _restore_budget(restore: dict) -> None:
    import os

    from treeimpact.analytic import budget

    if not restore:
        return
    import warnings

    warnings.showwarning = restore["showwarning"]
    name, value = restore["environment"]
    if value is None:
        os.environ.pop(name, None)
    else:
        os.environ[name] = value
    budget.set_progress_reporter(restore["reporter"])


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
