"""Importers: other tools' mechanism files as kinprop models (MJCF, Project Chrono suspensions)."""

from __future__ import annotations

from pathlib import Path

from kinprop.imports.chrono import read_chrono
from kinprop.imports.mjcf import document_to_model, read_mjcf
from kinprop.io.scales import warn_scales
from kinprop.model import Model


def import_model(
    path: str | Path, keyframe: str | None = None, tire_radius: float | None = None
) -> tuple[Model, list[str]]:
    """A model from an MJCF (``.xml``) or Chrono suspension (``.json``) file, with the importer's
    notes; a size implausible in the model's unit (a tyre radius in mm for a metre model) is a
    :class:`~kinprop.errors.UnitsWarning`."""
    path = Path(path)
    if path.suffix.lower() == ".json":
        model, notes = read_chrono(path, tire_radius)
    else:
        doc = read_mjcf(path)
        model, notes = document_to_model(doc, keyframe), doc.notes
    warn_scales(model, path, stacklevel=2)
    return model, notes


__all__ = ["import_model"]
