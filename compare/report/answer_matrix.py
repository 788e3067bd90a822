"""The answer in one picture (issue 53): per tree, for each quantity a user of the paper's
model reads (x_max, the energy delivered, the crown's acceleration, eq 57's energy loss, the
identified M_T and K_T), whether each assumption (the 1-DOF trunk; small e) holds at the
tree's own pad and e, and by how much it is off.

:func:`matrix_cells` reads every cell from a number the report already holds (the answer
rows of :func:`.answer.one_dof_answer`, the small-e answers at the tree's e, the full-record
fits of the continuum's record) and judges it by the validity tolerance
(compare.runs.verdicts.validity_tolerance, 5 %): within it the assumption holds, beyond it it is
off; a number that does not exist is n/a with its reason. :func:`matrix_figure` draws the
cells (matplotlib, as :mod:`.figures`), readable in grey scale: "holds" light, "off" darker
the further off and hatched, n/a white with a letter naming its reason. SI units; relative
differences in 1 (drawn in %).
"""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass
from enum import StrEnum

import numpy as np
from matplotlib.colors import to_rgba
from matplotlib.patches import Patch, Rectangle

from ..runs.rungs import RungKind
from ..runs.verdicts import validity_tolerance
from .answer import one_dof_answer
from .figures import plt
from .scenario import fit_cells, fit_truth


class State(StrEnum):
    """A cell's verdict under the tolerance rule (the strings the table holds)."""

    HOLDS = "holds"  # |difference| <= the validity tolerance
    OFF = "off"  # beyond it
    NOT_AVAILABLE = "n/a"  # no number: the reason beside it


class Assumption(StrEnum):
    """The two assumptions of the paper the matrix judges (its columns, per tree)."""

    ONE_DOF = "1-DOF trunk"
    SMALL_E = "small e"


@dataclass(frozen=True)
class Quantity:
    """One row: its ``key``, ``label``, where its 1-DOF-trunk cell is read (``one_dof``: an
    answer metric, "pad_loss" or a full-record fit's "fit:M_T") and its small-e cell (the
    small-e approximation's name, compare.studies.small_e.APPROXIMATIONS; None: the paper
    draws no small-e formula for it)."""

    key: str
    label: str
    one_dof: str
    small_e: str | None


#: The rows, in the figure's order.
QUANTITIES = (
    Quantity("x_max", "x_max", "x_max", None),
    Quantity("energy_delivered", "energy delivered\n(small e: eq 58)", "energy_delivered",
             "eq58_energy_transferred"),
    Quantity("crown_acceleration", "crown acceleration*", "crown_peak_acceleration", None),
    Quantity("eq57_loss", "eq 57 energy loss", "pad_loss", "eq57_energy_loss"),
    Quantity("M_T", "identified M_T", "fit:M_T", "identification_M_T"),
    Quantity("K_T", "identified K_T", "fit:K_T", "identification_K_T"),
)
#: Why a small-e cell of a quantity without a small-e formula has no number.
NO_SMALL_E = "no small-e formula: the exact 1-DOF model gives it at any e"


def judge(value, tolerance: float) -> State:
    """The tolerance rule of the answer table (one_dof_answer's good_enough): ``value`` (a
    relative difference, 1) holds within +-``tolerance`` (1), is off beyond, n/a when it
    is None or not finite."""
    if value is None or not math.isfinite(value):
        return State.NOT_AVAILABLE
    return State.HOLDS if abs(value) <= tolerance else State.OFF


def cell_text(value, tolerance: float | None = None) -> str:
    """A cell's number, ``value`` (1) as the signed percentage, one decimal under 10 %, none
    above ('+1.2 %', '-77 %'), more (up to three) where the printed number would otherwise
    be judged otherwise than ``value`` against ``tolerance`` (1; -5.01 %, not -5.0 %, for an
    "off" cell); 'n/a' without a number (None, NaN)."""
    if value is None or not math.isfinite(value):
        return "n/a"
    digits = 1 if abs(value) < 0.095 else 0
    while tolerance is not None and digits < 3 and \
            judge(round(100 * value, digits) / 100, tolerance) != judge(value, tolerance):
        digits += 1
    return f"{100 * value:+.{digits}f} %"


def short_reason(text: str) -> str:
    """A reason ``text`` as the figure's legend says it: up to its first parenthesis (the
    full reason stays in the cell)."""
    return str(text).split(" (", 1)[0].strip().rstrip(".:;,")


def continuum_fits(scen_sections) -> dict:
    """Per scenario of ``scen_sections`` (the report's scenario sections, their fits made),
    the 1-DOF model fitted to the continuum's whole record (the beam rungs', mean over
    them) against the two-body model's truth (eqs 7-11): {tree: {"M_T": (error or None,
    reason or None), "K_T": ...}}; errors (fit - truth) / truth (1)."""
    out = {}
    for s in scen_sections:
        chains = [r.rung.id for r in s.ladder.rungs if r.rung.kind == RungKind.BEAM and r.ok]
        fits = {f["rung"]: f for f in getattr(s, "fits", [])}
        truth = fit_truth(s.ladder)
        tree = {}
        for k in ("M_T", "K_T"):
            errors, why = [], None
            for rid in chains:
                f = fits.get(rid)
                if f is None or f.get("error"):
                    why = f"{rid}: the fit did not run: {f['error']}" if f else \
                        f"{rid}: no full-record fit"
                    break
                cell = next(c for c in fit_cells(f, truth) if c["metric"] == k)
                if cell["error"] is None:
                    why = f"{rid}: the record does not fix {k}"
                    break
                errors.append(cell["error"])
            if not chains:
                why = "no continuum rung was run"
            tree[k] = (float(np.mean(errors)), None) if errors and why is None else (None, why)
        out[s.ladder.name] = tree
    return out


def _one_dof_cell(row: dict, q: Quantity, fits: dict) -> tuple:
    """(value, reason, source) of quantity ``q``'s 1-DOF-trunk cell of the answer ``row``."""
    tree = row["scenario"]
    if not row.get("available"):
        return None, row.get("why") or "no answer", f"answer[{tree}].why"
    if q.one_dof == "pad_loss":
        lo, hi = row["pad_loss"]["one_dof"], row["pad_loss"]["continuum"]
        ok = all(v is not None and math.isfinite(v) for v in (lo, hi)) and lo != 0.0
        return ((hi - lo) / abs(lo) if ok else None,
                None if ok else "no energy loss of the 1-DOF model or the continuum",
                f"answer[{tree}].pad_loss")
    if q.one_dof.startswith("fit:"):
        k = q.one_dof[4:]
        value, why = (fits.get(tree) or {}).get(k, (None, "no full-record fit"))
        return value, why, f"scenarios[{tree}].record_fits[beam].errors.{k}"
    rel = row["metrics"][q.one_dof]["rel"]
    ok = rel is not None and math.isfinite(rel)
    return (rel if ok else None, None if ok else "no 1-DOF value to compare with",
            f"answer[{tree}].metrics.{q.one_dof}.rel")


def _small_e_cell(answers: dict | None, tree: str, q: Quantity) -> tuple:
    """(value, reason, source) of quantity ``q``'s small-e cell of ``tree`` from its small-e
    answers (``answers``, compare.studies.small_e.small_e_answer; None: none made)."""
    if q.small_e is None:
        return None, NO_SMALL_E, None
    if not answers or q.small_e not in answers:
        return None, "no small-e curve was run", None
    a = answers[q.small_e]
    v = a["error_at_e"]
    source = f"small_e[{tree}].{q.small_e}.error_at_e"
    if v is not None and math.isfinite(v):
        return v, None, source
    why = (a.get("reasons") or {}).get(f"{a['e']:g}") or "no value at the tree's e"
    if q.small_e.startswith("identification_"):
        why = f"the paper's procedure on the exact 1-DOF record: {why}"
    return None, why, source


def matrix_cells(answer: list[dict], small_e_trees: dict, fits: dict,
                 tolerance: float) -> dict:
    """The matrix's table: per tree of the answer rows ``answer`` (one_dof_answer), for each
    of :data:`QUANTITIES` and each :class:`Assumption`, the cell {tree, quantity, label,
    assumption, value (relative difference, 1, or None), state (:func:`judge` against
    ``tolerance``), text (:func:`cell_text`), reason (None, or why there is no number),
    note (the legend's letter of the reason's :func:`short_reason`), source (where the
    number is read)}; ``small_e_trees``: tree -> its small-e answers; ``fits``:
    :func:`continuum_fits`. Returns {tolerance, trees (with e and pad, s), quantities,
    assumptions, cells, notes (letter -> reason)}."""
    cells, notes = [], {}
    for row in answer:
        tree = row["scenario"]
        for q in QUANTITIES:
            for assumption in Assumption:
                value, why, source = (_one_dof_cell(row, q, fits)
                                      if assumption == Assumption.ONE_DOF
                                      else _small_e_cell(small_e_trees.get(tree), tree, q))
                note = None
                if value is None:
                    text = short_reason(why)
                    note = next((k for k, t in notes.items() if t == text), None)
                    if note is None:
                        note = chr(ord("a") + len(notes))
                        notes[note] = text
                cells.append({"tree": tree, "quantity": q.key, "label": q.label,
                              "assumption": assumption, "value": value,
                              "state": judge(value, tolerance),
                              "text": cell_text(value, tolerance),
                              "reason": why, "note": note, "source": source})
    trees = [{"name": a["scenario"], "restitution": a.get("restitution"),
              "contact_duration": a.get("contact_duration")} for a in answer]
    return {"tolerance": tolerance, "trees": trees,
            "quantities": [{"key": q.key, "label": q.label} for q in QUANTITIES],
            "assumptions": list(Assumption), "cells": cells, "notes": notes}


#: The face of a cell that holds (light: grey 0.90 in luminance; every "off" is darker).
HOLDS_FACE = "#dcefd8"
#: The colour map of the cells that are off, by how far: from the tolerance (its 0.55,
#: grey 0.62) to :data:`FULL_DARK` times it (its 0.95, grey 0.17): darker the further off.
OFF_MAP, OFF_RANGE = "OrRd", (0.55, 0.95)
#: How many tolerances off a cell is at its darkest (5 % x 20 = 100 %).
FULL_DARK = 20.0
#: The narrowest figure (in): one tree's two columns leave its legend room.
MIN_WIDTH = 8.0
#: The legend's characters per line per inch of figure (8.5 pt text at figures.DPI: about
#: 7 px a character, 110 px an inch, less the margins).
LEGEND_CHARS = 11.0


def off_face(value: float, tolerance: float):
    """The RGBA face of a cell ``value`` (1) beyond ``tolerance`` (1): :data:`OFF_MAP` at
    the log of how many tolerances off it is, from :data:`OFF_RANGE`'s low end at the
    tolerance to its high end at :data:`FULL_DARK` tolerances and beyond."""
    lo, hi = OFF_RANGE
    share = min(1.0, math.log(abs(value) / tolerance) / math.log(FULL_DARK))
    return plt.get_cmap(OFF_MAP)(lo + (hi - lo) * max(0.0, share))


def luminance(rgba) -> float:
    """The grey the colour ``rgba`` (0-1 channels) turns into (ITU-R 601 luma, as PIL's
    convert('L')), 0-1."""
    r, g, b = rgba[:3]
    return 0.299 * r + 0.587 * g + 0.114 * b


def face_of(cell: dict, tolerance: float):
    """The RGBA face of ``cell`` (:func:`matrix_cells`): light for holds, :func:`off_face`
    (against ``tolerance``, 1) for off, white for n/a."""
    if cell["state"] == State.HOLDS:
        return to_rgba(HOLDS_FACE)
    if cell["state"] == State.OFF:
        return off_face(cell["value"], tolerance)
    return to_rgba("white")


def matrix_figure(matrix: dict):
    """The matrix of :func:`matrix_cells` (``matrix``): a row per quantity, two columns per
    tree (the 1-DOF trunk, small e), each cell its signed difference and its verdict in
    words ('holds', 'off'; hatched when off) or 'n/a (letter)' with the reasons in the
    legend below."""
    tol, trees = matrix["tolerance"], [t["name"] for t in matrix["trees"]]
    quantities, assumptions = matrix["quantities"], list(matrix["assumptions"])
    ncol = len(trees) * len(assumptions)
    width = max(1.55 * ncol + 2.6, MIN_WIDTH)
    fig, ax = plt.subplots(figsize=(width, 0.62 * len(quantities) + 3.0),
                           layout="constrained")
    cols = {(t, a): i * len(assumptions) + j for i, t in enumerate(trees)
            for j, a in enumerate(assumptions)}
    rows = {q["key"]: i for i, q in enumerate(quantities)}
    for cell in matrix["cells"]:
        _draw_cell(ax, cols[(cell["tree"], cell["assumption"])], rows[cell["quantity"]],
                   cell, tol)
    ax.set_xlim(0, ncol)
    ax.set_ylim(len(quantities), 0)
    ax.set_yticks([i + 0.5 for i in range(len(quantities))], [q["label"] for q in quantities])
    ax.set_xticks([i + 0.5 for i in range(ncol)], [a for _ in trees for a in assumptions],
                  fontsize=9)
    ax.xaxis.tick_top()
    ax.tick_params(length=0)
    ax.grid(False)
    for spine in ax.spines.values():
        spine.set_visible(False)
    for i, t in enumerate(matrix["trees"]):
        said = ([f"e = {t['restitution']:g}"] if t.get("restitution") is not None else []) + (
            [f"pad {1e3 * t['contact_duration']:g} ms"] if t.get("contact_duration") else [])
        ax.annotate(t["name"] + (f"\n({', '.join(said)})" if said else ""),
                    ((i + 0.5) * len(assumptions) / ncol, 1.0), xycoords="axes fraction",
                    xytext=(0, 22), textcoords="offset points", ha="center", va="bottom",
                    fontsize=10, fontweight="bold")
        if i:
            ax.axvline(i * len(assumptions), color="black", lw=2.0)
    _legend(fig, matrix, int(LEGEND_CHARS * width))
    fig.suptitle(f"Does each assumption hold at the tree's own pad and e? Each cell: the "
                 f"signed difference; holds within +-{100 * tol:.0f} %", fontsize=11)
    return fig


def _draw_cell(ax, x: int, y: int, cell: dict, tol: float) -> None:
    """One cell at column ``x``, row ``y``: its face, a hatch when off, its number and its
    verdict (or 'n/a (letter)')."""
    face = face_of(cell, tol)
    ax.add_patch(Rectangle((x, y), 1, 1, facecolor=face, edgecolor="white", lw=2.0))
    ink = "white" if luminance(face) < 0.45 else "black"
    if cell["state"] == State.OFF:  # hatched: off reads without colour
        ax.add_patch(Rectangle((x + 0.04, y + 0.06), 0.92, 0.88, fill=False, lw=0,
                               hatch="//", edgecolor=(0, 0, 0, 0.35)))
    if cell["state"] == State.NOT_AVAILABLE:
        ax.add_patch(Rectangle((x + 0.04, y + 0.06), 0.92, 0.88, fill=False, lw=0.8,
                               ls=(0, (2, 2)), edgecolor="0.45"))
        ax.text(x + 0.5, y + 0.5, f"n/a ({cell['note']})", ha="center", va="center",
                fontsize=9, color="0.25", style="italic")
        return
    box = {"boxstyle": "round,pad=0.15", "fc": face, "ec": "none"}  # the number over the hatch
    ax.text(x + 0.5, y + 0.42, cell["text"], ha="center", va="center", fontsize=11,
            fontweight="bold", color=ink, bbox=box)
    ax.text(x + 0.5, y + 0.78, str(cell["state"]), ha="center", va="center", fontsize=8,
            color=ink, bbox=box)


def _legend(fig, matrix: dict, chars: int) -> None:
    """The legend below the matrix: the three kinds of cell, what each column compares,
    and each n/a letter's reason, each line wrapped at ``chars`` characters."""
    tol = 100 * matrix["tolerance"]
    handles = [Patch(facecolor=HOLDS_FACE, edgecolor="0.6", label=f"holds: within +-{tol:.0f} %"),
               Patch(facecolor=off_face(2 * matrix["tolerance"], matrix["tolerance"]),
                     edgecolor="0.3", hatch="//",
                     label=f"off: beyond +-{tol:.0f} %, darker the further off (darkest from "
                           f"+-{tol * FULL_DARK:.0f} %)"),
               Patch(facecolor="white", edgecolor="0.45", ls="--",
                     label="n/a: no number; (letter) its reason, below")]
    words = ["1-DOF trunk: the continuum trunk (same pad) against the paper's 1-DOF model; "
             "M_T, K_T: the 1-DOF model fitted to the continuum's whole record against eqs "
             "7-11's",
             "small e: the paper's small-e formula (or its procedure, eqs 39-47, on the exact "
             "1-DOF record) against the exact 1-DOF model at the tree's e",
             "* mean over one collision duration"]
    words += [f"({k}) {v}" for k, v in matrix["notes"].items()]
    words = [textwrap.fill(w, chars, subsequent_indent="    ") for w in words]
    blank = [Patch(visible=False) for _ in words]
    fig.legend(handles + blank, [h.get_label() for h in handles] + words,
               loc="outside lower center", ncols=1, frameon=False, fontsize=8.5,
               handlelength=1.6, alignment="left")


def answer_matrix(scen_sections, small_e_trees: dict, sink=None) -> dict:
    """The report's matrix (:func:`matrix_cells`) of its scenario sections ``scen_sections``
    (their fits made) and small-e answers ``small_e_trees`` (tree -> answers), judged by
    compare.runs.verdicts.validity_tolerance, with its ``figure``: the path ``sink(fig, stem)``
    gives (:class:`.figures.FigureFiles`; None without a sink)."""
    matrix = matrix_cells(one_dof_answer(scen_sections), small_e_trees,
                          continuum_fits(scen_sections), validity_tolerance())
    # every tree's e and pad from its scenario (a tree without an answer row has neither)
    contacts = [(s.ladder.name, s.ladder.scenario.contact) for s in scen_sections]
    matrix["trees"] = [{"name": name, "restitution": c.restitution,
                        "contact_duration": c.duration} for name, c in contacts]
    matrix["figure"] = sink(matrix_figure(matrix), "answer-matrix") if sink else None
    return matrix
