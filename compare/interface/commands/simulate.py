"""``treeimpact simulate SCENARIO``: one run on one backend, printed key by key beside the
paper's model (or as JSON), optionally written as a pendulum-test record (SI units)."""

from __future__ import annotations

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.metrics import METRIC_UNITS
from treeimpact.analytic.model.registry import units_of
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.analytic.results import json_text
from treeimpact.compare.runs.backends import BACKENDS
from treeimpact.compare.runs.provenance import provenance
from treeimpact.compare.runs.recording import DEFAULTS, REST, check_sampling, sample

from ...runs.exits import ExitCode
from ._common import (
    add_budget_flag,
    add_option_flags,
    backend_options,
    count,
    fmt,
    number,
    options_of,
    relative_text,
    unit_text,
)

NAME = "simulate"
#: Removed spellings -> their names now (compare.runs.names).
RENAMED = {"damping": "trunk_damping_model", "release_angle": "release_angle_deg"}


def add_arguments(sp) -> None:
    """The command's flags, added to its subparser ``sp``: the backend, its options (from
    the backends' OPTIONS), the run budget, --json and the record flags."""
    sp.add_argument("scenario", help="shipped scenario name or TOML path")
    sp.add_argument("--backend", default="analytic", choices=tuple(BACKENDS),
                    help="the model to run (default: analytic, the paper's)")
    add_option_flags(sp)
    add_budget_flag(sp)
    sp.add_argument("--json", action="store_true", help="machine-readable output")
    add_record_arguments(sp)


#: Units of the ``model`` keys every backend reports (README); others print without one.
MODEL_UNITS = {**units_of("M_T", "C_T", "K_T", "m", "k", "restitution", "contact_stiffness"),
               "u1": units_of("u_1")["u_1"], "dt": "s", "contact_damping": units_of("c_c")["c_c"],
               "engine_contact_stiffness": "N/m", "engine_contact_damping": "N s/m",
               "effective_mass": "kg",
               "contact_reduced_mass": "kg", "pad_damping_ratio": "1",
               "touch_duration": "s", "contact_duration": "s", "omega_max": "rad/s"}


#: Metrics printed without a relative difference: a count and a numerical residual.
_NO_DIFFERENCE = ("n_impacts", "ledger_residual")


def print_simulation(scenario, result, reference) -> None:
    """The text output of ``result`` (a run of ``scenario``): one key per line, units in
    their own column; beside a backend's value the paper's model (the analytic backend) and
    the relative difference, when ``reference`` (its result) is given."""
    print(f"{scenario.name} ({result.backend})")
    print("model:")
    # every column as wide as its widest cell, header included (crown_peak_acceleration,
    # 23 characters, pushed its row out of a 22-wide column)
    wk = max(len(k) for k in ("metric", *result.model, *result.metrics)) + 1
    wv = max(14, len(result.backend) + 1, *(len(fmt(v)) + 1 for v in result.metrics.values()))
    for key, value in result.model.items():
        text = fmt(value) if not isinstance(value, (list, tuple)) else " ".join(
            fmt(v) for v in value)
        print(f"  {key:<{wk}}{text:>{wv}}  {unit_text(MODEL_UNITS.get(key, ''))}")
    head = f"  {'metric':<{wk}}{result.backend:>{wv}}  {'unit':<7}"
    if reference is not None:
        head += f"{'paper model':>{wv}}{'difference':>12}"
    print("metrics:" if reference is None else "metrics (paper model: the analytic backend, "
          "eqs 12-35):")
    print(head + "  meaning")
    for key, value in result.metrics.items():
        unit, meaning = METRIC_UNITS[key]
        line = f"  {key:<{wk}}{fmt(value):>{wv}}  {unit_text(unit):<7}"
        if reference is not None:
            ref = reference.metrics.get(key)
            diff = "" if key in _NO_DIFFERENCE else relative_text(value, ref)
            line += f"{fmt(ref):>{wv}}{diff:>12}"
        print(line + f"  {meaning}")


def run(args) -> int:
    """Run the scenario on the backend of the parsed command line ``args`` and print it
    (text or ``--json``; with ``--record`` also write the record); exit code 0."""
    # lazy: +250 ms at import otherwise (the API's modules, numpy), which --help does not need
    from treeimpact.compare.interface.api import simulate

    scenario = load_scenario(args.scenario)
    opts = options_of(args, backend_options())
    check_record_arguments(args)
    result = simulate(scenario, args.backend, **opts).result
    written = write_record(args, scenario, result) if args.record else None
    if args.json:
        out = result.to_json() | {"provenance": provenance(scenario, result, options=opts)}
        print(json_text(out, indent=2))
        return ExitCode.OK
    reference = None
    if args.backend != "analytic":  # the paper's model beside it (a few ms)
        opts = options_of(args, ("restitution", "t_end"))
        reference = simulate(scenario, "analytic", **opts).result
    print_simulation(scenario, result, reference)
    if written:
        print(written)
    return ExitCode.OK


def add_record_arguments(sp) -> None:
    """`treeimpact simulate --record FILE.csv [--rate HZ --noise FRAC --seed N]`: the flags,
    added to the subparser ``sp``."""
    sp.add_argument("--record", help="also write the trunk's displacement as a pendulum-test "
                                     "record (CSV 't [s],x [m]', what `identify` reads)")
    sp.add_argument("--rate", type=number,
                    help=f"--record: sampling rate, Hz (default {DEFAULTS['rate']:g})")
    sp.add_argument("--noise", type=number,
                    help="--record: Gaussian noise, a fraction of the peak (default "
                         f"{DEFAULTS['noise']:g})")
    sp.add_argument("--seed", type=count,
                    help=f"--record: the noise's seed (default {DEFAULTS['seed']})")


def check_record_arguments(args) -> None:
    """--rate, --noise and --seed of the parsed command line ``args`` in range (one line
    each) and only with --record (they would be ignored without it), before a run is spent;
    fills in their defaults."""
    for key, default in DEFAULTS.items():
        if getattr(args, key) is not None and not args.record:
            raise ParameterError(f"--{key}: only with --record FILE.csv (it sets the "
                                 "record's sampling; without --record nothing is recorded)")
        if getattr(args, key) is None:
            setattr(args, key, default)
    if args.record:
        check_sampling(args.rate, args.noise, args.seed)


def write_record(args, scenario, result) -> str:
    """Write ``result``'s trunk displacement (a run of ``scenario``) as a record
    (compare.runs.recording.sample at
    ``args.rate`` Hz, ``args.noise`` of the peak, ``args.seed``) to ``args.record``; returns
    a one-line summary. Raises ParameterError naming --record if it cannot be written."""
    t, x = sample(result, args.rate, args.noise, args.seed)
    try:
        with open(args.record, "w", encoding="utf-8") as f:
            f.write(f"# {scenario.name} ({result.backend}), {args.rate:g} Hz, noise "
                    f"{args.noise:g} of the peak, seed {args.seed}; impact at t = "
                    f"{REST:g} s\n")
            f.write("t [s],x [m]\n")
            f.writelines(f"{a:.9g},{b:.9g}\n" for a, b in zip(t, x))
    except OSError as exc:
        raise ParameterError(f"--record {args.record!r}: cannot be written "
                             f"({exc.strerror or exc})") from None
    return f"record: {args.record} ({t.size} samples at {args.rate:g} Hz, noise {args.noise:g})"
