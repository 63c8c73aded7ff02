"""The example and report plots (issue 21): no legend or inset covers a data point or the target
line, legend entries draw the line styles of their curves, log axes carry readable labels. The
figures are built from small synthetic data (their functions take the numbers, not a run)."""
import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402

from mortar1d3d.study.plots import EMBEDDING_STYLES, _error_time_grid  # noqa: E402

from example_modules import load_example  # noqa: E402


def _example(name):
    return load_example(name, f"{name}_plot_example")


def _data_points(ax):
    """Display coordinates of every data point of the curves of ``ax`` (not axhline & co.)."""
    pts = [np.column_stack(line.get_data()) for line in ax.get_lines() if line.get_transform() == ax.transData]
    pts = [p for p in pts if len(p)]
    return ax.transData.transform(np.vstack(pts).astype(float)) if pts else np.zeros((0, 2))


def _covered(fig):
    """(axes title, what) of every data point that a legend or an inset of ``fig`` covers."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    boxes = [("figure legend", lg.get_window_extent(renderer)) for lg in fig.legends]
    for ax in fig.axes:
        if ax.get_legend() is not None:
            boxes.append((f"legend of {ax.get_title()!r}", ax.get_legend().get_window_extent(renderer)))
        for child in ax.child_axes:
            boxes.append((f"inset of {ax.get_title()!r}", child.get_tightbbox(renderer)))
    hits = []
    for ax in fig.axes:
        if not ax.axison or ax in {c for a in fig.axes for c in a.child_axes}:
            continue
        pts = _data_points(ax)
        for what, box in boxes:
            if what.endswith(f"{ax.get_title()!r}") or what == "figure legend":
                inside = ((pts[:, 0] > box.x0) & (pts[:, 0] < box.x1) & (pts[:, 1] > box.y0) & (pts[:, 1] < box.y1))
                if inside.any():
                    hits.append((ax.get_title(), what))
    return hits


def _tick_labels(axis, minor=False):
    """The non-empty tick labels of ``axis`` inside its view (major, or minor ones)."""
    axis.axes.figure.canvas.draw()
    lo, hi = sorted(axis.get_view_interval())
    return [t.get_text() for t in axis.get_ticklabels(minor=minor) if t.get_text() and lo <= t.get_position()[
        0 if axis.axis_name == "x" else 1] <= hi]


def test_overlap_check_sees_a_covering_legend():
    """The helper itself: a legend placed over the data is found."""
    fig, ax = plt.subplots()
    ax.plot(np.linspace(0, 1, 50), np.full(50, 0.5), label="data")
    ax.legend(loc="center")
    assert _covered(fig) == [("", "legend of ''")]
    plt.close(fig)


def _scenes():
    rng = np.random.default_rng(0)
    scenes = []
    for embedding in ("embedded", "partly outside"):
        records = [{"integration": i, "time_s": t * 1e-3, "err": e}
                   for i in ("element", "segment", "auto")
                   for t, e in zip(np.sort(rng.uniform(1, 20, 6)), np.sort(10.0 ** rng.uniform(-16, 0, 6))[::-1])]
        scenes.append({"kind": "straight fibres, hex8", "ratio": 1.0, "embedding": embedding, "records": records})
    return scenes


def test_pareto_legend_is_outside_and_draws_the_curves_line_styles():
    fig = _error_time_grid(plt, matplotlib, _scenes(), ["straight fibres, hex8"], [1.0], lambda r: r["err"],
                           "error", 1e-17, pareto=True)
    assert _covered(fig) == []
    (legend,) = fig.legends
    styles = {t.get_text(): h.get_linestyle() for t, h in zip(legend.get_texts(), legend.legend_handles)}
    assert styles["embedded"] == "-" and styles["partly outside"] == "--"
    ax = fig.axes[0]
    dashed = [line for line in ax.get_lines() if line.get_linestyle() == "--"]
    assert len(dashed) == 3 and all("partly outside" in line.get_label() for line in dashed)
    assert EMBEDDING_STYLES == {"embedded": "-", "partly outside": "--"}
    labels = _tick_labels(ax.xaxis)
    assert len(labels) >= 3 and all("$" not in t for t in labels)      # 1, 2, 5, 10, 20: plain numbers
    assert _tick_labels(ax.xaxis, minor=True) == []
    plt.close(fig)


def test_convergence_figure_keeps_legends_off_the_curves():
    conv = _example("convergence")
    levels = [4, 8, 16, 32]
    variants = ("mortar segment", "mortar element", "gauss-point penalty")
    ratios = (0.25, 0.5, 1.0, 2.0)
    h = 1.0 / np.array(levels[:-1])
    errors = {(v, r): [0.4 * (h / h[0]) ** (1 + k / 3) * (1 + r / 10), 0.35 * (h / h[0]) ** 1.5]
              for k, v in enumerate(variants) for r in ratios}
    s = np.linspace(0, 0.8, 33)
    line_load = {(v, r, 16): (s, np.column_stack([0 * s, 0 * s, 2e-3 * np.sin(40 * s) * np.exp(-4 * s)]))
                 for v in variants for r in ratios}
    fig = conv.figure({"levels": levels, "errors": errors, "line_load": line_load}, 16)
    assert _covered(fig) == []
    error_axes = fig.axes[:2]
    for ax in error_axes:
        assert _tick_labels(ax.xaxis) == ["1/4", "1/8", "1/16"] and _tick_labels(ax.xaxis, minor=True) == []
        assert all("$" not in t for t in _tick_labels(ax.yaxis)) and len(_tick_labels(ax.yaxis)) >= 3
    plt.close(fig)


def test_composite_plate_figure_keeps_legends_and_insets_off_the_curves_and_shows_the_target():
    cp = _example("composite_plate")
    x = np.linspace(0, 1, 33)
    curves = {}
    for level in (1, 2, 3):
        a = 1.0 / level ** 2
        curves["tension", level] = {"x": x, "u_homogenised": 5e-4 * np.sin(1.5 * x),
                                    "u_explicit": 5e-4 * np.sin(1.5 * x) * (1 + 4e-3 * a * np.sqrt(x)),
                                    "tip": 5e-3 * a, "field": 5e-3 * a}
        curves["bending", level] = {"x": x, "u_homogenised": 9e-3 * x ** 2,
                                    "u_explicit": 9e-3 * x ** 2 - 7e-5 * a * x ** 3 + 1e-5 * a * np.sin(6 * x),
                                    "tip": 7e-3 * a, "field": 7e-3 * a}
    fig = cp.figure(curves, [1, 2, 3])
    assert _covered(fig) == []
    density = fig.axes[2]
    low, high = density.get_ylim()
    assert low < 2.0 < high                                      # the 2 % target line is in view
    assert all("$" not in t for t in _tick_labels(density.yaxis))
    plt.close(fig)
