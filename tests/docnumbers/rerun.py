"""The cheap part of docs/numbers.json, rerun now (:func:`cheap_numbers`, a few seconds; what
``numbers`` reruns beside a report and tests/test_doc_numbers.py checks the pages against):
the shipped trees' analytic rungs and mechanism, their inputs and the code's constants, the
beam studies, ``treeimpact contact``'s collisions, the procedure on noisy records, the
small-e answer and the models at the contact fitted to the paper's trees. SI units in,
display units out as the keys say."""

from __future__ import annotations

import json
import math
from dataclasses import replace

from .base import CONTACT_FIT, TREES, per_tree, put, rounded, span
from .from_report import cheap_ladders, from_small_e, from_view, view_from_ladders


def small_e_now() -> dict:
    """:func:`from_small_e` of the shipped trees computed now (compare.studies.small_e, in this
    process: a few seconds)."""
    from treeimpact.compare.studies.small_e import small_e_answer, small_e_table

    return from_small_e({t: small_e_answer(_scenario(t), small_e_table(t)) for t in TREES})


def _scenario(name: str):
    from treeimpact.analytic.model.scenario import load_scenario

    return load_scenario(name)


def at_fitted_contact(fit: dict) -> dict:
    """The 1-DOF soft model against the continuum at the pad the continuum was fitted to on
    each tree (what the 1-DOF assumption costs there): four runs, a second."""
    from treeimpact.analytic.contact.soft import simulate_soft
    from treeimpact.analytic.continuum.beam_impact import simulate_beam
    from treeimpact.analytic.model.options import numerical_options, scenario_as_run
    from treeimpact.analytic.model.scenario import load_scenario

    out: dict = {}
    gaps: dict = {"x_max": {}, "energy_delivered": {}}
    for name, tree in fit["contact_fit"].items():
        params = {k: v["value"] for k, v in tree["fits"]["beam"]["parameters"].items()}
        scen = scenario_as_run(load_scenario(name), params)  # the fitted pad and e
        soft = simulate_soft(scen, **numerical_options(params)).metrics
        beam = simulate_beam(scen, **numerical_options(params)).metrics
        for m in gaps:
            gaps[m][name] = 100.0 * (beam[m] / soft[m] - 1.0)
    for m, by_tree in gaps.items():
        for t, v in by_tree.items():
            put(out, f"fit.at_beam_contact.gap_pct.{m}.{t}", v)
        put(out, f"fit.at_beam_contact.gap_pct.{m}", span(by_tree.values()))
    return out


def shipped() -> dict:
    """The shipped trees' inputs the pages quote, and the studies' tolerance (%); the
    Timoshenko trunk's softening, the code's limits, where the flexibility at the clamp is,
    the hinged chain's errors and the sensitivity study's design."""
    from treeimpact.analytic.model.scenario import load_scenario
    from treeimpact.compare.runs.verdicts import validity_tolerance

    out: dict = {"validity_tolerance_pct": rounded(100.0 * validity_tolerance())}
    scens = {t: load_scenario(t) for t in TREES}
    for key, get in (("contact_duration_ms", lambda s: 1e3 * s.contact.duration),
                     ("restitution", lambda s: s.contact.restitution),
                     ("clamp_mass_kg", lambda s: s.trunk.clamp_mass),
                     ("crown_mass_kg", lambda s: s.trunk.crown_mass),
                     ("impactor_mass_kg", lambda s: s.impactor.mass)):
        per_tree(out, f"shipped.{key}", {t: get(s) for t, s in scens.items()})
    _timoshenko_softening(out, scens)
    _code_limits(out)
    _clamp_flexibility(out, scens)
    _chain_errors(out, scens)
    _sensitivity_design(out)
    return out


def _timoshenko_softening(out: dict, scens: dict) -> None:
    """How much softer the Timoshenko trunk is at the clamp (%): with each scenario's shear
    modulus, and over E / G from 10 to 20."""
    from treeimpact.analytic.continuum.beam import beam_static_stiffness

    def softening(trunk, e_over_g=None):
        if e_over_g is not None:
            trunk = replace(trunk, shear_modulus=trunk.youngs_modulus / e_over_g)
        return 100.0 * (1.0 - beam_static_stiffness(trunk, "timoshenko")
                        / beam_static_stiffness(trunk))

    per_tree(out, "timoshenko.static_softening_pct",
             {t: softening(s.trunk) for t, s in scens.items()})
    put(out, "timoshenko.static_softening_pct.e_over_g_10_to_20",
        span([softening(s.trunk, r) for s in scens.values() for r in (10.0, 20.0)]))


def _code_limits(out: dict) -> None:
    """The code's own limits the pages quote: the chatter's impacts, the record fit's
    resolution, the report's fit noise (%), the persistence factor, the engines' time-step
    rule and the work budget (steps, GB, s)."""
    import inspect

    from treeimpact.analytic import budget
    from treeimpact.analytic.contact import timestep
    from treeimpact.analytic.identify.record_fit import RESOLUTION
    from treeimpact.analytic.impact.solver import MAX_CHATTER_IMPACTS
    from treeimpact.analytic.records import metrics_from_record
    from treeimpact.compare.studies.ident_fits import FIT_NOISE

    out["code.max_chatter_impacts"] = MAX_CHATTER_IMPACTS
    out["code.identify_resolution"] = RESOLUTION
    out["code.report_fit_noise_pct"] = rounded(100.0 * FIT_NOISE)
    out["code.persist_factor"] = inspect.signature(metrics_from_record).parameters[
        "persist_factor"].default
    rule = inspect.signature(timestep.choose_time_step).parameters
    out["code.timestep.steps_per_collision"] = rule["steps_per_collision"].default
    out["code.timestep.steps_per_period"] = rule["steps_per_period"].default
    out["code.budget.max_steps"] = budget.MAX_STEPS
    out["code.budget.max_gb"] = budget.MAX_BYTES / 1e9
    out["code.budget.max_seconds"] = budget.MAX_SECONDS


def _clamp_flexibility(out: dict, scens: dict) -> None:
    """Where the flexibility at the clamp is: the root spring's share (%), and what shear
    adds below the clamp (%, E / G = 13, the default)."""
    from treeimpact.analytic.continuum.beam import beam_static_stiffness

    shares, shear = {}, {}
    for t, scen in scens.items():
        tr = scen.trunk
        a = tr.clamp_height
        root = a * a / tr.base_stiffness if math.isfinite(tr.base_stiffness) else 0.0
        shares[t] = 100.0 * root * beam_static_stiffness(tr)
        shear[t] = 100.0 * (a / tr.shear_rigidity) / (a ** 3 / (3.0 * tr.bending_stiffness))
    per_tree(out, "root.flexibility_share_pct", shares)
    per_tree(out, "timoshenko.shear_over_bending_pct", shear)


def _chain_errors(out: dict, scens: dict) -> None:
    """The engines' hinged chain against the beam, one segment below the default (%) and
    the worst at 64 segments."""
    from treeimpact.analytic.continuum.chain import chain_errors, default_segments

    worst64 = []
    for t, scen in scens.items():
        n = default_segments(scen.trunk)
        for k, v in chain_errors(scen.trunk, n - 1).items():
            out[f"chain.below_default.{k}_pct.{t}"] = rounded(100.0 * v)
        worst64 += [abs(v) for v in chain_errors(scen.trunk, 64).values()]
    out["chain.n64.worst"] = rounded(max(worst64))


def _sensitivity_design(out: dict) -> None:
    """The sensitivity study's design (compare/studies/sensitivity.py, the presets): levels,
    inputs and their ranges, pads (ms), and each preset's trajectories and points."""
    from treeimpact.compare.report.validity.study import PRESETS
    from treeimpact.compare.studies.sensitivity import DURATIONS as PADS
    from treeimpact.compare.studies.sensitivity import LEVELS
    from treeimpact.compare.studies.study_inputs import INPUTS

    out["code.sensitivity.levels"] = LEVELS
    out["code.sensitivity.inputs"] = len(INPUTS)
    out["code.sensitivity.pads"] = len(PADS)
    out["code.sensitivity.pad_range_ms"] = rounded([1e3 * PADS[0], 1e3 * PADS[-1]])
    for name, (low, high, unit, *_) in INPUTS.items():
        if unit == "log10 s":
            low, high = 1e3 * 10.0 ** low, 1e3 * 10.0 ** high
        out[f"code.sensitivity.input.{name}"] = rounded([low, high])
    for name, preset in PRESETS.items():
        out[f"code.preset.{name}.trajectories"] = preset.sensitivity
        out[f"code.preset.{name}.points"] = preset.sensitivity * (len(INPUTS) + 1)


def beam_studies() -> dict:
    """The continuum rung's convergence in elements and what Timoshenko's theory changes on
    the shipped trees (docs/beam-impact.md; about 2 s)."""
    from treeimpact.analytic.continuum.beam import beam_natural_frequencies
    from treeimpact.analytic.continuum.beam_impact import simulate_beam
    from treeimpact.analytic.model.scenario import load_scenario

    out: dict = {}
    for t in TREES:
        scen = load_scenario(t)
        runs = {n: simulate_beam(scen, elements=n).metrics for n in (12, 24, 40, 48)}
        for n, m in runs.items():
            out[f"beam.elements{n}.energy_delivered.{t}"] = rounded(m["energy_delivered"])
            out[f"beam.elements{n}.x_max_mm.{t}"] = rounded(1e3 * m["x_max"])
            if n != 48:
                for k in ("energy_delivered", "x_max"):
                    out[f"beam.elements{n}.vs48_pct.{k}.{t}"] = rounded(
                        100.0 * abs(m[k] / runs[48][k] - 1.0))
        w_eb = beam_natural_frequencies(scen.trunk, 2)
        if t == "central-leader":  # rotary inertia alone: the Rayleigh beam (G = inf)
            rayleigh = beam_natural_frequencies(replace(scen.trunk, shear_modulus=math.inf),
                                                2, "timoshenko")
            for i in (0, 1):
                out[f"rayleigh.omega_{i + 1}_pct.{t}"] = rounded(
                    100.0 * abs(rayleigh[i] / w_eb[i] - 1.0))
        for e_over_g in (10.0, 13.0, 20.0):
            trunk = replace(scen.trunk, shear_modulus=scen.trunk.youngs_modulus / e_over_g)
            m = simulate_beam(replace(scen, trunk=trunk), beam_theory="timoshenko").metrics
            w = beam_natural_frequencies(trunk, 2, "timoshenko")
            key = f"timoshenko.e_over_g{e_over_g:g}"
            for k in ("x_max", "energy_delivered"):
                out[f"{key}.{k}_pct.{t}"] = rounded(100.0 * (m[k] / runs[12][k] - 1.0))
            for i in (0, 1):
                out[f"{key}.omega_{i + 1}_pct.{t}"] = rounded(100.0 * (w[i] / w_eb[i] - 1.0))
    for n in (12, 24, 40):
        for k in ("energy_delivered", "x_max"):
            put(out, f"beam.elements{n}.vs48_pct.{k}", span(
                [out[f"beam.elements{n}.vs48_pct.{k}.{t}"] for t in TREES]))
    put(out, "timoshenko.omega_2_drop_pct", span(
        [-out[f"timoshenko.e_over_g{r:g}.omega_2_pct.{t}"] for t in TREES
         for r in (10.0, 13.0, 20.0)]))
    return out



#: The collisions of docs/contact-settings.md's table: (m1, m2 (inf: fixed), e, duration,
#: dt), SI.
CONTACT_CASES = ((132.4, 4.0, 0.5, 2e-3, 4e-5), (132.4, 110.0, 0.1, 5e-4, 1e-5),
                 (1.0, math.inf, 0.8, 1e-3, 1e-5), (132.4, 4.0, 0.5, 2e-3, 2e-4),
                 (1.0, math.inf, 0.05, 1e-3, 1e-4))


def contact_command() -> dict:
    """``treeimpact contact`` on :data:`CONTACT_CASES`: what each engine achieves with the
    corrected settings and with the naive formula (about 1 s)."""
    from treeimpact.compare.runs.contact_settings import contact_settings

    out: dict = {}
    errs: dict = {"mujoco": [], "bullet": []}
    naive: dict = {"mujoco": [], "bullet": []}
    durations: dict = {}
    for i, (m1, m2, e, duration, dt) in enumerate(CONTACT_CASES):
        res = contact_settings(mass=m1, other_mass=m2, restitution=e,
                               touch_duration=duration, dt=dt)
        key = f"contact_cmd.{i}"
        law = res["target"]
        steps = round(law["touch_duration"] / dt)
        out[f"{key}.steps"] = steps
        out[f"{key}.damping_ratio"] = rounded(law["damping_ratio"])
        for engine in ("mujoco", "bullet"):
            ach = res[engine]["achieved"]
            ach = ach if "restitution" in ach else ach["solref"]
            out[f"{key}.{engine}.e"] = rounded(ach["restitution"])
            out[f"{key}.{engine}.duration_pct"] = rounded(
                100.0 * (ach["touch_duration"] / law["touch_duration"] - 1.0))
            out[f"{key}.{engine}.naive_e"] = rounded(res[engine]["naive"]["restitution"])
            out[f"{key}.{engine}.naive_miss"] = rounded(
                res[engine]["naive"]["restitution"] - e)
            errs[engine] += [abs(a["restitution"] - e) for a in (
                [res[engine]["achieved"]] if "restitution" in res[engine]["achieved"]
                else res[engine]["achieved"].values())]
            naive[engine].append(abs(res[engine]["naive"]["restitution"] - e))
            durations.setdefault(steps, []).append(abs(out[f"{key}.{engine}.duration_pct"]))
        timeconst = res["mujoco"]["achieved"].get("solref_timeconst")
        if timeconst:
            out[f"{key}.mujoco.timeconst_e"] = rounded(timeconst["restitution"])
    for engine in errs:
        out[f"contact_cmd.{engine}.e_error_max"] = rounded(max(errs[engine]))
        put(out, f"contact_cmd.{engine}.naive_miss", span(naive[engine]))
    for steps, d in durations.items():
        out[f"contact_cmd.duration_pct_max.steps{steps}"] = rounded(max(d))
    put(out, "contact_cmd.steps", span(out[f"contact_cmd.{i}.steps"]
                                         for i in range(len(CONTACT_CASES))))
    return out


#: docs/contact-settings.md's example at MuJoCo's default step: (m1, m2, e, touch duration,
#: dt), SI; the step Bullet cannot hold for it.
DEFAULT_STEP_CASE = (1.0, 1.0, 0.75, 5e-3, 2e-3)
BULLET_REFUSED_DT = 1e-3


def contact_default_step() -> dict:
    """``treeimpact contact`` at MuJoCo's default 2 ms step (:data:`DEFAULT_STEP_CASE`): the
    touch's steps, the duration's error, e of the same setting at dt/2 and 2 dt, and the
    largest step Bullet takes for it (about 0.1 s)."""
    from treeimpact.compare.runs.contact_settings import contact_settings

    m1, m2, e, touch, dt = DEFAULT_STEP_CASE
    res = contact_settings(mass=m1, other_mass=m2, restitution=e, touch_duration=touch, dt=dt,
                           engines=("mujoco",))
    mj = res["mujoco"]
    bl = contact_settings(mass=m1, other_mass=m2, restitution=e, touch_duration=touch,
                          dt=BULLET_REFUSED_DT, engines=("bullet",))["bullet"]
    key = "contact_cmd.default_step"
    return {f"{key}.steps_per_touch": touch / dt,
            f"{key}.e": rounded(mj["achieved"]["solref"]["restitution"]),
            f"{key}.duration_pct": rounded(100.0 * (
                mj["achieved"]["solref"]["touch_duration"] / touch - 1.0)),
            f"{key}.half_dt_e": rounded(mj["at_half_dt"]["solref"]["restitution"]),
            f"{key}.double_dt_e": rounded(mj["at_double_dt"]["solref"]["restitution"]),
            "contact_cmd.bullet_largest_dt": rounded(bl["largest_dt"])}


#: Seeds of :func:`procedure_on_noisy_records` (issue 34: the README quoted a median from
#: one kind of record that the README's own commands do not give).
PROCEDURE_SEEDS = 100


def procedure_on_noisy_records() -> dict:
    """The paper's procedure (eqs 39-48, its ``paper`` reading) on seeded records of the
    central-leader model at 5 kHz with 1 % noise (compare.runs.recording, as `treeimpact simulate
    --record` writes them), with 20 ms of rest before the impact (the README's commands)
    and with 10 ms (the cut docs/identification.md's table uses): the median and the range
    over :data:`PROCEDURE_SEEDS` seeds of its M_T error, % (a few seconds)."""
    import numpy as np
    from treeimpact.analytic.identify.procedure import PendulumTest, identify_from_record
    from treeimpact.analytic.model.scenario import load_scenario
    from treeimpact.compare.runs.backends import get_backend
    from treeimpact.compare.runs.recording import REST, sample

    tree = load_scenario("central-leader")
    result = get_backend("analytic").simulate(tree)
    pend, trunk = tree.impactor, tree.trunk
    test = PendulumTest(impactor_mass=pend.mass, equivalent_length=pend.equivalent_length,
                        release_angle=pend.release_angle_rad, clamp_height=trunk.clamp_height,
                        diameter=trunk.diameter, gravity=pend.gravity)
    out = {}
    for rest in (0.02, 0.01):
        errors = []
        for seed in range(PROCEDURE_SEEDS):
            t, x = sample(result, 5000.0, 0.01, seed)
            keep = t >= REST - rest - 1e-12
            with np.errstate(all="ignore"):
                ident, _ = identify_from_record(t[keep] - t[keep][0], x[keep], test)
            errors.append(100.0 * (ident.dynamic_mass / result.model["M_T"] - 1.0))
        key = f"ident.procedure.rest{round(1e3 * rest)}ms.M_T_pct"
        out[f"{key}.median"] = rounded(float(np.median(errors)))
        put(out, f"{key}.range", rounded(span(errors)))
    return out


def cheap_numbers() -> dict:
    """The part of docs/numbers.json a test reruns (a few seconds)."""
    out = (from_view(view_from_ladders(cheap_ladders())) | shipped() | beam_studies()
           | contact_command() | contact_default_step() | procedure_on_noisy_records()
           | small_e_now())
    if CONTACT_FIT.exists():
        out |= at_fitted_contact(json.loads(CONTACT_FIT.read_text()))
    return out
