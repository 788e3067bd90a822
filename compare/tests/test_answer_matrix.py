"""The answer's matrix (issue 53 item 2): every cell read from the number it names and judged
by the 5 % rule, n/a with its reason where the number does not exist, and the figure drawing
exactly those numbers in faces that stay apart in grey scale. A report's own matrix is
checked against its report.json in compare/tests/test_report.py."""

from __future__ import annotations

import math

import numpy as np
import pytest
from matplotlib.colors import to_rgba
from matplotlib.patches import Rectangle
from matplotlib.text import Annotation

from treeimpact.compare.report.answer_matrix import (
    HOLDS_FACE,
    NO_SMALL_E,
    QUANTITIES,
    Assumption,
    State,
    cell_text,
    judge,
    luminance,
    matrix_cells,
    matrix_figure,
)

TOL = 0.05


def _metrics(x_max, energy, accel):
    return {m: {"rel": v} for m, v in (("x_max", x_max), ("energy_delivered", energy),
                                        ("crown_peak_acceleration", accel))}


def _small_e(e, eq57, eq58, m_t, k_t, why=None):
    def a(v):
        return {"error_at_e": v, "e": e, "reasons": {} if v is not None else {f"{e:g}": why}}
    return {"eq57_energy_loss": a(eq57), "eq58_energy_transferred": a(eq58),
            "identification_M_T": a(m_t), "identification_K_T": a(k_t)}


#: Two trees with an answer (one whose identification is refused at its e) and one without.
ANSWER = [
    {"scenario": "stiff", "available": True, "restitution": 0.1, "contact_duration": 5e-4,
     "metrics": _metrics(0.05, -0.0501, 2.4),  # the rule's edge: 5 % holds, 5.01 % is off
     "pad_loss": {"one_dof": 100.0, "continuum": 98.0}},
    {"scenario": "light", "available": True, "restitution": 0.3, "contact_duration": None,
     "metrics": _metrics(0.93, 0.002, -0.7), "pad_loss": {"one_dof": 40.0, "continuum": 10.0}},
    {"scenario": "failed", "available": False, "why": "beam: diverged"},  # as one_dof_answer's
]
SMALL_E = {"stiff": _small_e(0.1, 0.001, -0.0006, -0.19, -0.26),
           "light": _small_e(0.3, -0.02, 0.008, None, None,
                             "not identifiable: the impact process is not short (23 ms)")}
FITS = {"stiff": {"M_T": (-0.49, None), "K_T": (0.07, None)},
        "light": {"M_T": (None, "beam: the record does not fix M_T"), "K_T": (0.15, None)}}


def _expected(tree: str, quantity: str, assumption: Assumption):
    """The number each cell must hold, read from the inputs directly (None: none)."""
    row = next(a for a in ANSWER if a["scenario"] == tree)
    if not row["available"]:
        return None
    if assumption == Assumption.ONE_DOF:
        if quantity == "eq57_loss":
            lo, hi = row["pad_loss"]["one_dof"], row["pad_loss"]["continuum"]
            return (hi - lo) / lo
        if quantity in ("M_T", "K_T"):
            return FITS[tree][quantity][0]
        key = {"crown_acceleration": "crown_peak_acceleration"}.get(quantity, quantity)
        return row["metrics"][key]["rel"]
    name = {"energy_delivered": "eq58_energy_transferred", "eq57_loss": "eq57_energy_loss",
            "M_T": "identification_M_T", "K_T": "identification_K_T"}.get(quantity)
    return SMALL_E[tree][name]["error_at_e"] if name else None


def test_every_cell_is_the_number_it_reads_judged_by_the_rule():
    matrix = matrix_cells(ANSWER, SMALL_E, FITS, TOL)
    cells = {(c["tree"], c["quantity"], c["assumption"]): c for c in matrix["cells"]}
    assert len(cells) == len(ANSWER) * len(QUANTITIES) * len(Assumption)
    for (tree, quantity, assumption), c in cells.items():
        want = _expected(tree, quantity, assumption)
        if want is None:
            assert c["value"] is None and c["state"] == State.NOT_AVAILABLE
            assert c["text"] == "n/a" and c["reason"] and c["note"] in matrix["notes"]
            continue
        assert c["value"] == pytest.approx(want, rel=1e-12)  # read, not recomputed
        assert c["state"] == (State.HOLDS if abs(want) <= TOL else State.OFF)
        assert c["text"] == cell_text(want, TOL) and c["note"] is None
    assert cells[("stiff", "x_max", Assumption.ONE_DOF)]["state"] == State.HOLDS  # 5 %
    edge = cells[("stiff", "energy_delivered", Assumption.ONE_DOF)]
    assert edge["state"] == State.OFF and edge["text"] == "-5.01 %"  # not "-5.0 %": off
    assert cells[("stiff", "x_max", Assumption.ONE_DOF)]["text"] == "+5.0 %"
    assert cells[("stiff", "eq57_loss", Assumption.ONE_DOF)]["value"] == pytest.approx(-0.02)


def test_a_cell_without_a_number_says_why():
    matrix = matrix_cells(ANSWER, SMALL_E, FITS, TOL)
    cells = {(c["tree"], c["quantity"], c["assumption"]): c for c in matrix["cells"]}
    notes = matrix["notes"]
    assert notes[cells[("stiff", "x_max", Assumption.SMALL_E)]["note"]] == NO_SMALL_E
    refused = cells[("light", "M_T", Assumption.SMALL_E)]
    assert "not identifiable: the impact process is not short" in notes[refused["note"]]
    assert "(23 ms)" in refused["reason"] and "(23 ms)" not in notes[refused["note"]]
    assert notes[cells[("light", "M_T", Assumption.ONE_DOF)]["note"]] == \
        "beam: the record does not fix M_T"
    assert notes[cells[("failed", "x_max", Assumption.ONE_DOF)]["note"]] == "beam: diverged"
    assert len(set(notes.values())) == len(notes)  # one letter per reason


def test_judge_and_text():
    assert judge(-0.05, TOL) == State.HOLDS and judge(0.0500001, TOL) == State.OFF
    assert judge(math.nan, TOL) == State.NOT_AVAILABLE and judge(None, TOL) == \
        State.NOT_AVAILABLE
    assert (cell_text(0.0123), cell_text(-0.77), cell_text(2.13), cell_text(None)) == (
        "+1.2 %", "-77 %", "+213 %", "n/a")
    # printed on the side of the tolerance the value lies: more digits only where needed
    assert (cell_text(0.0501, TOL), cell_text(0.05, TOL), cell_text(0.04996, TOL),
            cell_text(0.0499999, TOL)) == ("+5.01 %", "+5.0 %", "+5.0 %", "+5.0 %")


def _drawn(fig):
    """(column, row) -> (face RGBA, hatched, [texts]) of the cells the figure draws."""
    ax = fig.axes[0]
    out = {}
    for p in ax.patches:
        if isinstance(p, Rectangle) and p.get_width() == 1:
            out[(int(p.get_x()), int(p.get_y()))] = [p.get_facecolor(), False, []]
    for p in ax.patches:
        if isinstance(p, Rectangle) and p.get_hatch():
            out[(int(p.get_x()), int(p.get_y()))][1] = True
    for t in ax.texts:
        if isinstance(t, Annotation):  # the trees' heads above the matrix
            continue
        x, y = t.get_position()
        out[(int(x), int(y))][2].append(t.get_text())
    return out


def test_the_figure_draws_each_cell_s_number_in_its_verdict_s_face():
    matrix = matrix_cells(ANSWER, SMALL_E, FITS, TOL)
    fig = matrix_figure(matrix)
    drawn = _drawn(fig)
    trees = [t["name"] for t in matrix["trees"]]
    rows = [q.key for q in QUANTITIES]
    assert len(drawn) == len(matrix["cells"])
    holds = luminance(to_rgba(HOLDS_FACE))
    for c in matrix["cells"]:
        col = 2 * trees.index(c["tree"]) + list(Assumption).index(c["assumption"])
        face, hatched, texts = drawn[(col, rows.index(c["quantity"]))]
        if c["state"] == State.NOT_AVAILABLE:
            assert texts == [f"n/a ({c['note']})"] and face == to_rgba("white")
            continue
        assert texts == [c["text"], str(c["state"])]
        assert hatched == (c["state"] == State.OFF)
        if c["state"] == State.HOLDS:
            assert face == to_rgba(HOLDS_FACE)
        else:  # apart from "holds" in grey: 0.2 of the grey range, a step an eye sees
            assert luminance(face) < holds - 0.2
    legend = " ".join(t.get_text() for t in fig.legends[0].get_texts())
    assert all(f"({k}) {v}" in legend for k, v in matrix["notes"].items())


def test_in_grey_the_off_cells_are_darker_than_the_ones_that_hold():
    """The drawn pixels turned grey (ITU-R 601, PIL's convert('L')): every "off" cell's
    median darker than every "holds" cell's, n/a white."""
    matrix = matrix_cells(ANSWER, SMALL_E, FITS, TOL)
    fig = matrix_figure(matrix)
    fig.canvas.draw()
    rgba = np.asarray(fig.canvas.buffer_rgba(), float)[..., :3] / 255
    grey = rgba @ np.array([0.299, 0.587, 0.114])
    ax, height = fig.axes[0], grey.shape[0]
    trees = [t["name"] for t in matrix["trees"]]
    medians = {}
    for c in matrix["cells"]:
        col = 2 * trees.index(c["tree"]) + list(Assumption).index(c["assumption"])
        row = [q.key for q in QUANTITIES].index(c["quantity"])
        (x0, y0), (x1, y1) = ax.transData.transform([(col + 0.1, row + 0.1),
                                                     (col + 0.9, row + 0.9)])
        patch = grey[int(height - y0):int(height - y1), int(x0):int(x1)]
        medians.setdefault(c["state"], []).append(float(np.median(patch)))
    assert max(medians[State.OFF]) < min(medians[State.HOLDS]) - 0.1
    assert min(medians[State.NOT_AVAILABLE]) > 0.98


@pytest.mark.parametrize("trees", [1, 3])
def test_every_text_lies_inside_the_figure_saved_as_the_report_saves_it(tmp_path, trees):
    """One tree (a user's report: the narrowest figure, a long name) and three: the
    suptitle, the trees' heads, the cells and every legend line inside the figure's box."""
    from treeimpact.compare.report.figures import FigureFiles
    from treeimpact.compare.runs import figure_text

    name = "a-user-tree-with-a-rather-long-name"
    rows = [dict(ANSWER[1], scenario=f"{name}-{i}") for i in range(trees)]
    matrix = matrix_cells(rows, {r["scenario"]: SMALL_E["light"] for r in rows},
                          {r["scenario"]: FITS["light"] for r in rows}, TOL)
    fig = matrix_figure(matrix)
    FigureFiles(tmp_path)(fig, "answer-matrix")  # titles fitted as the report's are
    renderer, box = figure_text.renderer_of(fig), fig.bbox
    texts = [fig._suptitle, *fig.axes[0].texts, *fig.legends[0].get_texts()]
    out = [t.get_text() for t in texts if not box.contains(
        *t.get_window_extent(renderer).min) or not box.contains(
        *t.get_window_extent(renderer).max)]
    assert not out, out
