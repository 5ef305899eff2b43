"""Units at the user boundary (docs/units.md): the one public door for unit conversion.

**One rule**: every number a user gives or reads is in the model's declared units — lengths in
``units.length``, angles in ``units.angle`` (``deg`` or ``rad``). That covers ``--set``,
``--drive``, ``--vary``, ``--tolerance`` sigmas, sensitivity rows and columns, targets, the
Python API (``units="model"``, the default) and every printed, CSV, JSON and Parquet value.
Inside, the solver works in *solver units*: the model's length unit and radians.

The conversions are implemented once, in the lowest layer that knows the quantity:
:mod:`kinprop.propagation.units` (joint coordinates and design variables, so that
:class:`kinprop.Propagation` can report model units) and :mod:`kinprop.analysis.units` (suspension
metrics, computed in degrees). This module re-exports them; nothing else converts.
"""

from __future__ import annotations

from kinprop.analysis.units import derivative_scale, unit_of
from kinprop.propagation.units import (
    angle_indices,
    changes_to_internal,
    changes_to_model_units,
    from_solver_units,
    to_solver_units,
)

__all__ = [
    "angle_indices",
    "changes_to_internal",
    "changes_to_model_units",
    "derivative_scale",
    "from_solver_units",
    "to_solver_units",
    "unit_of",
]
