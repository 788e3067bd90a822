"""Synthetic pendulum-test records and their identification (the identification study's
cases, docs/identification.md): a rung's run sampled as a test would record it (rate, noise,
the pendulum's swing), identified by the full-record fit (analytic.identify.record_fit) and by
the paper's procedure (analytic.identify.procedure, "paper" reading), with errors against the
scenario's SDOF truth. SI units."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.identify.procedure import (
    identify_from_record,
    pendulum_test_of,
    truth_of,
)
from treeimpact.analytic.model.ratios import apply_input
from treeimpact.compare.runs.backends import get_backend
from treeimpact.compare.runs.cache import resolve_scenario

from ..runs.cache import FAILED, OK

RATE = 5e3  # Hz: a common displacement-transducer rate
NOISE = 0.01  # Gaussian noise, fraction of the record's peak
REST = 0.02  # s of rest recorded before the impact (analytic.identify.record_fit needs a baseline)
PARAMETERS = ("M_T", "K_T", "b")  # b = C_T / (2 (M_T + m)), eq 42: what both methods find


@dataclass(frozen=True)
class Case:
    """One case of the study: the shipped ``scenario`` at ``restitution`` (1) and
    ``crown_ratio`` (m_f / m_trunk, 1), run on the backend ``rung``, its record sampled at
    ``rate`` (Hz) with Gaussian noise of ``noise`` x its peak from the seed ``seed``."""

    scenario: str
    restitution: float
    crown_ratio: float
    rung: str
    seed: int = 0
    rate: float = RATE  # Hz
    noise: float = NOISE  # fraction of the record's peak


def _scenario(case: Case):
    """The case's scenario: its e and crown ratio applied by the registry
    (analytic.model.ratios.apply_input)."""
    scen = apply_input(resolve_scenario(case.scenario), "restitution", case.restitution)
    return apply_input(scen, "crown_ratio", case.crown_ratio)


def sampled_record(trajectory, rate: float = RATE, noise: float = NOISE, seed: int = 0, *,
                   rest: float = REST):
    """(t, x) as a transducer would give them: the ``trajectory``'s x (m) at ``rate`` (Hz)
    from ``rest`` s before the impact (x = 0 there), linear interpolation, Gaussian noise of
    ``noise`` x the peak (m; none at 0) drawn from the random ``seed``."""
    t = np.arange(-rest, float(trajectory.t[-1]), 1.0 / rate)
    x = np.where(t > 0.0, np.interp(t, trajectory.t, trajectory.x), 0.0)
    rng = np.random.default_rng(seed)
    return t, x + noise * float(np.max(np.abs(x))) * rng.standard_normal(t.size)


def sampled_pendulum(trajectory, test, t: np.ndarray, noise: float = NOISE, seed: int = 0):
    """The pendulum's y (m) at the record's times ``t`` (s): the free swing
    u_1 sin(w_2 t) / w_2 (eq 13; u_1 and w_2 of the ``test``, an
    analytic.identify.procedure.PendulumTest) before the contact, the ``trajectory``'s y
    after, Gaussian noise of ``noise`` x its peak from the random ``seed`` (a stream of its
    own, apart from :func:`sampled_record`'s)."""
    w2 = math.sqrt(test.omega2_sq)
    before = test.impact_speed * (np.sin(w2 * t) / w2 if w2 > 0 else t)
    y = np.where(t > 0.0, np.interp(t, trajectory.t, trajectory.y), before)
    rng = np.random.default_rng([seed, 1])
    return y + noise * float(np.max(np.abs(y))) * rng.standard_normal(t.size)


#: The columns of one identified record in a sweep table (nested keys joined by '.').
_FITTED = tuple(f"{m}.{k}" for m in ("fit", "fit_known_e", "fit_with_y", "paper")
                for k in PARAMETERS)
RECORD_COLUMNS = (*_FITTED, "fit_not_fixed", "fit_covered.M_T", "fit_covered.K_T",
                  "fit_covered.C_T", "explained", "fit_error", "paper_error")


def record_identification(result, scenario, record: dict) -> dict:
    """The sweep analysis of the study: the run's record (``result``, the backend's
    SimulationResult, its trajectory) sampled as a test would be (``record``: rate Hz, noise
    fraction of the peak, seed), identified by the full-record fit and by the paper's
    procedure; errors (1) against the ``scenario``'s SDOF truth as flat columns
    (:data:`RECORD_COLUMNS`). Never raises: a failing method is its column's text."""
    # lazy: +665 ms at import otherwise (scipy, numpy),
    # which this module's other callers do not need
    from treeimpact.analytic.identify.record_fit import Record, fit_record

    rate, noise = record.get("rate", RATE), record.get("noise", NOISE)
    seed = int(record.get("seed", 0))
    truth = truth_of(scenario)
    test = pendulum_test_of(scenario)
    t, x = sampled_record(result.trajectory, rate, noise, seed=seed)
    out: dict = {}

    def errors(fit) -> dict:
        v = dict(fit.values)
        v["b"] = v["C_T"] / (2.0 * (v["M_T"] + test.impactor_mass))
        return {k: v[k] / truth[k] - 1.0 for k in PARAMETERS}

    try:
        rec = Record(t, x)
        fit = fit_record(rec, test)
        if fit.determined["M_T"]:
            out["fit"] = errors(fit)
        else:  # a one-impact record: ranges; the pad's e given or the pendulum's record fix them
            out["fit_not_fixed"] = True
            out["fit_known_e"] = errors(fit_record(rec, test,
                                                   restitution=scenario.contact.restitution,
                                                   free_fit=fit))
            y = sampled_pendulum(result.trajectory, test, t, noise, seed)
            out["fit_with_y"] = errors(fit_record(Record(t, x, y), test))
        truth_c = {"M_T": truth["M_T"], "K_T": truth["K_T"],
                   "C_T": 2.0 * truth["b"] * (truth["M_T"] + test.impactor_mass)}
        out["fit_covered"] = {k: bool(fit.intervals[k][0] <= w <= fit.intervals[k][1])
                              for k, w in truth_c.items()}
        out["explained"] = bool(fit.explained)
    except (ParameterError, ValueError, FloatingPointError) as exc:
        out["fit_error"] = str(exc).splitlines()[0]
    try:
        ident, _ = identify_from_record(t, x, test, reading="paper")
        found = ident.as_dict()  # by the symbols PARAMETERS names
        out["paper"] = {k: float(found[k]) / truth[k] - 1.0 for k in PARAMETERS}
    except (ParameterError, ValueError, FloatingPointError) as exc:
        text = str(exc).splitlines()[0]
        out["paper_error"] = "not identifiable" if text.startswith("not identifiable") else text
    return _flat(out)


record_identification.columns = RECORD_COLUMNS
#: The analysis's reference, as the sweeps load it in a worker.
ANALYSIS = "treeimpact.compare.studies.ident_records:record_identification"


def _flat(nested: dict) -> dict:
    """{"fit": {"M_T": v}} as {"fit.M_T": v}; plain keys as they are."""
    out = {}
    for key, value in nested.items():
        if isinstance(value, dict):
            out.update({f"{key}.{k}": v for k, v in value.items()})
        else:
            out[key] = value
    return out


def _missing(v) -> bool:
    """An empty cell of a sweep table (None, NaN or pandas' NA)."""
    # lazy: +216 ms at import otherwise (pandas, numpy, pyarrow),
    # which this module's other callers do not need
    import pandas as pd

    return v is None or (not isinstance(v, str) and bool(pd.isna(v)))


def case_row(row: dict) -> dict:
    """A table row as the study's case dict: the analysis's columns nested again, empty
    ones dropped, with the case's rung, restitution, crown ratio, rate, noise and seed."""
    out = {"scenario": row.get("scenario"), "rung": row["target"],
           "restitution": float(row["restitution"]),
           "crown_ratio": float(row.get("crown_ratio", 0.0)),
           "rate": float(row.get("record.rate", RATE)),
           "noise": float(row.get("record.noise", NOISE)),
           "seed": int(row.get("record.seed", 0))}
    if row.get("status") != OK:
        out["error"] = row.get("error")
        return out
    for col in RECORD_COLUMNS:
        v = row.get(col)
        if _missing(v):
            continue
        if col in ("fit_not_fixed", "explained") or col.startswith("fit_covered."):
            v = v if isinstance(v, bool) else str(v) == "True" if isinstance(v, str) \
                else bool(v)
        elif not isinstance(v, str):
            v = float(v)
        head, _, tail = col.partition(".")
        if tail:
            out.setdefault(head, {})[tail] = v
        else:
            out[head] = v
    return out


def identify_case(case: Case) -> dict:
    """Simulate, sample, identify both ways (:func:`record_identification`); never raises
    (errors are the outcome). The case as the study's rows hold it."""
    row = {"scenario": case.scenario, "restitution": case.restitution,
           "crown_ratio": case.crown_ratio, "target": case.rung, "record.rate": case.rate,
           "record.noise": case.noise, "record.seed": case.seed}
    try:
        scen = _scenario(case)
        result = get_backend(case.rung).simulate(scen)
    except Exception as exc:  # noqa: BLE001 - recorded per case
        return case_row(row | {"status": FAILED, "error": f"{type(exc).__name__}: {exc}"})
    return case_row(row | {"status": OK} | record_identification(
        result, scen, {"rate": case.rate, "noise": case.noise, "seed": case.seed}))
