"""Model files: schema, validation, loading, writing."""

from kinprop.io.files import load_model, model_from_data
from kinprop.io.hardpoints import model_to_hardpoints
from kinprop.io.loader import parse_text
from kinprop.io.writer import atomic_write, dump_model, model_to_data

__all__ = [
    "atomic_write",
    "dump_model",
    "load_model",
    "model_from_data",
    "model_to_data",
    "model_to_hardpoints",
    "parse_text",
]
