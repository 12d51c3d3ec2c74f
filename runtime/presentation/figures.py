"""Turning matplotlib figures into text an HTML page can embed, deterministically.

Figures get an Agg canvas explicitly (no pyplot, no global state, no display); SVG output has a
fixed hash salt and no date, so the same campaign gives the same page. This module must never
write files.
"""

from __future__ import annotations

import base64
import io
from typing import TYPE_CHECKING

import matplotlib
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

if TYPE_CHECKING:
    from matplotlib.axes import Axes

SVG_SALT = "rei-report"
TEXT_PT = 9.0
"""Ticks, labels, legends and annotations: 12 px at the plots' drawn size, which the pages
only ever enlarge (at least 11 px on screen, issue 27)."""
TITLE_PT = 11.0
PLOT_WIDTH = 7.0
"""inches (672 px at 96 dpi): fits the text column of an 800 px wide window unscaled."""


def new_figure(width: float, height: float) -> Figure:
    fig = Figure(figsize=(width, height), dpi=96, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def label_axes(ax: Axes, x: str | None = None, y: str | None = None,
               title: str | None = None, title_pad: float | None = None) -> None:
    """A plot's axis labels, tick labels and title at the pages' sizes (TEXT_PT, TITLE_PT):
    every plot of the campaign and run pages labels its axes this one way."""
    if x is not None:
        ax.set_xlabel(x, fontsize=TEXT_PT)
    if y is not None:
        ax.set_ylabel(y, fontsize=TEXT_PT)
    ax.tick_params(labelsize=TEXT_PT)
    if title is not None:
        ax.set_title(title, fontsize=TITLE_PT, pad=title_pad)


def settle_layout(fig: Figure) -> None:
    """Run the figure's constrained layout once, then fix its positions and drop the engine.

    With a layout engine set, ``savefig`` draws the figure twice (a dry run, so that the
    layout sees the text, then the real one) and the engine lays it out on both. Laying out
    once (text measured by the Agg canvas) and printing once keeps the engine's margins at
    ~15 % less CPU per run page (issue 26, bench/RESULTS.md)."""
    engine = fig.get_layout_engine()
    if engine is not None:
        engine.execute(fig)
        fig.set_layout_engine(None)


def inline_svg(fig: Figure) -> str:
    """The figure as an <svg> element (XML prolog and DOCTYPE dropped) for inline embedding."""
    settle_layout(fig)
    buffer = io.StringIO()
    with matplotlib.rc_context({"svg.hashsalt": SVG_SALT, "svg.fonttype": "none"}):
        fig.savefig(buffer, format="svg", metadata={"Date": None, "Creator": None})
    text = buffer.getvalue()
    return text[text.index("<svg"):]


def png_data_uri(fig: Figure, dpi: int = 96) -> str:
    """PNG at 96 dpi: 9 pt text is 12 px in the image, which pages never shrink below
    11 px."""
    settle_layout(fig)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=dpi, metadata={"Software": None})
    return "data:image/png;base64," + base64.b64encode(buffer.getvalue()).decode("ascii")
