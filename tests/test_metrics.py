"""Metrics declared once (issue 51 item 4): each output metric is one ``Metric`` of
analytic/metrics.py's ``METRICS`` (name, unit, label, meaning, equation, whether the ladder
compares it, whether it is a count, what a run must have for it to exist). The metric keys,
the units' table, the ladder's metrics, the times checked against t_end and the verdicts'
absence reasons are derived from it; what is written elsewhere by hand is checked against it
here: the API's ``Metrics`` (its fields, types and docstring), the tolerance file (an entry
per ladder metric in every section), the glossary (tests/test_glossary.py), the report's and
the studies' selections of metrics and docs/whole-event-metrics.md's table. The last test
adds a declaration on a copy of the source and shows the derived lists follow it."""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import json
import math
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

import treeimpact as ti
from treeimpact.analytic.metrics import (
    FORCE,
    LADDER_METRICS,
    METRIC_KEYS,
    METRICS,
    PARTED,
    TOGETHER,
    Metric,
)
from treeimpact.compare.runs.verdicts import TOLERANCES_PATH

from test_glossary import _cited, glossary_problems
from test_registry_defaults import _copy

ROOT = Path(__file__).resolve().parents[1]
#: The tolerance file, as the verdicts read it.
TOLERANCES = Path(TOLERANCES_PATH)
#: A declaration the tests add, as a new metric would be: a ladder metric without a field,
#: a tolerance entry or a glossary entry yet.
EXTRA = Metric("probe_time", "s", "probe time", "a probe's time after the first touch",
               "eq 58", needs=PARTED)


def _compare_module(name: str):
    """The compare module (outside its tests) that assigns ``name`` at its top level,
    imported: found by its source, so a module moved into a subfolder is still found."""
    hits = [p for p in sorted((ROOT / "compare").rglob("*.py")) if "tests" not in p.parts
            and re.search(rf"^{re.escape(name)}\b[^=\n]*=", p.read_text(), flags=re.M)]
    assert len(hits) == 1, (name, hits)
    parts = hits[0].relative_to(ROOT).with_suffix("").parts
    return importlib.import_module(".".join(("treeimpact", *parts)))


def _ladder_metrics(metrics) -> tuple:
    """The ladder's metric names of ``metrics`` and the identified ``id_`` ones."""
    ident = _compare_module("IDENT_METRICS").IDENT_METRICS
    return tuple(m.name for m in metrics if m.ladder) + tuple(f"id_{k}" for k in ident)


def test_the_declarations_are_one_per_metric_and_well_formed():
    names = [m.name for m in METRICS]
    assert len(set(names)) == len(names) and len({m.label for m in METRICS}) == len(names)
    for m in METRICS:
        assert m.needs in (None, TOGETHER, PARTED, FORCE), m.name
        assert not m.count or m.unit == "1", m.name  # a count is dimensionless
        assert m.meaning and "\n" not in m.meaning, m.name
    # the ladder's metric list is the declarations', re-exported where the ladder reads it
    assert _compare_module("ALL_METRICS").LADDER_METRICS is LADDER_METRICS
    assert _compare_module("ALL_METRICS").ALL_METRICS == _ladder_metrics(METRICS)


@pytest.mark.parametrize("backend", ["analytic", "soft"])
def test_each_backend_computes_what_its_declaration_says(backend):
    """central-leader's pendulum moves together with the trunk and parts within t_end, so
    every metric exists on the soft contact; the paper's Newton impacts have no contact
    force (``needs`` FORCE: NaN there, and only there); counts are integers. No number is
    compared (no kernel round-off can move a NaN or an integer's type)."""
    metrics = ti.simulate("central-leader", backend=backend).result.metrics
    assert tuple(metrics) == METRIC_KEYS
    for m in METRICS:
        v = metrics[m.name]
        assert isinstance(v, int) == m.count and not isinstance(v, bool), (m.name, v)
        absent = backend == "analytic" and m.needs == FORCE
        assert math.isnan(v) if absent else math.isfinite(v), (m.name, v)


def _refs(text: str) -> set[str]:
    """The paper's equations and tables ``text`` cites: {"56", "37-38", "Table 1"}."""
    return _cited(text) | set(re.findall(r"\bTable \d+", text))


def _doc_entries(cls) -> dict[str, str]:
    """name -> its text (continuation lines joined) of ``cls``'s docstring Attributes."""
    doc = inspect.getdoc(cls).split("Attributes:\n", 1)[1]
    out, name = {}, None
    for line in doc.splitlines():
        m = re.match(r"    (\w+): (.*)", line)
        if m:
            name, out[m[1]] = m[1], m[2]
        elif name and line.startswith("        "):
            out[name] += " " + line.strip()
    return out


def metrics_field_problems(metrics, cls) -> list[str]:
    """What ``cls`` (the API's Metrics) lacks against the declarations ``metrics``: a field
    per declaration, in their order, int for a count and float otherwise, and a docstring
    entry per field ending in its unit (", a count." for a count; a parenthesis may follow
    the unit) that cites the declaration's equations and tables, no other."""
    out = []
    fields = {f.name: f.type for f in dataclasses.fields(cls)}
    names = [m.name for m in metrics]
    out += [f"{n}: no field" for n in names if n not in fields]
    out += [f"{n}: a field and no declaration" for n in fields if n not in names]
    if [n for n in fields if n in names] != [n for n in names if n in fields]:
        out.append("fields not in the declarations' order")
    doc = _doc_entries(cls)
    for m in metrics:
        if m.name not in fields:
            continue
        if fields[m.name] != ("int" if m.count else "float"):
            out.append(f"{m.name}: type {fields[m.name]}")
        text = doc.get(m.name)
        unit = "a count" if m.count else m.unit
        if text is None:
            out.append(f"{m.name}: not in the docstring")
        elif not re.search(rf", {re.escape(unit)}(?: \([^)]*\))?\.$", text):
            out.append(f"{m.name}: the docstring does not end in its unit {unit!r}")
        elif _refs(text) != _refs(m.equation):
            out.append(f"{m.name}: the docstring cites {_refs(text)}, the declaration "
                       f"{_refs(m.equation)}")
    return out


def test_the_api_metrics_has_a_field_per_declaration():
    assert metrics_field_problems(METRICS, ti.Metrics) == []
    run = ti.simulate("central-leader")
    assert run.metrics.as_dict() == {k: run.result.metrics[k] for k in METRIC_KEYS}


def test_each_meaning_cites_its_declared_equation():
    """The one-line meaning (what the command line and the ladder table print) cites the
    equations and tables the declaration names, and says NaN under Newton impulses exactly
    for the metrics that need a contact force."""
    for m in METRICS:
        assert _refs(m.meaning) == _refs(m.equation), m.name
        assert ("NaN for Newton impulses" in m.meaning) == (m.needs == FORCE), m.name


def tolerance_problems(metrics, tol: dict) -> list[str]:
    """The rule of the tolerance file (its header): every ladder metric of ``metrics`` (and
    the identified ones) has an entry in every [step.*] and [engines.*] section of ``tol``
    (rel, bound, report_only or undefined), and every entry names one."""
    want = _ladder_metrics(metrics)
    out = []
    for section in ("step", "engines"):
        for kind, entries in tol[section].items():
            out += [f"[{section}.{kind}] {m}: no entry" for m in want if m not in entries]
            out += [f"[{section}.{kind}] {m}: not a ladder metric" for m in entries
                    if m not in want]
    return out


def test_every_ladder_metric_has_an_entry_in_every_section():
    tol = tomllib.loads(TOLERANCES.read_text())
    assert tol["step"] and tol["engines"]  # the sections the rule covers were read
    assert tolerance_problems(METRICS, tol) == []


def test_a_missing_entry_would_be_reported_without_a_tolerance():
    """What the rule prevents: a comparison whose metric has no entry is only reported,
    with "no tolerance entry" as its reason, however far apart the values are."""
    judge = _compare_module("WHY_NONE").judge
    check = judge("tree", "beam", "beam", "x_max", 2.0, "soft", 1.0, None, {"finding": []})
    assert (check.verdict, check.tolerance, check.reason) == ("reported", None,
                                                              "no tolerance entry")


#: The SI unit and factor of each display unit the report's tables print a metric in.
DISPLAY = {"mm": ("m", 1e3), "km/s^2": ("m/s^2", 1e-3), "kN": ("N", 1e-3)}


def test_the_report_and_studies_name_declared_metrics_in_their_units():
    """The hand-chosen selections of metrics (the answer table, the mechanism table, the
    studies' outputs, the command line's columns without a difference) name declared
    metrics; the answer's tooltips are the declared labels; a display unit is the
    declared SI unit scaled (mm = 1e3 m)."""
    units = {m.name: m.unit for m in METRICS}
    labels = {m.name: m.label for m in METRICS}
    answer = _compare_module("ANSWER_METRICS")
    rows = {"ANSWER_METRICS": [(m, s, u) for m, _, s, u in answer.ANSWER_METRICS],
            "MECHANISM_METRICS": list(_compare_module("MECHANISM_METRICS").MECHANISM_METRICS)}
    for table, entries in rows.items():
        for metric, scale, unit in entries:
            si, factor = DISPLAY.get(unit, (unit, 1.0))
            assert (units[metric], scale) == (si, factor), (table, metric)
    assert answer.ANSWER_TERMS == {m: labels[m] for m, *_ in answer.ANSWER_METRICS}
    named = {n: tuple(getattr(_compare_module(n), n)) for n in (
        "SPEED_METRICS", "HEADLINE_METRICS", "ANSWER", "_NO_DIFFERENCE", "METRICS")}
    named |= {n: tuple(k.removeprefix("gap.") for k in getattr(_compare_module(n), n))
              for n in ("GAP_WORDS", "HEADLINE_WORDS")}
    for name, keys in named.items():
        assert keys and set(keys) <= set(units), (name, keys)


def test_the_whole_event_page_gives_the_declared_units():
    text = (ROOT / "docs" / "whole-event-metrics.md").read_text()
    rows = re.findall(r"^\| `(\w+)` \| ([^|]+) \|", text, flags=re.M)
    units = {m.name: m.unit for m in METRICS}
    assert len(rows) == 8
    assert {k: u.strip() for k, u in rows} == {k: units[k] for k, _ in rows}


def test_a_new_declaration_is_caught_where_it_still_needs_writing():
    """A declaration added alone: the API's Metrics, each of the tolerance file's [step.*]
    and [engines.*] sections (11 today) and the glossary report what it still needs."""
    metrics = (*METRICS, EXTRA)
    assert metrics_field_problems(metrics, ti.Metrics) == ["probe_time: no field"]
    changed = tuple(dataclasses.replace(m, unit="mm") if m.name == "x_max" else
                    dataclasses.replace(m, equation="eq 57") if m.name == "V" else m
                    for m in METRICS)
    assert metrics_field_problems(changed, ti.Metrics) == [
        "V: the docstring cites {'34'}, the declaration {'57'}",
        "x_max: the docstring does not end in its unit 'mm'"]
    tol = tomllib.loads(TOLERANCES.read_text())
    missing = tolerance_problems(metrics, tol)
    assert len(missing) == len(tol["step"]) + len(tol["engines"])
    assert all(p.endswith("] probe_time: no entry") for p in missing)
    assert glossary_problems(metrics) == ["probe_time: no glossary entry 'probe time'"]


PROBE = r"""
import json
from treeimpact.analytic import metrics, results
from treeimpact.compare.runs import verdicts
from treeimpact.compare.tree.ladder import ALL_METRICS, LADDER_METRICS, meaning_of, unit_of
print(json.dumps({"keys": metrics.METRIC_KEYS, "units": metrics.METRIC_UNITS,
                  "ladder": LADDER_METRICS, "all": ALL_METRICS,
                  "unit": unit_of("probe_time"), "meaning": meaning_of("probe_time"),
                  "times": results.TIME_KEYS, "why_none": verdicts.WHY_NONE.get("probe_time"),
                  "together": verdicts.MOVING_TOGETHER}))
"""


def test_adding_a_declaration_on_a_copy_is_one_line_and_the_lists_follow(tmp_path):
    copy = _copy(tmp_path)
    source = copy / "treeimpact/analytic/metrics.py"
    text = source.read_text()
    last = '"of the crown averaged over t_c (NaN for Newton impulses)", needs=FORCE),\n'
    assert text.count(last) == 1  # the last declaration
    text = text.replace(last, last + '    Metric("probe_time", "s", "probe time", "a probe\'s '
                        'time after the first touch", "eq 58", needs=PARTED),\n')
    source.write_text(text)
    proc = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True,
                          cwd=copy, env={"PYTHONPATH": str(copy), "PATH": "/usr/bin:/bin"},
                          timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    got = json.loads(proc.stdout)
    assert got["keys"] == [*METRIC_KEYS, "probe_time"]
    assert got["units"]["probe_time"] == ["s", "a probe's time after the first touch"]
    assert got["ladder"] == [*LADDER_METRICS, "probe_time"]
    assert "probe_time" in got["all"] and got["all"][:len(got["ladder"])] == got["ladder"]
    assert (got["unit"], got["meaning"]) == ("s", "a probe's time after the first touch")
    assert got["times"][-1] == "probe_time"  # checked against t_end as every time is
    assert "parted for good" in got["why_none"] and "probe_time" not in got["together"]
