"""The generated blocks of the pages (``<!-- BEGIN generated: NAME -->``): one function per
block, from the numbers (``n``, :func:`.from_files.numbers`) and the checked-in results
files, giving the block's markdown (:data:`GENERATED`)."""

from __future__ import annotations

import json
import math

from .base import CONTACT_FIT, NUMBERS, TREES, TRUNKS_JSON
from .rerun import CONTACT_CASES


def _fmt(v: float, digits: int) -> str:
    return f"{v:.{digits}f}"


def _signed(v: float, digits: int) -> str:
    return f"{v:+.{digits}f}"


def _thousands(v: float) -> str:
    return f"{v:,.0f}".replace(",", " ")


def whole_event_table(n: dict) -> str:
    """docs/whole-event-metrics.md: the 1-DOF model -> the continuum on the shipped trees, as
    the report's answer table: the paper's (Newton) model, the soft one for the force and the
    acceleration (Newton's impulses have none)."""
    rows = ["| tree | energy delivered (J) | contact loss (J) | crown peak (mm) | crown "
            "acceleration (m/s^2) | contact force (kN) |", "|---|---|---|---|---|---|"]
    for t in TREES:
        cells = []
        for m, fmt in (("energy_delivered", lambda v: f"{v:.0f}"),
                       ("contact_dissipation", lambda v: f"{v:.0f}"),
                       ("crown_peak", lambda v: f"{v:.1f}"),
                       ("crown_peak_acceleration", lambda v: _thousands(round(v, -1))),
                       ("peak_force", lambda v: f"{v:.0f}")):
            one_dof = "contact" if m in ("crown_peak_acceleration", "peak_force") else "newton"
            a, b = n[f"value.{one_dof}.{m}.{t}"], n[f"value.beam.{m}.{t}"]
            cells.append(f"{fmt(a)} -> {fmt(b)} ({100 * (b / a - 1):+.0f} %)")
        rows.append(f"| {t} | " + " | ".join(cells) + " |")
    return "\n".join(rows) + "\n"


def mechanism_table(n: dict) -> str:
    """docs/whole-event-metrics.md: the 1-DOF model with the continuum's impact loss."""
    rows = ["| tree | e* | energy delivered gap at e -> at e* | x_max gap at e -> at e* | "
            "crown peak gap at e -> at e* |", "|---|---|---|---|---|"]
    for t in TREES:
        cells = [f"{n[f'mechanism.e_star.{t}']:.3f}"]
        for m in ("energy_delivered", "x_max", "crown_peak"):
            a, b = n[f"mechanism.gap_pct.{m}.{t}"], n[f"mechanism.matched_gap_pct.{m}.{t}"]
            cells.append(f"{a:+.1f} % -> {b:+.1f} %")
        rows.append(f"| {t} | " + " | ".join(cells) + " |")
    return "\n".join(rows) + "\n"


_TARGET_ORDER = ("V", "x0", "T0", "x_max", "tau", "theta_b")
_PARAM = {"contact_duration": ("pad", "ms", 3), "restitution": ("e", "", 3),
          "clamp_mass": ("clamp", "kg", 3)}


def contact_fit_table(n: dict) -> str:
    """docs/contact-law.md: every model against every measured number (the fit file)."""
    fit = json.loads(CONTACT_FIT.read_text())["contact_fit"]
    head = "| tree | model | fitted | dof | " + " | ".join(_TARGET_ORDER) + " | rms |"
    rows = [head, "|---|---|---|---:|" + "---:|" * len(_TARGET_ORDER) + "---:|"]
    for t in ("open-center", "central-leader"):
        for model, f in fit[t]["fits"].items():
            params = ", ".join(
                f"{_PARAM[p][0]} {n[f'fit.{t}.{model}.{p}']:.{_PARAM[p][2]}g}"
                f"{' ' + _PARAM[p][1] if _PARAM[p][1] else ''}"
                f"{' (bound)' if v['on_bound'] else ''}" for p, v in f["parameters"].items())
            cells = []
            for k in _TARGET_ORDER:
                r = n.get(f"fit.{t}.{model}.residual_pct.{k}")
                cells.append("n/a" if r is None else f"{r:+.0f} %"
                             + (" (explained)" if f["targets"][k]["explained"] else ""))
            rows.append(f"| {t} | {model} | {params} | {f['dof']} | " + " | ".join(cells)
                        + f" | {n[f'fit.{t}.{model}.rms_pct']:.0f} % |")
    return "\n".join(rows) + "\n"


def _trunks() -> dict:
    return json.loads(TRUNKS_JSON.read_text())


def trunks_cheapest_table(n: dict) -> str:
    """docs/engines.md: the cheapest MuJoCo run within 1 % of the continuum on x_max, per
    tree and trunk (compare/report/data/trunks.json, bench_trunks.py)."""
    rows = ["| tree | use | N | dt (s) | x default | x_max | energy delivered "
            "| s per simulated s |", "|---|---|---|---|---|---|---|---|"]
    for tree, sc in _trunks()["scenarios"].items():
        for c in sc["cheapest"]:
            row = next(r for r in sc["rows"]
                       if r["model"] == c["model"] and r["segments"] == c["segments"])
            factor = next(r["factor"] for r in row["runs"] if r["dt"] == c["dt"])
            rows.append(f"| {tree} | `--trunk {c['model']}` | {c['segments']} | {c['dt']:.2g} "
                        f"| {factor:g} | {c['x_max_error']:+.2%} | "
                        f"{c['energy_delivered_error']:+.2%} | "
                        f"{c['wall_per_simulated_s']:.2g} |")
    return "\n".join(rows) + "\n"


def trunks_segments_table(n: dict) -> str:
    """docs/engines.md: central-leader's MuJoCo trunks per segment count at the default step
    (benchmarks/results/trunks.json; ``bench_trunks.py --table`` prints every tree)."""
    return "\n".join(trunk_rows_table(_trunks()["scenarios"]["central-leader"]["rows"])) + "\n"


def trunk_rows_table(trunk_rows: list) -> list[str]:
    """The markdown lines of one tree's rows of trunks.json (bench_trunks.py): each (model,
    N) at the runner's default step, errors against the continuum, steps and cost."""
    rows = ["| trunk | N | static K at a | omega_1 | omega_2 | x_max | energy delivered "
            "| default dt (s) | largest stable dt, trunk (s) | runner's limit (s) "
            "| s per simulated s |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for row in trunk_rows:
        run = row["runs"][0]
        w1, w2 = row["omega_errors"]
        rows.append(
            f"| {row['model']} | {row['segments']} | {row['static_stiffness_error']:+.2%} "
            f"| {w1:+.2%} | {w2:+.2%} | {run['x_max_error']:+.2%} "
            f"| {run['energy_delivered_error']:+.2%} | {row['default_dt']:.2g} "
            f"| {row['trunk_stable_dt']:.2g} | {row['runner_limit']:.2g} "
            f"| {run['wall_per_simulated_s']:.3g} |")
    return rows


def timoshenko_table(n: dict) -> str:
    """docs/beam-impact.md: Timoshenko against Euler-Bernoulli on the shipped trees."""
    rows = ["| tree | E / G | x_max | energy_delivered | omega_1 | omega_2 |",
            "|---|---|---|---|---|---|"]
    for t in TREES:
        cells = []
        for k, d in (("x_max", 2), ("energy_delivered", 2), ("omega_1", 2), ("omega_2", 1)):
            vals = [n[f"timoshenko.e_over_g{r}.{k}_pct.{t}"] for r in (10, 13, 20)]
            cells.append(" / ".join(_signed(v, d) for v in vals) + " %")
        rows.append(f"| {t} | 10 / 13 / 20 | " + " | ".join(cells) + " |")
    return "\n".join(rows) + "\n"


def beam_cost_table(n: dict) -> str:
    """docs/beam-impact.md: bench_beam's medians (benchmarks/results/beam-12.json, -48)."""
    rows = ["| elements | `exact-full` (original) | `exact` | ratio | x_max, energy_delivered |",
            "|---|---|---|---|---|"]
    for e in (12, 48):
        b = f"bench.beam-{e}"
        full, exact, ratio = n[f"{b}.exact_full_ms"], n[f"{b}.exact_ms"], n[f"{b}.ratio"]
        dx, de = n[f"{b}.x_max_rel_diff"][1], n[f"{b}.energy_delivered_rel_diff"][1]
        rows.append(f"| {e} | {full[0]:.0f}-{full[1]:.0f} ms | {exact[0]:.1f}-{exact[1]:.1f} ms "
                    f"| {ratio[0]:.1f}-{ratio[1]:.1f} | the same to {dx:.0e}, {de:.0e} |")
    return "\n".join(rows) + "\n"


def solver_cost_table(n: dict) -> str:
    """docs/solver.md: bench_solver's medians (benchmarks/results/solver.json)."""
    rows = ["| scenario | simulate | + reading the trajectory | quadrature integrals, "
            "trajectory up front | ratio |", "|---|---|---|---|---|"]
    for t in TREES:
        b = "bench.solver"
        rows.append(f"| {t} | {n[f'{b}.simulate_ms.{t}']:.3f} | "
                    f"{n[f'{b}.with_trajectory_ms.{t}']:.3f} | "
                    f"{n[f'{b}.quadrature_ms.{t}']:.3f} | {n[f'{b}.ratio.{t}']:.1f} |")
    return "\n".join(rows) + "\n"


def _option_values(option) -> str:
    if option.choices:
        return ", ".join(f"`{c}`" for c in option.choices)
    kind = "integer" if option.kind is int else "number"
    low = "-inf" if option.low is None else f"{option.low:g}"
    high = "inf" if option.high is None else f"{option.high:g}"
    unit = f" {option.unit}" if option.unit not in ("", "1") else ""
    return f"{kind} in {'(' if option.low_open else '['}{low}, {high}]{unit}"


def preset_slice_table(n: dict) -> str:
    """docs/sweeps.md: a chain run's wall time per engine and segment count on the full
    preset's slice (benchmarks/results/presets.json)."""
    counts = (1, 2, 4, 8, 16, 32)
    rows = ["| segments | " + " | ".join(str(c) for c in counts) + " |",
            "|---|" + "---|" * len(counts)]
    for engine, label in (("mujoco", "MuJoCo"), ("bullet", "Bullet")):
        cells = []
        for c in counts:
            lo, hi = n[f"bench.presets.run_s.{engine}.{c}"]
            cells.append(f"{lo:.2g}-{hi:.2g} s")
        rows.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(rows) + "\n"


def contact_settings_table(n: dict) -> str:
    """docs/contact-settings.md: ``treeimpact contact`` on :data:`CONTACT_CASES`."""
    rows = ["| m1, m2 (kg) | target e, duration | dt (steps) | MuJoCo e, duration | MuJoCo "
            "naive e | Bullet e, duration | Bullet naive e |", "|---|---|---|---|---|---|---|"]
    for i, (m1, m2, e, duration, dt) in enumerate(CONTACT_CASES):
        k = f"contact_cmd.{i}"
        other = "fixed" if math.isinf(m2) else f"{m2:g}"
        mj = (f"{n[f'{k}.mujoco.e']:.6f}, {n[f'{k}.mujoco.duration_pct']:+.2f}% (timeconst "
              f"{n[f'{k}.mujoco.timeconst_e']:.6f})")
        bl = f"{n[f'{k}.bullet.e']:.6f}, {n[f'{k}.bullet.duration_pct']:+.2f}%"
        rows.append(f"| {m1:g}, {other} | {e:g}, {1e3 * duration:g} ms | {dt:g} s "
                    f"({n[f'{k}.steps']}) | {mj} | {n[f'{k}.mujoco.naive_e']:.4f} "
                    f"({n[f'{k}.mujoco.naive_miss']:+.4f}) | {bl} | "
                    f"{n[f'{k}.bullet.naive_e']:.4f} ({n[f'{k}.bullet.naive_miss']:+.4f}) |")
    return "\n".join(rows) + "\n"


def _backend_option_variants() -> dict:
    """option name -> [(Option, [backends])]: one entry per distinct definition (Bullet's
    --trunk takes fewer words than MuJoCo's)."""
    from treeimpact.analytic.errors import ParameterError
    from treeimpact.compare.runs.backends import BACKENDS

    out: dict = {}
    for name, backend in BACKENDS.items():
        try:
            table = backend.options()
        except ParameterError:  # a backend that is not installed
            continue
        for key, option in table.items():
            variants = out.setdefault(key, [])
            for known, takers in variants:
                if (known.kind, known.low, known.high, known.low_open, known.unit) == (
                        option.kind, option.low, option.high, option.low_open, option.unit):
                    takers.append(name)
                    break
            else:
                variants.append((option, [name]))
    return out


def options_table(names=None) -> str:
    """The flags the backends' OPTIONS give ``simulate`` (or ``modes``: ``names``)."""
    rows = ["| option | values | backends | what |", "|---|---|---|---|"]
    for key, variants in sorted(_backend_option_variants().items()):
        for option, takers in variants:
            if not option.cli or (names is not None and key not in names):
                continue
            rows.append(f"| `--{key.replace('_', '-')}` | {_option_values(option)} | "
                        f"{', '.join(takers)} | {option.help.replace('%%', '%')} |")
    return "\n".join(rows) + "\n"


def simulate_options(n: dict) -> str:
    """docs/cli.md: ``treeimpact simulate``'s backend options."""
    return options_table()


def modes_options(n: dict) -> str:
    """docs/cli.md: ``treeimpact modes``'s backend options."""
    from treeimpact.compare.interface.commands.modes import MODES_OPTIONS

    return options_table(MODES_OPTIONS)


def sweep_grid_names(n: dict) -> str:
    """docs/cli.md: the names a ``--grid`` axis may take besides dotted scenario fields."""
    from treeimpact.compare.studies.sweep.grid import ALIASES, DERIVED_RATIOS, RECORD_FIELDS

    rows = ["| NAME | what |", "|---|---|"]
    for name, target in sorted(ALIASES.items()):
        rows.append(f"| `{name}` | the scenario's `{target}` |")
    for name, (_, meaning) in DERIVED_RATIOS.items():
        rows.append(f"| `{name}` | {meaning} |")
    for key, variants in sorted(_backend_option_variants().items()):
        for option, takers in variants:
            if option.cli and key not in ALIASES:
                extra = " (1: the engine's SDOF trunk)" if key == "segments" else ""
                rows.append(f"| `{key}` | the option `--{key.replace('_', '-')}` of "
                            f"{', '.join(takers)}: {_option_values(option)}{extra} |")
    for name, (_, _, _, unit) in RECORD_FIELDS.items():
        unit = f" ({unit})" if unit not in ("", "1") else ""
        rows.append(f"| `record.{name}` | the sampling of a record{unit}: only in a sweep "
                    "with an analysis (the identification validation) |")
    return "\n".join(rows) + "\n"


#: The generated blocks: name -> function of the numbers giving the block's text.
def measure_first_list(n: dict) -> str:
    """README: what to measure first on each tree, the report's own sentences (docs/numbers.json
    ``texts``, from report.json's answer rows)."""
    texts = json.loads(NUMBERS.read_text())["texts"]["measure_first"]
    return "".join(f"  - {tree}: {said}\n" for tree, said in texts.items())


def design_answer_list(n: dict) -> str:
    """README: the design answer on each tree with a design study, the report's own sentences
    (docs/numbers.json ``texts``, from report.json's answer.design)."""
    texts = json.loads(NUMBERS.read_text())["texts"]["design"]
    return "".join(f"  - {tree}: {said}\n" for tree, said in texts.items())


def _phases_file() -> dict:
    from .base import ROOT

    return json.loads((ROOT / "benchmarks" / "results" / "chain_phases.json").read_text())


def _case_name(case: list) -> str:
    scen, engine, opts = case
    tree = scen.rsplit("/", 1)[-1].removesuffix(".toml")
    return f"{tree} | {engine} | {opts['trunk']}, {opts['pendulum']}"


def _worst(metrics: dict, key: str) -> str:
    name, row = max(metrics.items(), key=lambda kv: kv[1][key] / kv[1]["tolerance"])
    return f"{row[key] / row['tolerance']:.3f} ({name})"


def engine_phases_table(n: dict) -> str:
    """docs/engines.md: stepping by phase against the fixed step per case
    (benchmarks/results/chain_phases.json): steps and wall, and the largest share of its
    stated tolerance a metric's dt/2 and phased changes take."""
    rows = ["| tree | engine | trunk, pendulum | steps fixed -> phased | wall ratio | "
            "dt/2 vs dt, largest share of tolerance | phased vs dt, largest share | all within |",
            "|---|---|---|---|---|---|---|---|"]
    for c in _phases_file()["details"]["cases"]:
        cv, tm = c["convergence"], c["timing"]
        rows.append(f"| {_case_name(c['case'])} | {tm['fixed_steps']:,} -> "
                    f"{tm['phased_steps']:,} | {tm['ratio']:.2f} | "
                    f"{_worst(cv['metrics'], 'converged')} | "
                    f"{_worst(cv['metrics'], 'phased_change')} | "
                    f"{'yes' if cv['all_within'] else 'no'} |")
    return "\n".join(rows) + "\n"


def engine_phases_metrics_table(n: dict) -> str:
    """docs/engines.md: per judged metric, over every case of chain_phases.json, the largest
    relative change of the fixed step at dt/2 and of the phased run, against dt, and the
    stated tolerance (the tightest over the cases)."""
    cases = _phases_file()["details"]["cases"]
    names = list(cases[0]["convergence"]["metrics"])
    rows = ["| metric | dt/2 vs dt (largest) | phased vs dt (largest) | stated tolerance |",
            "|---|---|---|---|"]
    for m in names:
        got = [c["convergence"]["metrics"][m] for c in cases
               if m in c["convergence"]["metrics"]]
        tol = min(r["tolerance"] for r in got)
        what = "one contact step" if m == "first_contact_duration" else f"{tol:.3g}"
        rows.append(f"| {m} | {max(r['converged'] for r in got):.1e} | "
                    f"{max(r['phased_change'] for r in got):.1e} | {what} |")
    return "\n".join(rows) + "\n"


GENERATED = {"engine-phases-table": engine_phases_table,
             "engine-phases-metrics": engine_phases_metrics_table, "measure-first-list": measure_first_list, "design-answer": design_answer_list,"whole-event-table": whole_event_table, "mechanism-table": mechanism_table,
             "contact-fit-table": contact_fit_table, "timoshenko-table": timoshenko_table,
             "beam-cost-table": beam_cost_table, "solver-cost-table": solver_cost_table,
             "trunks-cheapest-table": trunks_cheapest_table,
             "trunks-segments-table": trunks_segments_table,
             "simulate-options": simulate_options, "modes-options": modes_options,
             "sweep-grid-names": sweep_grid_names,
             "contact-settings-table": contact_settings_table,
             "preset-slice-table": preset_slice_table}
