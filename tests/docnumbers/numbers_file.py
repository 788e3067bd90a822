"""docs/numbers.json written from a report directory (:func:`write_numbers`): the report's
numbers, the cheap part rerun now (and where the two disagree), only the keys the pages
quote, and the report's figures the pages show copied beside them."""

from __future__ import annotations

import json
from pathlib import Path

from .base import NUMBERS, RECOMPUTE_REL, ROOT
from .from_design import from_design
from .from_report import from_sensitivity, from_small_e, from_study, from_view, view_from_report
from .marks import used_keys
from .rerun import cheap_numbers

#: Keys kept in docs/numbers.json although no page quotes them (tests read them).
KEEP = ("scan", "checks.")


def write_numbers(report_dir: Path, path: Path = NUMBERS) -> list[str]:
    """docs/numbers.json from a report directory and the cheap part rerun now; returns the
    keys where the two disagree beyond :data:`RECOMPUTE_REL` (the report is from other
    code than this checkout: rerun ``make report``)."""
    from treeimpact.compare.runs.provenance import code_version, environment

    report = json.loads((Path(report_dir) / "report.json").read_text())
    out = (from_view(view_from_report(report)) | from_sensitivity(report)
           | from_small_e(report["answer"]["small_e"])
           | from_design(report["answer"].get("design", {})))
    study = Path(report_dir) / "study" / "study.json"
    if study.exists():
        out |= from_study(json.loads(study.read_text()))
    cheap = cheap_numbers()
    drift = [k for k, v in cheap.items() if k in out and not _close(out[k], v, RECOMPUTE_REL)]
    out |= cheap
    out = {k: v for k, v in out.items() if k in used_keys(out) or k.startswith(KEEP)}
    data = {"about": "The numbers README.md and docs/*.md quote (tests/docnumbers/): derived "
                     "from a report by `python -m tests.docnumbers numbers REPORT_DIR`, its "
                     "cheap part rerun; display units as the keys say (DISPLAY in "
                     "tests/docnumbers/base.py for value.*); [a, b] is a range (min, max).",
            "report": {"generated": report.get("generated"),
                       "provenance": report.get("provenance", {}).get("code")},
            "code": code_version(), "environment": environment(),
            "figures": copy_figures(Path(report_dir), report),
            "texts": texts_from_report(report),
            "numbers": dict(sorted(out.items()))}
    path.write_text(json.dumps(data, indent=1) + "\n")
    return drift



def texts_from_report(report: dict) -> dict:
    """The report's generated sentences a page quotes whole (its generated blocks): what to
    measure first on each tree (compare.report.measure.first_text) and the design answer on
    the first screen (compare.report.design_answer.in_short_text), tree -> sentence."""
    from treeimpact.compare.report.design_answer import tree_text

    rows = report.get("answer", {}).get("one_dof", [])
    design = report.get("answer", {}).get("design", {})
    return {"measure_first": {a["scenario"]: a["measure_first"]["said"] for a in rows
                              if (a.get("measure_first") or {}).get("said")},
            "design": {tree: tree_text(a) for tree, a in design.items()}}


#: The report's figures the pages show, copied with the numbers: page path -> report path.
FIGURES = {"docs/img/answer-matrix.png": "figures/answer-matrix.png",
           "docs/img/contact-scan.png": "figures/contact-scan.png",
           "docs/img/small-e.png": "figures/small-e.png",
           "docs/img/design-map.png": "design/design-a_over_l-contact_duration.png"}


def copy_figures(report_dir: Path, report: dict) -> dict:
    """Copy :data:`FIGURES` from the report directory into docs/ (the README shows the
    contact scan); what was copied, with each copy's SHA-1 and the report it came from
    (tests/test_doc_numbers.py checks the copies are these)."""
    import hashlib
    import shutil

    out = {}
    for page_path, report_path in FIGURES.items():
        source = Path(report_dir) / report_path
        if not source.exists():
            continue
        shutil.copyfile(source, ROOT / page_path)
        out[page_path] = {"from": report_path, "report_generated": report.get("generated"),
                          "sha1": hashlib.sha1((ROOT / page_path).read_bytes()).hexdigest()}
    return out


def _close(a, b, rel: float) -> bool:
    if isinstance(a, list) or isinstance(b, list):
        return (isinstance(a, list) and isinstance(b, list) and len(a) == len(b)
                and all(_close(x, y, rel) for x, y in zip(a, b)))
    return abs(a - b) <= rel * max(abs(a), abs(b)) + 1e-12
