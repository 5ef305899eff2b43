"""Importers: other tools' mechanism files as kinprop models (MJCF, Project Chrono suspensions)."""

from __future__ import annotations

from pathlib import Path

from kinprop.imports.chrono import read_chrono
from kinprop.imports.mjcf import document_to_model, read_mjcf
from kinprop.model import Model


def import_model(
    path: str | Path, keyframe: str | None = None, tire_radius: float | None = None
) -> tuple[Model, list[str]]:
    """A model from an MJCF (``.xml``) or Chrono suspension (``.json``) file, with the importer's notes."""
    path = Path(path)
    if path.suffix.lower() == ".json":
        return read_chrono(path, tire_radius)
    doc = read_mjcf(path)
    return document_to_model(doc, keyframe), doc.notes


__all__ = ["import_model"]
