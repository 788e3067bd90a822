"""Benchmark: the exact impact solver against a scipy solve_ivp event-driven integration.

Both do the same work on the paper's scenarios: the impact sequence, moving together and
separation (``--through separation``, the default) or everything up to t_end. Prints the
median wall time of each (repeats interleaved so machine noise hits both alike) and their
ratio, then the accuracy of each against a tighter reference.

Accuracy, like with like (the quantities the metrics report, :func:`impact_metrics`):

* the impact times tau_i common to all three;
* T0, the time the bodies start moving together, and V, the trunk velocity at T0. For the
  exact solver T0 is the accumulation point of the chattering sequence (the tail closed by
  the bouncing-ball sum) and V = state(T0). solve_ivp (default tolerances) resolves impacts
  until the relative velocity falls below gamma_tol = 1e-7 u1 and then moves together: its
  T0 and V are those of that switch (what it reports; nothing is added to it).
* The reference is solve_ivp at rtol 3e-14 (near the 100 eps DOP853 allows; the default
  atol, 1e-15 m on positions, would bind before rtol 1e-12, so atol is scaled with rtol),
  resolving the same impacts (gamma_tol 1e-7 u1), whose remaining chattering tail is then
  summed as a geometric series from its last impact: T0_ref = t_n + 2 gamma_n /
  (|a_rel| (1 - e)), V_ref = vc + a_c dt + j_c dt^2 / 2 (moving together over that dt,
  ~2e-9 s). The sum's own error, O(dt^2 |a_rel'| / |a_rel|), is ~1e-17 s here; without it
  the reference would stop dt early, like solve_ivp. Resolving more impacts instead would
  not make it more accurate: below gamma ~ 1e-8 u1 the gap x - y of a flight is below the
  round-off of x and y, and solve_ivp reports spurious impacts (separating, u - U < 0;
  refused here).
* The reference's uncertainty ("ref+-") is its spread to the same run at rtol 1e-13 plus a
  round-off floor: an impact time found from the gap x - y cannot be better than
  ~eps |x| / (u - U) (~3e-13 s for the last resolved impacts, in any integrator of x and y;
  the exact solver computes the gap from the displacements since the last impact and has no
  such floor). "x" is the deviation in units of ref+- (per impact for tau_i, the worst is
  shown); within 2 ref+- counts as agreement with the reference.

Targets (issue 2): a paper scenario through separation in under 0.2 ms median, at least
50 times faster than solve_ivp, with the exact solver the more accurate of the two.

Then (issue 39) ``ti.simulate`` through the public API against the code of ``--baseline``
(default ee677a4) in fresh processes, alternating, ``--rounds`` a side (target: 0.3 ms),
with every metric of the 53 cases of tests/data/newton_metrics.json computed by both (1e-9
relative, bitwise where the arithmetic is unchanged), and the floor estimated from the
evaluations one run makes (:func:`_floor`).

    python benchmarks/bench_solver.py [--repeats 200] [--through separation|t_end]
        [--baseline ee677a4] [--rounds 5]
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from pathlib import Path

from treeimpact.analytic.impact.ivp_reference import solve_ivp_impacts
from treeimpact.analytic.impact.simulate import impact_metrics
from treeimpact.analytic.impact.solver import solve_impacts
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.analytic.model.two_body import two_body_model

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results  # noqa: E402  (and _baseline, imported where used)

_DEFAULT_ATOL = (1e-15, 1e-12, 1e-15, 1e-12)  # solve_ivp_impacts' default
_EPS = 2.220446049250313e-16


def _time(fn, repeats: int) -> list[float]:
    out = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return out


def _reference(model, t_end, stop, rtol):
    """Impact times, T0, V of solve_ivp at rtol, its chattering tail summed (see the doc),
    and their round-off floors (s, s, m/s)."""
    atol = tuple(a * rtol / 1e-12 for a in _DEFAULT_ATOL)
    ref = solve_ivp_impacts(model, t_end, rtol=rtol, atol=atol, stop_at_separation=stop)
    M, C, K = model.dynamic_mass, model.equivalent_damping, model.equivalent_stiffness
    m, k, e = model.impactor_mass, model.impactor_stiffness, model.restitution
    if any(u - U <= 0.0 for _, U, u, _, _ in ref["impacts"]):
        raise RuntimeError("reference: a spurious (separating) impact; gamma_tol too small")
    t_sw, x, vc = ref["together"][0]
    t_n, _, _, V_n, v_n = ref["impacts"][-1]
    dt = 0.0
    if t_n == t_sw and V_n - v_n > 0.0 and e < 1.0:  # a chattering tail is left: sum it
        a_rel = (-K * x - C * V_n) / M + k * x / m
        dt = 2.0 * (V_n - v_n) / (-a_rel * (1.0 - e))
    a_c = (-(K + k) * x - C * vc) / (M + m)  # moving together from the switch, eq 34
    j_c = (-(K + k) * vc - C * a_c) / (M + m)
    # Round-off floor of an impact time: an error ~eps |x| in the gap x - y over the
    # approach velocity u - U (x at the switch, the largest of the chattering sequence).
    floors = [_EPS * abs(x) / (u - U) for _, U, u, _, _ in ref["impacts"]]
    floor_t0 = floors[-1] if t_n == t_sw else 0.0
    return ([imp[0] for imp in ref["impacts"]], t_sw + dt, vc + a_c * dt + 0.5 * j_c * dt * dt,
            floors, floor_t0, abs(a_c) * floor_t0 + _EPS * abs(vc))


def _verdict(r_exact: float, r_ivp: float) -> str:
    """From the deviations in units of the reference's uncertainty."""
    if max(r_exact, r_ivp) <= 2.0:
        return "neither: both within the reference's uncertainty"
    if r_exact <= 2.0 or r_exact < r_ivp:
        return "exact"
    return "solve_ivp"


def _bench_simulate(names, repeats: int) -> dict:
    """analytic.impact.simulate (solver, every metric, the ledger; closed forms, trajectory sampled
    on first read) against: the same plus reading the 2001-sample trajectory, and the code
    before issue 13's speed work (phase integrals by quadrature, trajectory sampled up front),
    interleaved; and the largest difference of any metric between closed and quadrature."""
    from contextlib import contextmanager

    from treeimpact.analytic.impact.simulate import simulate
    from treeimpact.analytic.impact.solver import ImpactSolution

    @contextmanager
    def quadrature():
        closed = ImpactSolution._phase_integral
        ImpactSolution._phase_integral = ImpactSolution._phase_integral_quadrature
        try:
            yield
        finally:
            ImpactSolution._phase_integral = closed

    def with_trajectory(scenario):
        return simulate(scenario).trajectory.x

    out: dict = {}
    print(f"\nanalytic.simulate: {'scenario':16s} {'ms':>6s} {'+traj ms':>8s} "
          f"{'before ms':>9s} {'ratio':>6s} {'max metric rel diff':>19s}")
    worst = 0.0
    for name in names:
        scenario = load_scenario(name)
        now_t, traj_t, before_t = [], [], []
        for _ in range(max(3, repeats // 20)):
            now_t += _time(lambda: simulate(scenario), 10)
            traj_t += _time(lambda: with_trajectory(scenario), 10)
            with quadrature():
                before_t += _time(lambda: with_trajectory(scenario), 10)
        a = simulate(scenario).metrics
        with quadrature():
            b = simulate(scenario).metrics
        diff = max(abs(a[k] - b[k]) / max(abs(b[k]), 1e-300) for k in a
                   if isinstance(a[k], float) and math.isfinite(a[k]) and k != "ledger_residual")
        mn, mt, mb = (statistics.median(x) * 1e3 for x in (now_t, traj_t, before_t))
        worst = max(worst, mn)
        print(f"{'':19s}{name:16s} {mn:6.3f} {mt:8.3f} {mb:9.3f} {mb / mn:6.1f} {diff:19.1e}")
        out |= {f"simulate_ms.{name}": round(mn, 4), f"with_trajectory_ms.{name}": round(mt, 4),
                f"quadrature_ms.{name}": round(mb, 4), f"ratio.{name}": round(mb / mn, 2),
                f"metric_rel_diff.{name}": diff}
    print(f"target (issue 13): simulate < 0.3 ms median: {'met' if worst < 0.3 else 'NOT met'}"
          f" (worst {worst:.3f} ms)")
    return out


#: Run in fresh processes by :func:`_bench_baseline`, old code and new alternating: the
#: medians of ti.simulate (the public API, backend analytic) and of the solver alone per
#: tree, and the metrics of the equivalence cases (tests/data/newton_metrics.json's).
_API_SNIPPET = """
import json, statistics, sys, time
import treeimpact as ti
from treeimpact.analytic.impact.solver import solve_impacts
from treeimpact.analytic.model.two_body import two_body_model
from treeimpact.compare.studies.sweep.apply import apply_point
REPEATS = int(sys.argv[1])
def median_us(fn):
    fn()
    out = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return statistics.median(out) * 1e6
res = {}
for name in ("open-center", "central-leader", "realistic-crown"):
    s = ti.load_scenario(name)
    model = two_body_model(s)
    res["api_us." + name] = median_us(lambda: ti.simulate(s))
    res["solve_us." + name] = median_us(lambda: solve_impacts(model, s.t_end))
cases = json.loads(sys.stdin.read()) if len(sys.argv) > 2 else []
metrics = []
for case in cases:
    scen, options = apply_point(ti.load_scenario(case["scenario"]), case["point"])
    m = ti.simulate(scen, backend="analytic", **options).metrics
    metrics.append({k: getattr(m, k) for k in m.__dataclass_fields__})
print(json.dumps({"times": res, "metrics": metrics}))
"""


def _run_side(site, repeats: int, cases: list | None) -> dict:
    """One fresh process of :data:`_API_SNIPPET` with ``site`` first on sys.path (None:
    today's package), one BLAS thread as the library sets it."""
    import json
    import os
    import subprocess
    import tempfile

    env = dict(os.environ)
    if site is not None:
        env["PYTHONPATH"] = os.pathsep.join([str(site), env.get("PYTHONPATH", "")])
    argv = [sys.executable, "-c", _API_SNIPPET, str(repeats)] + (["cases"] if cases else [])
    with tempfile.TemporaryDirectory(prefix="treeimpact-bench-") as cwd:
        proc = subprocess.run(argv, input=json.dumps(cases or []), capture_output=True,
                              text=True, env=env, cwd=cwd)
    if proc.returncode != 0:
        raise RuntimeError(f"snippet failed ({site or 'installed'}):\n{proc.stderr[-3000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _rel(new, old) -> float:
    """|new - old| / |old| (0 for equal values, NaN beside NaN included)."""
    if new == old or (isinstance(old, float) and math.isnan(old) and math.isnan(new)):
        return 0.0
    return abs(new - old) / abs(old) if old else math.inf


def _bench_baseline(rev: str, rounds: int, repeats: int) -> dict:
    """ti.simulate of the three trees, old code (``rev``) against today's in fresh processes,
    alternating (medians of the rounds' medians, ratio old / new), and every metric of the
    53 equivalence cases of both (the largest relative difference, how many are bitwise
    equal)."""
    import json

    from _baseline import baseline_tree

    fixture = Path(__file__).resolve().parents[1] / "tests" / "data" / "newton_metrics.json"
    cases = [{"scenario": c["scenario"], "point": c["point"]}
             for c in json.loads(fixture.read_text())["cases"] if "error" not in c]
    times: dict = {"old": [], "new": []}
    with baseline_tree(rev) as old:
        sides = {"old": old, "new": None}
        metrics = {side: _run_side(site, 1, cases)["metrics"] for side, site in sides.items()}
        for r in range(rounds):
            for side in (("old", "new") if r % 2 == 0 else ("new", "old")):
                times[side].append(_run_side(sides[side], repeats, None)["times"])
    out: dict = {}
    print(f"\nti.simulate (API, analytic), {rev} against today, {rounds} fresh processes "
          f"each, {repeats} runs a process, medians in us:")
    print(f"{'scenario':16s} {'old API':>8s} {'new API':>8s} {'ratio':>6s} "
          f"{'old solve':>9s} {'new solve':>9s}")
    for name in ("open-center", "central-leader", "realistic-crown"):
        med = {f"{side}.{what}": statistics.median(t[f"{what}_us.{name}"] for t in times[side])
               for side in times for what in ("api", "solve")}
        ratio = med["old.api"] / med["new.api"]
        print(f"{name:16s} {med['old.api']:8.1f} {med['new.api']:8.1f} {ratio:6.2f} "
              f"{med['old.solve']:9.1f} {med['new.solve']:9.1f}")
        out |= {f"api_us.old.{name}": round(med["old.api"], 1),
                f"api_us.new.{name}": round(med["new.api"], 1),
                f"api_ratio.{name}": round(ratio, 2),
                f"solve_us.old.{name}": round(med["old.solve"], 1),
                f"solve_us.new.{name}": round(med["new.solve"], 1)}
    diffs = [_rel(n[k], o[k]) for n, o in zip(metrics["new"], metrics["old"]) for k in o]
    out |= {"equivalence.cases": len(cases), "equivalence.metrics": len(diffs),
            "equivalence.bitwise": sum(d == 0.0 for d in diffs),
            "equivalence.max_rel_diff": max(diffs)}
    print(f"equivalence on {len(cases)} cases: {out['equivalence.bitwise']} of {len(diffs)} "
          f"metrics bitwise equal, the largest relative difference {max(diffs):.1e} "
          "(bound 1e-9)")
    return out


def _floor(names) -> dict:
    """The floor estimated per tree: what the exact solution must evaluate, at the cost of
    the bare evaluations, without the bookkeeping around them. The closed-form advances
    (eq 13/34, one oscillator at one time) and derivative bounds the solver and the metrics
    make in one run are counted (each oscillator's cached closures wrapped), the impacts
    too (eqs 20-21); floor = advances x the cost of one + bounds x theirs + impacts x a
    Newton impact's, each cost the median of a timed loop."""
    import timeit

    from treeimpact.analytic.impact.newton import newton_impact
    from treeimpact.analytic.impact.oscillator import Oscillator

    def cost_us(fn):
        return min(timeit.repeat(fn, number=20000, repeat=5)) / 20000 * 1e6

    out: dict = {}
    print("\nfloor: evaluations of one run (solver + metrics) x their bare cost")
    print(f"{'scenario':16s} {'impacts':>7s} {'advances':>8s} {'bounds':>6s} {'floor us':>8s}")
    for name in names:
        scenario = load_scenario(name)
        model = two_body_model(scenario)
        oscs = {Oscillator.from_mck(model.dynamic_mass, model.equivalent_damping,
                                    model.equivalent_stiffness),
                Oscillator.from_mck(model.impactor_mass, 0.0, model.impactor_stiffness),
                Oscillator.from_mck(model.dynamic_mass + model.impactor_mass,
                                    model.equivalent_damping,
                                    model.equivalent_stiffness + model.impactor_stiffness)}
        counts = {"scalar_advance": 0, "_bounds5": 0}
        saved = {}
        for osc in oscs:
            for attr in counts:
                fn = saved[(osc, attr)] = getattr(osc, attr)
                osc.__dict__[attr] = (lambda f, a: lambda *args: (
                    counts.__setitem__(a, counts[a] + 1), f(*args))[1])(fn, attr)
        try:
            sol = solve_impacts(model, scenario.t_end)
            impact_metrics(sol, scenario)
        finally:
            for (osc, attr), fn in saved.items():
                osc.__dict__[attr] = fn
        tree = Oscillator.from_mck(model.dynamic_mass, model.equivalent_damping,
                                   model.equivalent_stiffness)
        adv, bnd = tree.scalar_advance, tree._bounds5
        t_adv = cost_us(lambda: adv(1e-3, 1e-3, 0.5))
        t_bnd = cost_us(lambda: bnd(1e-3, 0.5))
        M, m, e = model.dynamic_mass, model.impactor_mass, model.restitution
        mu = model.reduced_mass
        t_imp = cost_us(lambda: newton_impact(1, 0.0, 0.0, 0.0, 1.0, M, m, e, mu))
        n_imp = len(sol.impacts)
        floor = counts["scalar_advance"] * t_adv + counts["_bounds5"] * t_bnd + n_imp * t_imp
        print(f"{name:16s} {n_imp:7d} {counts['scalar_advance']:8d} {counts['_bounds5']:6d} "
              f"{floor:8.1f}")
        out |= {f"floor_us.{name}": round(floor, 1),
                f"floor.advances.{name}": counts["scalar_advance"],
                f"floor.bounds.{name}": counts["_bounds5"], f"floor.impacts.{name}": n_imp,
                f"floor.advance_us.{name}": round(t_adv, 3)}
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=200)
    ap.add_argument("--through", choices=("separation", "t_end"), default="separation")
    ap.add_argument("--out", help="results file (default benchmarks/results/solver.json)")
    ap.add_argument("--baseline", default="ee677a4",
                    help="the commit the API's times and metrics are compared with")
    ap.add_argument("--rounds", type=int, default=5, help="fresh processes a side")
    args = ap.parse_args(argv)
    start_load = _results.load_average()
    stop = args.through == "separation"
    names = ("open-center", "central-leader", "realistic-crown")
    rows, medians, ratios, exact_wins = [], [], [], []
    numbers: dict = {}
    print(f"{'scenario':16s} {'exact ms':>9s} {'solve_ivp ms':>12s} {'ratio':>7s}")
    for name in names:
        scenario = load_scenario(name)
        model = two_body_model(scenario)
        t_end = scenario.t_end
        exact_t, ivp_t = [], []
        ivp_repeats = max(3, args.repeats // 20)
        for _ in range(ivp_repeats):  # interleave: noise falls on both
            exact_t += _time(lambda: solve_impacts(model, t_end, stop_at_separation=stop), 20)
            ivp_t += _time(lambda: solve_ivp_impacts(model, t_end, stop_at_separation=stop), 1)
        me, mi = statistics.median(exact_t) * 1e3, statistics.median(ivp_t) * 1e3
        medians.append(me)
        ratios.append(mi / me)
        print(f"{name:16s} {me:9.3f} {mi:12.3f} {mi / me:7.1f}")
        numbers |= {f"solver_ms.{name}": round(me, 4), f"solve_ivp_ms.{name}": round(mi, 3),
                    f"solver_ratio.{name}": round(mi / me, 1)}

        exact = solve_impacts(model, t_end, stop_at_separation=stop)
        met = impact_metrics(exact)
        ivp = solve_ivp_impacts(model, t_end, stop_at_separation=stop)
        ti_ref, T0_ref, V_ref, floors, fl_T0, fl_V = _reference(model, t_end, stop, 3e-14)
        ti_1, T0_1, V_1, _, _, _ = _reference(model, t_end, stop, 1e-13)
        n = min(len(exact.impacts), len(ivp["impacts"]), len(ti_ref), len(ti_1))
        unc = [abs(ti_1[i] - ti_ref[i]) + floors[i] for i in range(n)]
        d_exact = [abs(exact.impacts[i].t - ti_ref[i]) for i in range(n)]
        d_ivp = [abs(ivp["impacts"][i][0] - ti_ref[i]) for i in range(n)]

        def scaled(d):
            return max((di / ui if ui > 0 else (0.0 if di == 0 else math.inf))
                       for di, ui in zip(d, unc))

        t_ivp, _, v_ivp = ivp["together"][0]
        quantities = [
            ("max |dtau_i| s", max(d_exact), max(d_ivp), max(unc), scaled(d_exact),
             scaled(d_ivp)),
        ]
        for label, q_ex, q_ivp, q_ref, q_1, fl in (("|dT0| s", met["T0"], t_ivp, T0_ref, T0_1,
                                                    fl_T0),
                                                   ("|dV| m/s", met["V"], v_ivp, V_ref, V_1,
                                                    fl_V)):
            u = abs(q_1 - q_ref) + fl
            quantities.append((label, abs(q_ex - q_ref), abs(q_ivp - q_ref), u,
                               abs(q_ex - q_ref) / u, abs(q_ivp - q_ref) / u))
        rows.append((name, quantities))
    print("(medians; ratio = solve_ivp / exact)\n")
    print("deviation from the reference (solve_ivp at rtol 3e-14, chattering tail summed);")
    print("ref+-: its uncertainty (spread to rtol 1e-13 + round-off floor); x: deviation / ref+-,"
          " per impact for tau_i")
    print(f"{'scenario':16s} {'quantity':>14s} {'exact':>9s} {'x':>6s} {'solve_ivp':>9s} "
          f"{'x':>7s} {'ref+-':>9s}  more accurate")
    for name, quantities in rows:
        for label, d_ex, d_ivp, u, r_ex, r_ivp in quantities:
            verdict = _verdict(r_ex, r_ivp)
            exact_wins.append(verdict != "solve_ivp")
            print(f"{name:16s} {label:>14s} {d_ex:9.1e} {r_ex:6.1f} {d_ivp:9.1e} {r_ivp:7.1f} "
                  f"{u:9.1e}  {verdict}")
    numbers |= _bench_simulate(names, args.repeats)
    numbers |= _bench_baseline(args.baseline, args.rounds, 10 * args.repeats)
    numbers |= _floor(names)
    numbers["metric_rel_diff"] = max(numbers[f"metric_rel_diff.{n}"] for n in names)
    for key in ("simulate_ms", "ratio", "solver_ratio"):
        numbers[key] = _results.span(numbers[f"{key}.{n}"] for n in names)
    _results.write("solver", numbers, {"repeats": args.repeats, "through": args.through},
                   started_load=start_load, out=Path(args.out) if args.out else None)
    if not stop:
        print("\n(the targets below are set for --through separation)")
    print(f"\ntargets: median < 0.2 ms {'met' if max(medians) < 0.2 else 'MISSED'} "
          f"(worst {max(medians):.3f} ms); ratio >= 50 {'met' if min(ratios) >= 50 else 'MISSED'}"
          f" (worst {min(ratios):.1f}); exact the more accurate "
          f"{'met' if all(exact_wins) else 'MISSED'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
