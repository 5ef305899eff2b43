"""Reading any model file: kinprop's own (frame or hardpoint style, YAML or JSON) and other
tools' files (MJCF, Project Chrono suspensions), dispatched by extension and content."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from kinprop.errors import ModelError, Problem
from kinprop.imports import import_model
from kinprop.imports.chrono import chrono_hardpoints
from kinprop.io.hardpoints import model_from_hardpoints
from kinprop.io.loader import (
    STYLES,
    ModelFile,
    build_model,
    build_or_report,
    describe_found,
    parse_document,
    read_text,
)
from kinprop.io.scales import warn_scales
from kinprop.model import Model


def load_model(path: str | Path) -> Model:
    """Read and validate a model file (YAML or JSON); MJCF (``.xml``) and Project Chrono
    suspension files (``.json`` with a ``Template``) are imported (:mod:`kinprop.imports`)."""
    path = Path(path)
    file = str(path)
    if path.suffix.lower() in (".xml", ".mjcf"):
        return import_model(path)[0]
    data, dups = parse_document(read_text(path), file)
    if file.endswith(".json") and isinstance(data, dict) and "Template" in data and "kinprop" not in data:
        model = model_from_hardpoints(chrono_hardpoints(data, file)[0], file)
        warn_scales(model, file, stacklevel=2)  # implausible sizes for the declared unit (io/scales.py)
        return model
    if not dups:
        model = model_from_data(data, file)
        warn_scales(model, file, stacklevel=2)
        return model
    try:
        model_from_data(data, file)
    except ModelError as exc:  # the last of each duplicate was kept: report the rest too
        raise ModelError(dups + [p for p in exc.problems if p.location not in {d.location for d in dups}]) from None
    raise ModelError(dups)


def model_from_data(data: Any, file: str = "<data>") -> Model:
    """Validate parsed file data and build a Model; raise ModelError with every problem."""
    if not isinstance(data, dict):
        raise ModelError([Problem("model", f"expected a mapping at the top level, found {type(data).__name__}", file)])
    style = data.get("style", "frames")
    if not isinstance(style, str) or style not in STYLES:
        raise ModelError(
            [Problem("style", f"expected one of {', '.join(STYLES)}, found {describe_found(style)}", file)]
        )
    if style == "hardpoints":
        return model_from_hardpoints(data, file)
    return build_or_report(data, ModelFile, build_model, file)
