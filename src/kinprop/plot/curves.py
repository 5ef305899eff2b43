"""Curves versus wheel travel (or any swept output), several designs on one figure.

Input: one DataFrame per design (label -> frame), e.g. ``kinprop.analysis.sweep.sweep(...).frame``,
with the x column and the y columns present. Failed steps (``status`` other than
``converged``) are left out of the lines.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

#: the most panels side by side; more outputs start another row
GRID_COLUMNS = 3


def _label(name: str, units: Mapping[str, str]) -> str:
    short = name.split(".")[-1] if name.startswith("metric:") else name
    unit = units.get(name) or units.get(short)
    return f"{short.replace('_', ' ')} [{unit}]" if unit else short.replace("_", " ")


def plot_curves(
    curves: Mapping[str, pd.DataFrame],
    x: str,
    ys: Sequence[str],
    *,
    units: Mapping[str, str] | None = None,
    title: str | None = None,
    swap_axes: bool = False,
    path: str | Path | None = None,
    **figure_kw: Any,
) -> Figure:
    """One subplot per ``ys`` column, one line per design in ``curves``, against column ``x``.

    Panels fill a grid at most :data:`GRID_COLUMNS` wide (six outputs: two rows of three, not
    one strip). ``swap_axes`` puts ``x`` on the vertical axis (the usual layout of suspension
    curves, wheel travel up). ``units`` maps column (or short metric) names to unit labels. The
    axes fit the data; a zero line is drawn where zero is inside them (never forced in). When
    ``path`` is given the figure is saved there (format from the suffix). The figure is built
    without pyplot (no backend is switched, nothing is left open): a notebook shows it.
    """
    from matplotlib.figure import Figure

    units = dict(units or {})
    ncols = min(GRID_COLUMNS, max(1, len(ys)))
    nrows = -(-len(ys) // ncols)
    figsize = figure_kw.pop("figsize", (4.2 * ncols, 4.0 * nrows))
    fig = Figure(figsize=figsize, **figure_kw)
    axes = fig.subplots(nrows, ncols, squeeze=False).ravel()
    styles = ["-", "--", "-.", ":"]
    for ax, y in zip(axes, ys, strict=False):
        for k, (label, frame) in enumerate(curves.items()):
            ok = frame[frame["status"] == "converged"] if "status" in frame else frame
            xs, vs = ok[x].to_numpy(), ok[y].to_numpy()
            ax.plot(*((vs, xs) if swap_axes else (xs, vs)), styles[k % 4], label=label)
        xl, yl = _label(x, units), _label(y, units)
        ax.set_xlabel(yl if swap_axes else xl)
        ax.set_ylabel(xl if swap_axes else yl)
        (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
        if y0 < 0.0 < y1:
            ax.axhline(0.0, color="0.8", lw=0.8, zorder=0)
        if x0 < 0.0 < x1:
            ax.axvline(0.0, color="0.8", lw=0.8, zorder=0)
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize="small")
    for ax in axes[len(ys) :]:
        ax.set_visible(False)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    if path is not None:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=120)
    return fig


__all__ = ["GRID_COLUMNS", "plot_curves"]
