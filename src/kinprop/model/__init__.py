"""Model layer: Mechanism (structure), Design (numbers), Model (both plus coordinates)."""

from kinprop.model.design import GROUPS, Address, Coordinates, Design, as_coordinates, parse_address
from kinprop.model.mechanism import DESIGN_FIELDS, Body, Joint, Mechanism
from kinprop.model.model import Model

__all__ = [
    "DESIGN_FIELDS",
    "GROUPS",
    "Address",
    "Body",
    "Coordinates",
    "Design",
    "Joint",
    "Mechanism",
    "Model",
    "as_coordinates",
    "parse_address",
]
