"""Figure titles that fit the figure at the width it is drawn: every figure the report and the
studies write is saved through :func:`save_figure`, which wraps a title (an axes' title, the
figure's suptitle) wider than its room onto more lines before the figure lays itself out
(constrained layout makes the room for the extra lines). Measured with the figure's own
renderer at the dpi it is written at (a 737 px figure wraps where an 1100 px one does not).
On floor 1 of compare so that every floor that draws a figure may use it."""

from __future__ import annotations

import textwrap

#: Fraction of its room a title may fill (a margin against the antialiased glyph edges).
ROOM = 0.97
#: Rounds of measure, wrap, lay out again (a wrapped suptitle moves the axes below it).
ROUNDS = 4


def renderer_of(fig):
    """The renderer of the figure ``fig`` (an Agg canvas attached to a bare ``Figure``
    first)."""
    if not hasattr(fig.canvas, "get_renderer"):
        # lazy: +430 ms at import otherwise (matplotlib's Agg backend), which only a drawn
        # figure needs
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        FigureCanvasAgg(fig)
    return fig.canvas.get_renderer()


def titles(fig) -> list:
    """(Text, its room in pixels) of the suptitle of the figure ``fig`` and its subfigures'
    (their widths) and of each axes' centre title (the axes' width), those with text."""
    fig_width = fig.bbox.width
    out = []
    for part in (fig, *_subfigures(fig)):
        sup = getattr(part, "_suptitle", None)  # matplotlib keeps it there (no getter)
        if sup is not None and sup.get_text():
            out.append((sup, part.bbox.width))
    for ax in fig.get_axes():
        if ax.title.get_text():
            out.append((ax.title, min(ax.get_position().width * fig_width, fig_width)))
    return out


def _subfigures(fig) -> list:
    """Every subfigure of ``fig``, nested ones too."""
    out = []
    for sub in getattr(fig, "subfigs", []):
        out += [sub, *_subfigures(sub)]
    return out


def _wrap(text, room: float, renderer) -> bool:
    """Rewrap ``text`` (a matplotlib Text) to fit ``room`` pixels; True when it changed."""
    width = text.get_window_extent(renderer).width
    if width <= ROOM * room:
        return False
    words = " ".join(text.get_text().split())
    chars = max(8, int(len(words) * ROOM * room / width))
    while chars > 8:
        text.set_text(textwrap.fill(words, chars))
        if text.get_window_extent(renderer).width <= ROOM * room:
            break
        chars -= max(1, chars // 20)
    return True


def lay_out(fig) -> None:
    """Lay the figure ``fig`` out as its draw does first (its layout engine, constrained
    layout here, when it has axes and one), without drawing its artists: the axes' widths
    a title is fitted to are all :func:`fit_titles` reads. A draw with no output
    (``Figure.draw_without_rendering``) did the same layout plus a pass over every artist;
    the written PNG files are the same bytes (docs/benchmarks.md, "make report's
    floor")."""
    engine = fig.get_layout_engine()
    if fig.axes and engine is not None:
        try:
            engine.execute(fig)
        except ValueError:  # as Figure.draw: a layout that cannot be made is skipped
            pass


def fit_titles(fig, dpi: float | None = None) -> None:
    """Wrap every title of ``fig`` (at ``dpi``, default the figure's) that is wider than its
    room, laying the figure out again after each round of changes."""
    if dpi is not None:
        fig.set_dpi(dpi)
    renderer = renderer_of(fig)
    for _ in range(ROUNDS):
        lay_out(fig)  # the axes' final widths
        changed = [_wrap(text, room, renderer) for text, room in titles(fig)]
        if not any(changed):
            return


def save_figure(fig, path, dpi: float, **kwargs) -> None:
    """``fig.savefig(path, dpi=dpi, **kwargs)`` with its titles fitted first
    (:func:`fit_titles`)."""
    fit_titles(fig, dpi)
    fig.savefig(path, dpi=dpi, **kwargs)
