"""Issue 39 item 3 (make report's non-physics work): fitting a figure's titles
(compare.runs.figure_text.fit_titles) lays it out once per round with its layout engine alone; each
round was a draw with no output of every artist before, on top of savefig's two draws (its
own no-output one, then the one it writes). Counted here (a round's draw that comes back
fails), and the PNG bytes checked against the old procedure (written out below as the
reference) on the report's own figures of a tree and on a figure whose titles wrap. savefig's
own no-output draw stays: a layout in its place moves some of the report's figures by
a pixel (the displacement and contact-scan figures in a whole make report)."""

from __future__ import annotations

import io
from unittest import mock

import pytest
from matplotlib.figure import Figure
from matplotlib.layout_engine import ConstrainedLayoutEngine

from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.compare.report import figures as report_figures
from treeimpact.compare.runs import figure_text
from treeimpact.compare.tree.ladder import build_ladder

DPI = report_figures.DPI


def _old_save(fig, buf) -> None:
    """The procedure before this change: a draw with no output each round, then savefig."""
    fig.set_dpi(DPI)
    renderer = figure_text.renderer_of(fig)
    for _ in range(figure_text.ROUNDS):
        fig.draw_without_rendering()
        if not any([figure_text._wrap(t, room, renderer)
                    for t, room in figure_text.titles(fig)]):
            break
    fig.savefig(buf, dpi=DPI, format="png")


def _wrapping() -> Figure:
    """Two subfigures, long titles that wrap, a legend beside the axes: constrained layout."""
    fig = Figure(figsize=(7.4, 4.0), layout="constrained")
    fig.suptitle("A suptitle far too long for this figure's width at the report's dpi, so "
                 "that it wraps onto a second and maybe a third line " * 2)
    for k, sub in enumerate(fig.subfigures(1, 2)):
        ax = sub.subplots()
        ax.plot([0, 1, 2], [k, 2 * k + 1, 0.5], label=f"rung {k}")
        ax.set_title("an axes title long enough to be wrapped in half the figure " * 2)
        sub.legend(loc="outside right upper")
    return fig


@pytest.fixture(scope="module")
def ladder():
    """The central-leader ladder without the engines (exact runs only, a second)."""
    return build_ladder(load_scenario("central-leader"), engines=())


def _figures(ladder) -> dict:
    return {"displacement": report_figures.displacement_figure(ladder),
            "force": report_figures.force_figure(ladder),
            "sequence": report_figures.sequence_figure(ladder), "wrapping": _wrapping()}


def test_same_png_bytes_as_a_draw_per_round(ladder):
    """Every figure written by save_figure is, byte for byte, what the old procedure wrote
    (no tolerance: the same layout passes from the same state give the same pixels)."""
    old, new = _figures(ladder), _figures(ladder)
    for name in old:
        a, b = io.BytesIO(), io.BytesIO()
        _old_save(old[name], a)
        figure_text.save_figure(new[name], b, DPI, format="png")
        assert a.getvalue() == b.getvalue(), name


def test_only_savefig_draws(ladder):
    """save_figure draws a figure only in savefig (twice: without output, then written) and
    lays it out once per fitting round plus savefig's one: a draw per round coming back
    fails here."""
    for name, fig in _figures(ladder).items():
        with mock.patch.object(Figure, "draw", autospec=True,
                               side_effect=Figure.draw) as draw, \
                mock.patch.object(ConstrainedLayoutEngine, "execute", autospec=True,
                                  side_effect=ConstrainedLayoutEngine.execute) as layout:
            figure_text.save_figure(fig, io.BytesIO(), DPI, format="png")
        assert draw.call_count == 2, name
        # one per fitting round (one, and one more per round that wrapped a title), plus
        # savefig's (in its no-output draw; it writes the figure with that layout)
        assert 2 <= layout.call_count <= figure_text.ROUNDS + 1, name
