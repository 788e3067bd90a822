"""The run budget (analytic/budget.py): limits read from the environment, the estimate and the
refusal before a run, the cost model held to its measurement, and progress only when long."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from treeimpact.analytic import budget
from treeimpact.analytic.budget import StepCost, check_work
from treeimpact.analytic.errors import ParameterError

RESULTS = Path(__file__).resolve().parents[1] / "benchmarks" / "results" / "cost.json"


@pytest.mark.parametrize("text", ["abc", "", "-1", "0", "nan", "inf"])
def test_a_budget_variable_that_is_not_a_positive_number_is_named(text, monkeypatch):
    monkeypatch.setenv("TREEIMPACT_MAX_SECONDS", text)
    with pytest.raises(ParameterError, match=f"TREEIMPACT_MAX_SECONDS = {text!r}: expected a "
                                             "positive number"):
        check_work(0.1, 1e-5, StepCost(1e-6, 100.0))


def test_the_steps_of_a_run_within_its_budget():
    assert check_work(0.1, 1e-5, StepCost(1e-6, 100.0)) == 10_000


@pytest.mark.parametrize(("cost", "variable", "words"), [
    (StepCost(0.0, 1e6), None, "1e+04 GB > 2 GB (TREEIMPACT_MAX_BYTES)"),
    (StepCost(1e-2, 8.0, "a 66-joint chain"), None,
     "of ~10 ms (a 66-joint chain): ~1e+05 s > 120 s (--max-seconds, TREEIMPACT_MAX_SECONDS)"),
    (StepCost(0.0, 8.0), ("TREEIMPACT_MAX_STEPS", "1e6"), "1e+07 steps > 1e+06"),
    (StepCost(1e-6, 8.0), ("TREEIMPACT_MAX_SECONDS", "5"), "~10 s > 5 s"),
])
def test_a_run_beyond_any_budget_is_refused_with_its_estimate(cost, variable, words,
                                                                monkeypatch):
    if variable:
        monkeypatch.setenv(*variable)
    with pytest.raises(ParameterError) as exc:
        check_work(10.0, 1e-6, cost)
    message = str(exc.value)
    assert "\n" not in message and message.startswith("the run is beyond its budget: 1e+07 steps")
    assert words in message


def test_the_cost_model_is_within_a_factor_two_of_its_measurement():
    """benchmarks/results/cost.json: bench_cost.py's medians (marginal CPU seconds and bytes
    per step) on the 2-core reference machine; the model in the code must stay within 2x of
    them either way (a model fitted to a few sizes; the budget only needs the scale)."""
    from treeimpact.analytic.contact.soft import SAMPLE_COST as soft
    from treeimpact.analytic.continuum.beam_impact import SAMPLE_COST as beam

    def model(case) -> StepCost:
        if case["backend"] == "mujoco":  # step_cost reads nv only
            from treeimpact.mujoco_models._rollout import step_cost

            return step_cost(type("M", (), {"nv": case["size"]["nv"]})())
        if case["backend"] == "bullet":
            from treeimpact.bullet_models._runner import step_cost

            return step_cost(case["size"]["joints"])
        return {"soft": soft, "beam": beam}[case["backend"]]

    data = json.loads(RESULTS.read_text())
    assert {c["backend"] for c in data["cases"]} == {"mujoco", "bullet", "soft", "beam"}
    for case in data["cases"]:
        est = model(case)
        assert 0.5 <= est.seconds / case["seconds_per_step"] <= 2.0, case
        assert 0.5 <= est.bytes / case["bytes_per_step"] <= 2.0, case


def test_progress_is_reported_only_for_a_long_run_and_only_when_asked(monkeypatch):
    seen = []

    class Bar:
        def __init__(self, desc, total):
            seen.append(("start", desc, total))

        def update(self, n):
            seen.append(("update", n))

        def close(self):
            seen.append(("close",))

    with budget.progress("mujoco", 100, 1e3) as tick:  # no reporter: a library call
        tick(10)
    assert seen == []
    monkeypatch.setattr(budget, "_REPORTER", Bar)
    with budget.progress("mujoco", 100, 1.0) as tick:  # short
        tick(10)
    assert seen == []
    with budget.progress("mujoco", 100, 30.0) as tick:
        tick(10)
    assert seen == [("start", "mujoco (estimated 30 s)", 100), ("update", 10), ("close",)]


def test_the_readme_quotes_the_budget_the_code_applies():
    import re

    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    readme = re.sub(r"<!--.*?-->", "", readme)  # the doc-number marks (tests/docnumbers/)
    m = re.search(r"beyond the budget: (\S+) steps, a (\S+) GB record, (\S+) s\b", readme)
    assert m, "the README's budget sentence moved: update this test"
    assert float(m[1]) == budget.MAX_STEPS
    assert float(m[2]) * 1e9 == budget.MAX_BYTES
    assert float(m[3]) == budget.MAX_SECONDS
    m = re.search(r"estimated past (\S+) s\s+shows its progress", readme)
    assert m and float(m[1]) == budget.PROGRESS_AFTER_S


def test_the_docs_cost_table_is_the_code_s_cost_model():
    """docs/budgets.md's formulas, read as Python, against the code's StepCost."""
    import re

    from treeimpact.analytic.contact.soft import SAMPLE_COST as soft
    from treeimpact.analytic.continuum.beam_impact import SAMPLE_COST as beam
    from treeimpact.bullet_models._runner import step_cost as bullet
    from treeimpact.mujoco_models._rollout import step_cost as mujoco

    doc = (Path(__file__).resolve().parents[1] / "docs" / "budgets.md").read_text()

    def formula(cell: str):
        expr = cell.replace(" per sample", "").replace("^", "**")
        expr = re.sub(r"([\d.e-]+) us\b", r"\1e-6", expr)
        expr = re.sub(r"([\d.e-]+) s\b", r"\1", expr)
        expr = re.sub(r"(\d) (nv|N)\b", r"\1*\2", expr)
        return lambda n: eval(expr, {"nv": n, "N": n})  # noqa: S307 - our own docs

    rows = {m[1]: (formula(m[2]), formula(m[3])) for m in re.finditer(
        r"^\| (MuJoCo|PyBullet|soft contact|beam)[^|]*\| ([^|]+) \| ([^|]+) \|$", doc, re.M)}
    code = {"MuJoCo": lambda n: mujoco(type("M", (), {"nv": n})()),
            "PyBullet": bullet, "soft contact": lambda n: soft, "beam": lambda n: beam}
    assert set(rows) == set(code)
    for name, (seconds, nbytes) in rows.items():
        for n in (1, 10, 130):
            assert seconds(n) == pytest.approx(code[name](n).seconds, rel=1e-12), name
            assert nbytes(n) == pytest.approx(code[name](n).bytes, rel=1e-12), name


def test_the_docs_quote_the_budget_progress_and_chunks_the_code_applies():
    import re

    from treeimpact.bullet_models.options import MAX_SEGMENTS
    from treeimpact.mujoco_models._rollout import CHUNK_SECONDS

    doc = (Path(__file__).resolve().parents[1] / "docs" / "budgets.md").read_text()
    number = {key: float(re.search(pattern, doc)[1]) for key, pattern in {
        "steps": r"\| steps \| (\S+) \|", "bytes": r"\| memory the run keeps \| (\S+) GB \|",
        "seconds": r"\| estimated wall time of one run \| (\S+) s \|",
        "progress": r"longer than (\S+) s \(`PROGRESS_AFTER_S`\)",
        "chunk": r"in chunks of ~(\S+) s",
        "bullet": r"more than (\S+) hinges in one PyBullet"}.items()}
    assert number == {"steps": budget.MAX_STEPS, "bytes": budget.MAX_BYTES / 1e9,
                      "seconds": budget.MAX_SECONDS, "progress": budget.PROGRESS_AFTER_S,
                      "chunk": CHUNK_SECONDS, "bullet": MAX_SEGMENTS}
