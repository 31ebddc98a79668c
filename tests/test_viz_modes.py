"""Mode-shape figures say what they show: equilibrium, the torque holding it, and the key parameters (issue 20)."""

from __future__ import annotations

import matplotlib.pyplot as plt

import pendulab as pl
from pendulab.analysis.equilibria import equilibrium
from pendulab.viz.modes import plot_mode_shapes, save_mode_figures


def test_mode_shape_title_names_torque_actuation_and_parameters():
    model = pl.elastic(k1=800.0, k2=800.0, b1=0.1)
    eq = equilibrium(model, "down-down", [2.0, 0.0])
    fig = plot_mode_shapes(model, eq)
    title = fig._suptitle.get_text()
    plt.close(fig)
    assert "down-down" in title and "tau1 = 2" in title and "pendubot" in title
    assert "k1 = 800" in title and "b1 = 0.1" in title and "m1 = 1" in title and "c1" not in title  # zero dampers left out
    # The drawn equilibrium is the one held by the torque: the shoulder torque swings link 1 away from the vertical.
    assert abs(eq.x[0]) > 0.05


def test_mode_shape_title_without_torque_and_labels_inside_the_figure(tmp_path):
    model = pl.rigid()
    fig = plot_mode_shapes(model, "up-up")
    assert "no torque" in fig._suptitle.get_text() and "L1 = 1" in fig._suptitle.get_text()
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    box = fig.bbox
    for ax in fig.axes:
        for label in (ax.xaxis.label, ax.yaxis.label, ax.title):
            extent = label.get_window_extent(renderer)
            # Constrained layout keeps every label inside the figure (the x labels were clipped before).
            assert extent.y0 >= box.y0 - 1 and extent.y1 <= box.y1 + 1 and extent.x0 >= box.x0 - 1
    plt.close(fig)
    written = save_mode_figures(model, tmp_path, ["down-down"])
    assert [p.name for p in written] == ["modes_rigid_down-down.png"] and written[0].stat().st_size > 10_000
