"""3D stick figures of mechanisms: PNG (matplotlib) and interactive HTML (plotly).

``save_plot(path, model, before=other)`` draws ``model`` solid and ``before`` faded under it,
like the paper's Figs. 5 and 6. Models are drawn at their coordinates as given (not
re-assembled). matplotlib and plotly are imported only when a plot is drawn.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from kinprop.io.writer import atomic_write
from kinprop.model import Model
from kinprop.plot.forces import ForceArrow
from kinprop.plot.interactive import render_html
from kinprop.plot.scene import Scene, build_scene
from kinprop.plot.static import render_png
from kinprop.plot.style import Layer

FORMATS = (".png", ".html")


def layers(
    model: Model, before: Model | None = None, label: str = "after", before_label: str = "before"
) -> list[Layer]:
    """The states to draw: ``before`` faded (when given), then ``model``."""
    out = [Layer(build_scene(before), before_label, faded=True)] if before is not None else []
    return [*out, Layer(build_scene(model), label)]


def render(
    path: str | Path,
    model: Model,
    before: Model | None = None,
    *,
    label: str = "after",
    before_label: str = "before",
    title: str | None = None,
    view: tuple[float, float] = (20.0, -60.0),
    arrows: Sequence[ForceArrow] = (),
    force_unit: str = "",
) -> bytes | str:
    """The figure for ``path``'s format: PNG bytes or an HTML page; ``arrows``: forces drawn on
    ``model`` (:func:`kinprop.plot.forces.force_arrows`)."""
    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        found = suffix or "no suffix"
        raise ValueError(f"plot file {str(path)!r}: expected a name ending in .png or .html, found {found!r}")
    ls = layers(model, before, label, before_label)
    if suffix == ".png":
        return render_png(ls, title or "", view, arrows=arrows, force_unit=force_unit)
    return render_html(ls, title or "", arrows, force_unit)


def save_plot(
    path: str | Path,
    model: Model,
    before: Model | None = None,
    *,
    label: str = "after",
    before_label: str = "before",
    title: str | None = None,
    view: tuple[float, float] = (20.0, -60.0),
    arrows: Sequence[ForceArrow] = (),
    force_unit: str = "",
) -> Path:
    """Draw ``model`` (and ``before`` faded) to ``path`` (.png or .html), written atomically;
    ``arrows``: forces drawn on ``model``."""
    data = render(path, model, before, label=label, before_label=before_label, title=title, view=view,
                  arrows=arrows, force_unit=force_unit)  # fmt: skip
    atomic_write(path, data)
    return Path(path)


__all__ = ["FORMATS", "Layer", "Scene", "build_scene", "layers", "render", "save_plot"]
