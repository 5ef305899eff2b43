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

    ``swap_axes`` puts ``x`` on the vertical axis (the usual layout of suspension curves,
    wheel travel up). ``units`` maps column (or short metric) names to unit labels. When
    ``path`` is given the figure is saved there (format from the suffix).
    """
    import matplotlib

    if path is not None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    units = dict(units or {})
    figsize = figure_kw.pop("figsize", (4.2 * len(ys), 4.2))
    fig, axes = plt.subplots(1, len(ys), figsize=figsize, squeeze=False, **figure_kw)
    styles = ["-", "--", "-.", ":"]
    for ax, y in zip(axes[0], ys, strict=True):
        for k, (label, frame) in enumerate(curves.items()):
            ok = frame[frame["status"] == "converged"] if "status" in frame else frame
            xs, vs = ok[x].to_numpy(), ok[y].to_numpy()
            ax.plot(*((vs, xs) if swap_axes else (xs, vs)), styles[k % 4], label=label)
        xl, yl = _label(x, units), _label(y, units)
        ax.set_xlabel(yl if swap_axes else xl)
        ax.set_ylabel(xl if swap_axes else yl)
        ax.axhline(0.0, color="0.8", lw=0.8, zorder=0)
        ax.axvline(0.0, color="0.8", lw=0.8, zorder=0)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize="small")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    if path is not None:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=120)
    return fig


__all__ = ["plot_curves"]
