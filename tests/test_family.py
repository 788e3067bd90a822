"""A family of trees across the regimes (compare/tree/family.py; issue 50 items 2 and 8), at small
sizes, through what a user runs: ``treeimpact simulate`` on every backend (and the beam's
Timoshenko theory), ``pytest compare --scenario``, ``treeimpact report`` with its study (the
design map at its smallest, 2 values an input) and the design map itself. Each output is
finite, or refused in one line (exit 2 or 4), never a traceback; no check has a verdict
``n/a``; a skipped check says why in the tree's physics; a sentence reads only cells that
exist.

Cost: ``simulate`` runs on every member; ``pytest compare`` (a ladder of 12 rungs each) on
four members that cover the regimes and the exits (one impact, a billet, a re-strike after
moving together, the cut run), the report on three of them, the design map on five; the
whole family at full size is benchmarks/bench_family.py's.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import re
import subprocess
import sys

import pytest

from treeimpact.analytic.contact.soft import simulate_soft
from treeimpact.compare.interface.cli import main
from treeimpact.compare.runs.verdicts import MOVING_TOGETHER, WHY_NONE
from treeimpact.compare.tree import family as F

FAMILY = {m.name: (m, s, r) for m, s, r in F.family()}
#: The members whose ladder runs here (pytest compare; the report without low-clamp, its
#: 21-segment chain the dearest); the design map's; the rest: the benchmark.
LADDER = ("bounce-off", "free-billet", "low-clamp", "cut-by-t-end")
REPORTED = ("bounce-off", "free-billet", "cut-by-t-end")
MAPPED = ("bounce-off", "never-together", "cut-by-t-end", "low-clamp", "free-billet")
#: simulate's backends at small sizes: the fewest segments and elements each allows.
BACKENDS = {"analytic": [], "soft": [], "beam": ["--elements", "4"],
            "timoshenko": ["--backend", "beam", "--beam-theory", "timoshenko",
                           "--elements", "4"],
            "mujoco": ["--segments", "2"], "bullet": ["--segments", "2"]}
TRACEBACK = re.compile(r"Traceback \(most recent call last\)|^E\s+AssertionError", re.M)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    return F.write_family(tmp_path_factory.mktemp("family"))


def _one_line_refusal(code: int, err: str) -> None:
    """A refusal: exit 2 (bad input, a run the model cannot make) or 4 (ran, not as asked),
    one line on stderr, no traceback."""
    assert code in (2, 4), (code, err)
    lines = [ln for ln in err.strip().splitlines() if not ln.startswith("warning")]
    assert len(lines) == 1 and not TRACEBACK.search(err), err


# --------------------------------------------------------------------------- the family


def test_the_family_spans_the_regimes_and_both_impactors():
    """Built from m/M_T, a/l, m_f, e and the impactor; each regime as the exact solver found
    it (family() refuses a member out of the regime it was built for)."""
    regimes = [r for _, _, r in FAMILY.values()]
    assert len(FAMILY) >= 8
    assert any(r.n_impacts == 1 and not r.together for r in regimes)  # one impact, bounce-off
    assert any(r.n_impacts >= 3 and r.together for r in regimes)  # many impacts
    assert any(r.n_impacts >= 2 and not r.together for r in regimes)  # never moving together
    assert any(r.cut for r in regimes) and any(r.restrike for r in regimes)
    kinds = {m.impactor for m, _, _ in FAMILY.values()}
    assert kinds == set(F.Impactor)
    crowns = [s.trunk.crown_mass for _, s, _ in FAMILY.values()]
    clamps = [s.trunk.clamp_height / s.trunk.length for _, s, _ in FAMILY.values()]
    assert min(crowns) < 1.0 < 30.0 < max(crowns) and min(clamps) < 0.2 < 0.6 < max(clamps)


@pytest.mark.parametrize("name", list(FAMILY))
def test_the_soft_sdof_shows_the_same_regime(name):
    """An independent model of the same 1-DOF pair (the soft pad, DOP853) moves together
    where the Newton model does, and parts where it parts (the pad's 0.5 ms collision is 1 %
    of the trunk's period: the same sequence, with an impact's duration)."""
    _, scen, regime = FAMILY[name]
    m = simulate_soft(scen).metrics
    assert math.isfinite(m["T0"]) == regime.together, m["T0"]
    if regime.together:
        assert math.isfinite(m["t_sep"]) != regime.cut, m["t_sep"]


# --------------------------------------------------------------------------- simulate


def _simulate(path, extra) -> tuple[int, str, str]:
    args = ["simulate", str(path), "--json"]
    args += extra if "--backend" in extra else ["--backend", _backend_of(extra)] + extra
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(args)
    return code, out.getvalue(), err.getvalue()


def _backend_of(extra) -> str:
    return next(b for b, e in BACKENDS.items() if e is extra)


@pytest.mark.parametrize("backend", list(BACKENDS))
@pytest.mark.parametrize("name", list(FAMILY))
def test_simulate_every_backend(files, name, backend):
    """Exit 0 with every metric a finite number, or null only where the tree's motion has
    no such quantity (compare.runs.verdicts.WHY_NONE); or a one-line refusal."""
    code, out, err = _simulate(files[name], BACKENDS[backend])
    if code != 0:
        _one_line_refusal(code, err)
        return
    metrics = json.loads(out)["metrics"]
    assert metrics["x_max"] > 0 and metrics["n_impacts"] >= 1
    for key, v in metrics.items():
        assert v is None and key in WHY_NONE or math.isfinite(v), (key, v)
    if backend == "analytic":  # the moving-together metrics exist iff the bodies move together
        regime = FAMILY[name][2]
        assert (metrics["T0"] is not None) == regime.together
        assert metrics["n_impacts"] == regime.n_impacts


# --------------------------------------------------------------------------- pytest compare


@pytest.fixture(scope="module")
def compare_session(files):
    """One ``pytest compare`` session over the ladder members that run (the cut one ends
    the session at once: its own run below)."""
    args = [a for n in LADDER if n != "cut-by-t-end" for a in ("--scenario", str(files[n]))]
    proc = subprocess.run([sys.executable, "-m", "pytest", "compare", *args, "-q", "-rfsx",
                           "-p", "no:xdist", "-p", "no:cacheprovider"],
                          capture_output=True, text=True, timeout=1200)
    return proc


def _failed(proc, name) -> list[str]:
    return re.findall(rf"^FAILED \S+\[{re.escape(name)}-[^\]]*\]", proc.stdout, re.M)


@pytest.mark.parametrize("name", [n for n in LADDER if n != "cut-by-t-end"])
def test_pytest_compare_has_no_n_a_verdict_and_no_traceback(compare_session, name):
    """No check of the tree fails with a verdict n/a or a raw traceback; each skip of it
    carries its reason (pytest's ``-rs`` line)."""
    out = compare_session.stdout
    assert compare_session.returncode in (0, 1), out[-2000:]
    assert not TRACEBACK.search(out), out[-3000:]
    tables = re.findall(r"^metric .*verdict.*\n.*$", out, re.M)
    for table in tables:
        head, row = table.splitlines()
        assert row[head.index("verdict"):head.index("reason")].strip() != "n/a", table
    skips = re.findall(rf"^SKIPPED \[\d+\] \S+: {re.escape(name)} (.*)$", out, re.M)
    assert skips  # the tree's absent quantities are skipped, each with its words
    for reason in skips:
        assert re.search(r"never move together|does not apply|billet|regimes|part|"
                         r"instantaneous|not available|impactor is a billet", reason), reason


@pytest.mark.parametrize("name", [n for n in LADDER if n != "cut-by-t-end"])
def test_pytest_compare_passes_on_the_tree(compare_session, name):
    """Every check of the tree passes with the tolerances and reasons of that tree (issue
    50 item 3: per-tree bounds, the segments chosen by the compared metrics' convergence)."""
    assert _failed(compare_session, name) == []


def test_pytest_compare_refuses_a_run_the_paper_s_model_cannot_make(files):
    """The cut member: the paper's model has no energy delivered before the bodies part;
    the session ends at once with the one-line reason (exit 2)."""
    proc = subprocess.run([sys.executable, "-m", "pytest", "compare", "--scenario",
                           str(files["cut-by-t-end"]), "-q", "-p", "no:xdist",
                           "-p", "no:cacheprovider"], capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 2 and "still in contact at the end" in proc.stdout + proc.stderr
    assert not TRACEBACK.search(proc.stdout + proc.stderr)


# --------------------------------------------------------------------------- design map, report


@pytest.fixture(scope="module")
def designs(files, tmp_path_factory):
    """Each member's design map at its smallest (2 values an input, in this process)."""
    import treeimpact as ti

    root = tmp_path_factory.mktemp("design")
    out = {}
    for name in MAPPED:
        paths = ti.design_map(root / name, str(files[name]), count=2, workers=0)
        out[name] = json.loads(paths["json"].read_text())
    return out, root


def _labels(design) -> dict:
    return {q: v["label"] for q, v in design["quantities"].items()}


@pytest.mark.parametrize("name", MAPPED)
def test_the_design_map_reads_only_cells_that_exist(designs, name):
    """The tree's own sentence names only quantities its own cell has; a sentence along an
    input whose line and own cell have no number says so ('no cell', 'no number')."""
    design = designs[0][name]
    cell, labels = design["cell"], _labels(design)
    for q, label in labels.items():
        if cell[q] is None:
            assert f" on {label}" not in design["at_point"], (q, design["at_point"])
    if all(v is None for v in cell.values()):
        assert "has no numbers" in design["at_point"]
    for pair in design["pairs"]:
        for s in pair["sentences"]:
            q = s.get("quantity")
            if q in pair["maps"] and cell.get(q) is None and all(
                    v is None for row in pair["maps"][q] for v in row):
                assert "no cell" in s["text"] or "no number" in s["text"], s["text"]
            for lo, hi in s.get("within") or []:  # a stretch read off the input's range
                assert math.isfinite(lo) and math.isfinite(hi) and lo <= hi, s


@pytest.fixture(scope="module")
def report(files, designs, tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    args = [a for n in REPORTED for a in ("--scenario", str(files[n]))]
    proc = subprocess.run([sys.executable, "-m", "treeimpact.compare.interface.cli", "report",
                           *args, "--study", str(designs[1] / REPORTED[0]), "--out", str(out)],
                          capture_output=True, text=True, timeout=1200)
    return proc, out


def test_the_report_with_its_study_is_written_for_every_regime(report):
    """Exit 4 (the cut member has no 1-DOF answer: named on stderr in one line), the pages
    written; no check of any tree has a verdict n/a (a quantity the tree does not have is
    'skipped' with its reason); the answer's sentences read only values that exist."""
    proc, out = report
    _one_line_refusal(proc.returncode, proc.stderr)
    assert "cut-by-t-end" in proc.stderr
    data = json.loads((out / "report.json").read_text())
    for name, section in data["scenarios"].items():
        for c in section["checks"]:
            assert c["verdict"] != "n/a" or c["reference"] == "truth", (name, c)
            if c["verdict"] == "skipped":
                assert re.search(r"move together|part|instantaneous|regimes|procedure",
                                 c["reason"]), c
    answer = data["answer"]
    assert "No answer for cut-by-t-end" in answer["in_short"]["one_dof"]
    _small_e_reads_existing_cells(answer)
    assert (out / "report.html").stat().st_size and (out / "report.md").stat().st_size


#: What a shipped tree's measurement looks like in words: its name, or the three trees'
#: values side by side ("+4.0 / +4.2 / +1.9 %").
SHIPPED_WORDS = re.compile(r"open-center|central-leader|realistic-crown|"
                           r"[-+]?\d[\d.]* / [-+]?\d[\d.]* / [-+]?\d[\d.]*")


def test_no_reason_shown_for_a_tree_quotes_a_shipped_tree(report):
    """Every reason the report shows for a family member (each check's, each step left
    uncompared) quotes that tree's numbers or none (issue 50 item 3): no tolerance entry's
    ``measured`` words (the shipped trees' evidence, shown on those trees only), no shipped
    tree's name and no three trees' values side by side."""
    from treeimpact.compare.runs.verdicts import load_tolerances

    tol = load_tolerances()
    measured = [e["measured"] for section in ("step", "engines")
                for kind in tol.get(section, {}).values() for e in kind.values()
                if "measured" in e]
    measured += [e["measured"] for e in tol.get("identification", {}).values()
                 if isinstance(e, dict) and "measured" in e]
    data = json.loads((report[1] / "report.json").read_text())
    for name, section in data["scenarios"].items():
        reasons = [c["reason"] for c in section["checks"]]
        reasons += [n["reason"] for n in section.get("not_compared", [])]
        for reason in reasons:
            assert not any(m in reason for m in measured), (name, reason)
            assert not SHIPPED_WORDS.search(reason), (name, reason)


def _small_e_reads_existing_cells(answer) -> None:
    """Each tree the small-e sentence names as having no value at e = 0 for a consequence
    has none there, and each range it quotes at e = 0 rests on a tree that has one."""
    text, trees = answer["in_short"]["small_e"], answer["small_e"]
    first = next(iter(trees.values()))
    for q, a in first.items():
        label = a["label"].split(": ", 1)[-1]
        found = re.search(rf"{re.escape(label)} [-+0-9.]+(?:\.\.[-+0-9.]+)? %"
                          rf"(?: \(no value at e = 0 on ([^)]*)\))?", text)
        if not found:
            continue
        zeros = {tree: t[q]["error_at_zero"] for tree, t in trees.items()}
        assert any(z is not None and math.isfinite(z) for z in zeros.values()), (q, zeros)
        for tree in (found.group(1) or "").split(", ") if found.group(1) else []:
            assert zeros[tree] is None or not math.isfinite(zeros[tree]), (q, tree)
