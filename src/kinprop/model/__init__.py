"""Model layer: Mechanism (structure), Design (numbers), Model (both plus coordinates)."""

from kinprop.constraints.coupling import N_COEF
from kinprop.model.design import GROUPS, Address, Coordinates, Design, as_coordinates, parse_address
from kinprop.model.elements import Element, Vehicle
from kinprop.model.loads import LoadCase, Loads, Mass, PointLoad
from kinprop.model.mechanism import DESIGN_FIELDS, Body, Coupling, Joint, Mechanism
from kinprop.model.model import Model

__all__ = [
    "DESIGN_FIELDS",
    "GROUPS",
    "N_COEF",
    "Address",
    "Body",
    "Coordinates",
    "Coupling",
    "Design",
    "Element",
    "Joint",
    "LoadCase",
    "Loads",
    "Mass",
    "Mechanism",
    "Model",
    "PointLoad",
    "Vehicle",
    "as_coordinates",
    "parse_address",
]
