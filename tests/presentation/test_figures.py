"""figures.py: every plot of the pages is laid out once and drawn once (issue 26), and the
settled layout still makes room for its text, the same figure giving the same bytes."""

from __future__ import annotations

from collections.abc import Callable

import pytest
from matplotlib.figure import Figure

from rei.runtime.presentation.figures import (
    TEXT_PT,
    inline_svg,
    label_axes,
    new_figure,
    png_data_uri,
)

LONG_TASK = "#12 deliver_the_parcel_to_the_kitchen_table"


def _plot() -> Figure:
    """A run-page-like plot: long tick labels on the left, a title, a legend below."""
    fig = new_figure(7.0, 3.2)
    ax = fig.add_subplot()
    ax.plot([0, 1, 2], [0, 2, 1], label="driven (ground truth)")
    ax.axhline(1.5, linestyle="--", label="speed limit (1.5 m/s)")
    ax.set_yticks([0, 1, 2], [LONG_TASK, "#2 go", "#3 come_back"])
    label_axes(ax, "simulation time [s]", "tasks", "Speed over time")
    fig.legend(loc="outside lower center", ncols=2, fontsize=TEXT_PT, frameon=False)
    return fig


@pytest.mark.parametrize("image", [inline_svg, png_data_uri], ids=["svg", "png"])
def test_each_image_draws_its_figure_once(image: Callable[[Figure], str]) -> None:
    # With the layout engine left on the figure, savefig draws twice (a dry run for the
    # layout, then the output) and lays out on both: the run page's largest cost.
    fig = _plot()
    draws: list[object] = []
    fig.canvas.mpl_connect("draw_event", draws.append)
    image(fig)
    assert len(draws) == 1


def test_the_settled_layout_keeps_every_text_inside_the_figure() -> None:
    fig = _plot()
    inline_svg(fig)
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    (ax,) = fig.axes
    whole = fig.bbox
    # the long task name needs more than the default 0.875 in left margin: only a layout
    # that measured it keeps it on the figure
    label = ax.get_tightbbox(renderer)
    assert label is not None
    assert whole.x0 <= label.x0 and label.x1 <= whole.x1
    assert whole.y0 <= label.y0 and label.y1 <= whole.y1
    (legend,) = fig.legends
    box = legend.get_window_extent(renderer)
    assert whole.y0 <= box.y0 and box.y1 <= ax.get_position().y0 * whole.height


def test_the_same_figure_gives_the_same_bytes() -> None:
    assert inline_svg(_plot()) == inline_svg(_plot())
    assert png_data_uri(_plot()) == png_data_uri(_plot())
