"""The numbers of the checked-in results files: the paper's trees fitted
(docs/results/contact-fit.json), the identification's validation
(docs/results/identify-validation.json) and the benchmarks (benchmarks/results/*.json;
timings are quoted from there only), and :func:`numbers`: all of them with
docs/numbers.json, what a page may quote."""

from __future__ import annotations

import json
from pathlib import Path

from .base import (
    BENCHMARKS,
    CONTACT_FIT,
    IDENTIFY_VALIDATION,
    NUMBERS,
    TRUNKS_JSON,
    finite,
    put,
    rounded,
    span,
)


def from_contact_fit(fit: dict) -> dict:
    """The models held against the paper's measurements (``paper --fit-contact``)."""
    out: dict = {}
    trees = fit["contact_fit"]
    explained = 0
    for name, tree in trees.items():
        for model, f in tree["fits"].items():
            key = f"fit.{name}.{model}"
            for p, v in f["parameters"].items():
                out[f"{key}.{p}"] = rounded(1e3 * v["value"] if p == "contact_duration"
                                           else v["value"])
            for target, v in f["targets"].items():
                if finite(v["residual"]):
                    out[f"{key}.residual_pct.{target}"] = rounded(100.0 * v["residual"])
            out[f"{key}.rms_pct"] = rounded(100.0 * f["rms"])
            out[f"{key}.dof"] = f["dof"]
            explained += len(f["explains"])
        out[f"fit.{name}.explained_by_none"] = len(tree["explained_by_none"])
    out["fit.explained"] = explained
    for model in {m for t in trees.values() for m in t["fits"]}:
        for target in {k for t in trees.values() for k in t["measured"]}:
            vals = [out.get(f"fit.{n}.{model}.residual_pct.{target}") for n in trees]
            put(out, f"fit.{model}.residual_pct.{target}", span(vals))
        put(out, f"fit.{model}.rms_pct", span([out.get(f"fit.{n}.{model}.rms_pct")
                                                 for n in trees]))
    for target in {k for t in trees.values() for k in t["measured"]}:
        vals = [out.get(f"fit.{n}.{m}.residual_pct.{target}") for n, t in trees.items()
                for m in t["fits"]]
        put(out, f"fit.all.residual_pct.{target}", span(vals))
        put(out, f"abs.fit.all.residual_pct.{target}",
             span([abs(v) for v in vals if finite(v)]))
    out["fit.targets"] = sum(len(t["measured"]) for t in trees.values())
    out["fit.models"] = len({m for t in trees.values() for m in t["fits"]})
    return out


def from_benchmarks(results: Path | None = None) -> dict:
    """What the benchmarks measured (their results files; timings are quoted from here
    only). Each file's numbers under ``bench.<file>.``; see the benchmark for their meaning."""
    out: dict = {}
    results = BENCHMARKS if results is None else results
    for path in sorted(results.glob("*.json")):
        data = json.loads(path.read_text())
        flat = data.get("numbers")
        if isinstance(flat, dict):
            for k, v in flat.items():
                put(out, f"bench.{path.stem}.{k}", v)
        load = data.get("load_average") or {}
        if isinstance(load, dict) and load.get("start") and load.get("end"):  # 1-minute
            put(out, f"bench.{path.stem}.load_average",
                 span([load["start"][0], load["end"][0]]))
    trunks = TRUNKS_JSON if results is BENCHMARKS else results / "trunks.json"
    if trunks.is_file():  # bench_trunks.py's file is the report's package data
        out |= from_trunks(json.loads(trunks.read_text()))
    return out


def from_trunks(data: dict) -> dict:
    """compare/report/data/trunks.json (bench_trunks.py): per tree, trunk model and segment
    count, its errors against the continuum (%) and cost at the default step, and each
    step's run (``run<factor>``)."""
    out: dict = {}
    loads = [v for sc in data["scenarios"].values() for v in (
        (sc.get("record") or {}).get("load_average"),
        (sc.get("record") or {}).get("load_average_after")) if v is not None]
    if loads:  # the 1-minute load before and after each tree's runs
        put(out, "bench.trunks.load_average", span(loads))
    for tree, sc in data["scenarios"].items():
        for row in sc["rows"]:
            key = f"bench.trunks.{tree}.{row['model']}.{row['segments']}"
            w1, w2 = row["omega_errors"]
            put(out, f"{key}.static_stiffness_pct", 100.0 * row["static_stiffness_error"])
            put(out, f"{key}.omega_1_pct", 100.0 * w1)
            put(out, f"{key}.omega_2_pct", 100.0 * w2)
            for run in row["runs"]:
                if "x_max_error" not in run:
                    continue
                rk = key if run["factor"] == 1 else f"{key}.run{run['factor']:g}"
                put(out, f"{rk}.x_max_pct", 100.0 * run["x_max_error"])
                put(out, f"{rk}.energy_delivered_pct", 100.0 * run["energy_delivered_error"])
                put(out, f"{rk}.s_per_s", run["wall_per_simulated_s"])
    # across the trees: the recommended N = 8 at 16 times the default step, what the step
    # changes there, and the energy delivered from N = 16 on
    rows = [(tree, row) for tree, sc in data["scenarios"].items() for row in sc["rows"]]
    n8 = [row for _, row in rows if row["segments"] == 8]
    at16 = [r for row in n8 for r in row["runs"] if r["factor"] == 16 and "x_max_error" in r]
    put(out, "bench.trunks.n8.run16.s_per_s", span(r["wall_per_simulated_s"] for r in at16))
    put(out, "bench.trunks.n8.run16.dt", span(r["dt"] for r in at16))
    put(out, "bench.trunks.n8.step_effect_x_max_pct", max(
        abs(100.0 * (r["x_max_error"] - row["runs"][0]["x_max_error"]))
        for row in n8 for r in row["runs"] if "x_max_error" in r))
    put(out, "bench.trunks.n16_up.abs_energy_delivered_pct", max(
        abs(100.0 * row["runs"][0]["energy_delivered_error"]) for _, row in rows
        if row["segments"] >= 16))
    return out


def numbers() -> dict:
    """Every quotable number: docs/numbers.json and what the checked-in results files give."""
    out = dict(json.loads(NUMBERS.read_text())["numbers"]) if NUMBERS.exists() else {}
    if CONTACT_FIT.exists():
        out |= from_contact_fit(json.loads(CONTACT_FIT.read_text()))
    if IDENTIFY_VALIDATION.exists():
        for k, v in json.loads(IDENTIFY_VALIDATION.read_text())["numbers"].items():
            put(out, f"identify.{k}", v)
    out |= from_benchmarks()
    return out
