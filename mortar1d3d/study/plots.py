"""The report's plots: error against time per variant, the stages, the scaling (matplotlib, optional)."""
import math

import numpy as np

from .accuracy import dm_error, u_error
from .config import INTEGRATIONS
from .timing import STAGES


#: line style per embedding of the error-time plots (legend and curves use the same)
EMBEDDING_STYLES = {"embedded": "-", "partly outside": "--"}


def readable_log_ticks(axis, matplotlib):
    """Label a log axis at 1, 2 and 5 times the powers of ten, written as plain numbers (0.5, 20):
    the default labels only the powers of ten, often one or two on a time axis."""
    axis.set_major_locator(matplotlib.ticker.LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
    axis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
    axis.set_minor_formatter(matplotlib.ticker.NullFormatter())


def _error_time_grid(plt, matplotlib, scenes, kinds, ratios, error, ylabel, floor, pareto=False):
    """One log-log panel per (kind, ratio): ``error`` of each record against its median time, a
    curve per integration and embedding (records without the error are left out); ``pareto``
    marks the Pareto-optimal points.

    The legend sits below the panels, outside every one of them, and has separate entries for
    the colours (integration) and the line styles (embedding), drawn long enough to show dashes.
    """
    colours = {"element": "tab:blue", "segment": "tab:orange", "auto": "tab:green"}
    fig, axes = plt.subplots(len(kinds), len(ratios), figsize=(4.2 * len(ratios), 3.4 * len(kinds)),
                             squeeze=False, sharey=True)
    for i, kind in enumerate(kinds):
        for j, ratio in enumerate(ratios):
            ax = axes[i, j]
            for scene in scenes:
                if scene["kind"] != kind or scene["ratio"] != ratio:
                    continue
                style = EMBEDDING_STYLES.get(scene["embedding"], ":")
                for integration in INTEGRATIONS:
                    recs = [r for r in scene["records"] if r["integration"] == integration and error(r) is not None]
                    if not recs:
                        continue
                    x = [r["time_s"] * 1e3 for r in recs]
                    y = [max(error(r), floor) for r in recs]
                    ax.loglog(x, y, style, marker="o", ms=3, color=colours[integration],
                              label=f"{integration}, {scene['embedding']}")
                    if pareto:
                        front = _pareto(x, y)
                        ax.loglog([x[k] for k in front], [y[k] for k in front], "s", ms=6, mfc="none",
                                  color=colours[integration])
            ax.set_title(f"{kind}, h_B/h_S = {ratio:g}", fontsize=9)
            readable_log_ticks(ax.xaxis, matplotlib)
            ax.grid(True, which="major", alpha=0.3)
            if i == len(kinds) - 1:
                ax.set_xlabel("median assemble_mortar time [ms]")
            if j == 0:
                ax.set_ylabel(ylabel)
    from matplotlib.lines import Line2D
    handles = [Line2D([], [], color=c, marker="o", ms=4, ls="-", label=k if k == "auto" else f"{k}-based")
               for k, c in colours.items()]
    handles += [Line2D([], [], color="k", ls=s, lw=1.2, label=e) for e, s in EMBEDDING_STYLES.items()]
    if pareto:
        handles.append(Line2D([], [], color="k", marker="s", ms=6, mfc="none", ls="none", label="Pareto-optimal"))
    fig.legend(handles=handles, loc="lower center", ncol=len(handles), fontsize=8, handlelength=3.5,
               frameon=False)
    # room in inches, whatever the number of rows: two lines of suptitle above, the legend below
    height = fig.get_figheight()
    fig.tight_layout(rect=(0, 0.35 / height, 1, 1 - 0.55 / height))
    return fig


def _scaling_panel(ax, points, values, ylabel, fitted, **style):
    """One log-log panel of the scaling plot: ``values`` against ``points`` (``style``: of the
    measured curve) and, if ``fitted``, their least-squares line in log-log."""
    ax.loglog(points, values, "o-", **style)
    if fitted:
        c = np.polyfit(np.log10(points), np.log10(values), 1)
        ax.loglog(points, 10 ** np.polyval(c, np.log10(points)), "k--", label=f"fit, slope {c[0]:.2f}")
    ax.set_xlabel("integration points")
    ax.set_ylabel(ylabel)
    ax.legend(fontsize=8)
    ax.grid(True, which="major", alpha=0.3)


def _save(plt, fig, out, name, layout=True):
    """Lay out (unless ``layout`` is False: the figure is laid out already), write ``out/name`` as
    PNG, close; returns ``name``."""
    if layout:
        fig.tight_layout()
    fig.savefig(out / name, dpi=110)
    plt.close(fig)
    return name


def write_plots(results, out):
    """Write the report's PNG plots into the directory ``out``.

    Returns
    -------
    dict
        File names by plot (``pareto``, ``monitor`` where the monitor ran, ``stages``,
        ``scaling``); empty without matplotlib.
    """
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        import matplotlib.ticker
    except ImportError:
        return {}
    files = {}
    cfg = results["config"]
    kinds, ratios = cfg["kinds"], cfg["ratios"]
    floor = 1e-17
    fig = _error_time_grid(plt, matplotlib, results["scenes"], kinds, ratios, dm_error,
                           "max(rel. Frobenius error of D, M)", floor, pareto=True)
    fig.suptitle("Error vs time per variant\n(squares: Pareto-optimal; solid: embedded, dashed: partly outside; "
                 "errors < 1e-17 drawn at 1e-17)", fontsize=9)
    files["pareto"] = _save(plt, fig, out, "pareto.png", layout=False)

    monitored = [sc for sc in results["scenes"] if sc.get("monitor")]
    if monitored:
        mkinds = [k for k in kinds if any(sc["kind"] == k for sc in monitored)]
        fig = _error_time_grid(plt, matplotlib, monitored, mkinds, ratios, u_error, "monitor displacement error",
                               floor)
        fig.suptitle("Solution error vs assembly time per variant: |u - u_ref| / |u_ref| at the monitor point\n"
                     "(solid: embedded, dashed: partly outside; errors < 1e-17 drawn at 1e-17)", fontsize=9)
        files["monitor"] = _save(plt, fig, out, "monitor.png", layout=False)

    # stage breakdown on the benchmark scene
    t = results["auto_target"]
    fig, ax = plt.subplots(figsize=(7.5, 3.6))
    bottom = np.zeros(len(INTEGRATIONS))
    for stage in STAGES:
        v = np.array([t[k]["stages_s"][stage] * 1e3 for k in INTEGRATIONS])
        ax.bar(INTEGRATIONS, v, bottom=bottom, label=stage)
        bottom += v
    ax.set_ylabel("median time [ms]")
    ax.set_title(f"Stages of assemble_mortar, fibre_cube{tuple(t['scene'])}, n_gauss = 4", fontsize=10)
    # beside the bars (inside it covered the tallest one), in the order of the stack, top first
    handles, labels = ax.get_legend_handles_labels()
    ax.legend(handles[::-1], labels[::-1], fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    files["stages"] = _save(plt, fig, out, "stages.png")

    rows = results["scaling"]["rows"]
    fig, ax = plt.subplots(1, 2 if cfg["memory"] else 1, figsize=(10 if cfg["memory"] else 5.5, 3.8), squeeze=False)
    pts = np.array([r["points"] for r in rows], dtype=float)
    tt = np.array([r["time_s"] for r in rows])
    fit = results["scaling"]["fit"]
    _scaling_panel(ax[0, 0], pts, tt, "median time [s]", fit.get("time_slope") is not None, label="measured")
    if cfg["memory"]:
        m = np.array([r["peak_bytes"] for r in rows], dtype=float) / 2 ** 20
        _scaling_panel(ax[0, 1], pts, m, "peak memory [MiB]", fit.get("memory_slope") is not None,
                       color="tab:red", label="tracemalloc peak")
    fig.suptitle("Scaling of segment-based assembly (fibre_cube(20, F, 20), n_gauss = 4)", fontsize=10)
    files["scaling"] = _save(plt, fig, out, "scaling.png")
    return files


def _pareto(x, y):
    """Indices of the points not dominated in (time, error), sorted by time."""
    order = sorted(range(len(x)), key=lambda k: (x[k], y[k]))
    front, best = [], math.inf
    for k in order:
        if y[k] < best:
            front.append(k)
            best = y[k]
    return front
