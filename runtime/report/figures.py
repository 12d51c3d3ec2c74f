"""Turning matplotlib figures into text an HTML page can embed, deterministically.

Figures get an Agg canvas explicitly (no pyplot, no global state, no display); SVG output has a
fixed hash salt and no date, so the same campaign gives the same page. This module must never
write files.
"""

from __future__ import annotations

import base64
import io

import matplotlib
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

SVG_SALT = "rei-report"


def new_figure(width: float, height: float) -> Figure:
    fig = Figure(figsize=(width, height), dpi=96, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def inline_svg(fig: Figure) -> str:
    """The figure as an <svg> element (XML prolog and DOCTYPE dropped) for inline embedding."""
    buffer = io.StringIO()
    with matplotlib.rc_context({"svg.hashsalt": SVG_SALT, "svg.fonttype": "none"}):
        fig.savefig(buffer, format="svg", metadata={"Date": None, "Creator": None})
    text = buffer.getvalue()
    return text[text.index("<svg"):]


def png_data_uri(fig: Figure, dpi: int = 80) -> str:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=dpi, metadata={"Software": None})
    return "data:image/png;base64," + base64.b64encode(buffer.getvalue()).decode("ascii")
