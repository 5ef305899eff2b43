"""Design propagation (section 5): overwrite design variables, re-assemble over a free set.

A propagation starts from the model's state exactly as it is; only the changed variables are
overwritten, and they are never free (PAPER-NOTES 7).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from kinprop.errors import AddressError, SingularityWarning
from kinprop.kinematics.assembly import Assembly
from kinprop.kinematics.layout import read, retract
from kinprop.model.design import as_coordinates, parse_address
from kinprop.model.mechanism import Mechanism
from kinprop.model.model import Model
from kinprop.propagation.conditioning import SINGULAR_RTOL, conditioning
from kinprop.solver.newton import SolveOptions, SolveResult, newton
from kinprop.spatial import Array, is_rotation


def warn_if_singular(ratio: float, rtol: float = SINGULAR_RTOL, stacklevel: int = 3) -> None:
    """Issue a :class:`SingularityWarning` when a solved configuration is near singular:
    unit-independent ``s_r / s_1`` of the free-variable Jacobian below ``rtol``
    (:mod:`kinprop.propagation.conditioning`; docs/analysis/mobility.md)."""
    if ratio < rtol:
        warnings.warn(
            f"near-singular configuration (toggle): smallest/largest singular value of the (scaled) free-variable "
            f"Jacobian = {ratio:.3g} < {rtol:g}; small design changes may move the free variables a lot or "
            "leave no assembly",
            SingularityWarning,
            stacklevel=stacklevel,
        )


@lru_cache(maxsize=64)
def assembly_for(mechanism: Mechanism) -> Assembly:
    """The (cached) Assembly of a mechanism."""
    return Assembly(mechanism)


@dataclass(frozen=True)
class Propagation:
    """Before and after of one re-assembly, with the solver's result."""

    before: Model
    after: Model
    result: SolveResult
    changes: Mapping[str, Array]
    free: tuple[str, ...]
    #: unit-independent s_r / s_1 of the free-variable Jacobian at the solution (NaN if not converged)
    singularity_ratio: float = float("nan")

    @property
    def converged(self) -> bool:
        return self.result.converged

    def changed_variables(self, atol: float = 0.0) -> list[str]:
        """Layout keys whose value differs between before and after."""
        asm = assembly_for(self.before.mechanism)
        out = []
        for v in asm.layout.variables:
            a = read(asm.layout, self.before.design, self.before.coordinates, v.key)
            b = read(asm.layout, self.after.design, self.after.coordinates, v.key)
            if np.max(np.abs(a - b)) > atol:
                out.append(v.key)
        return out


#: converged when ||Phi|| < max(tol, ROUNDOFF * eps * L^2): distance rows d.d - l^2 carry
#: round-off of about eps * L^2, which exceeds 1e-10 for metre-sized mechanisms in mm
ROUNDOFF = 16.0


def length_scale(model: Model) -> float:
    """Characteristic length L of a model: the largest body position, s' or length (>= 1)."""
    kin = assembly_for(model.mechanism).kinematics(model.design, model.coordinates)
    vals = [1.0, *(float(np.linalg.norm(r)) for r in kin.r.values())]
    for k, v in model.design.items():
        if k.endswith((".s_i", ".s_j", ".length")):
            vals.append(float(np.linalg.norm(v)))
    return max(vals)


def roundoff_floor(model: Model) -> float:
    """``ROUNDOFF * eps * L^2``: below this ||Phi|| is round-off (about 1e-13 for the paper's
    metre-scale examples, 1e-8 for a vehicle suspension in mm)."""
    return ROUNDOFF * float(np.finfo(float).eps) * length_scale(model) ** 2


def apply_changes(model: Model, changes: Mapping[str, object]) -> tuple[Model, dict[str, Array], set[str]]:
    """Overwrite design variables / coordinates by address; returns the model, the normalised
    change values and the set of changed variable keys."""
    asm = assembly_for(model.mechanism)
    design_updates: dict[str, Array] = {}
    coords = dict(model.coordinates)
    normalised: dict[str, Array] = {}
    changed: set[str] = set()
    pending: dict[str, Array] = {}
    for text, value in changes.items():
        addr = parse_address(text)
        if addr.key not in asm.layout:
            known = ", ".join(v.key for v in asm.layout.variables)
            raise AddressError(f"{text!r} is not a design variable or coordinate of this model; known: {known}")
        var = asm.layout[addr.key]
        if addr.key in pending:  # several components of one variable in the same change set
            current = pending[addr.key]
        elif var.group == "C":
            current = np.asarray(model.design[addr.key], dtype=float)
        else:
            current = read(asm.layout, model.design, model.coordinates, addr.key)
        new = np.array(current, dtype=float)
        val = np.asarray(value, dtype=float)
        if addr.index is not None:
            if addr.index >= new.size or val.size != 1:
                raise AddressError(
                    f"{text!r}: expected one number for component {addr.index} of a size-{new.size} variable"
                )
            new.flat[addr.index] = float(val.ravel()[0])
        else:
            if val.size != new.size:
                raise AddressError(f"{text!r}: expected {new.size} numbers, found {val.size}")
            new = val.reshape(new.shape)
        if not np.all(np.isfinite(new)):
            raise AddressError(f"{text!r}: value must be finite")
        if var.group == "C" and not is_rotation(new):
            raise AddressError(f"{text!r}: not a proper rotation matrix (C^T C = I, det C = +1)")
        if var.group == "l" and new.ravel()[0] <= 0:
            raise AddressError(f"{text!r}: a length must be positive")
        normalised[str(addr)] = new
        pending[addr.key] = new
        changed.add(addr.key)
        if var.group == "q":
            coords[var.joint] = new
        else:
            design_updates[addr.key] = float(new.ravel()[0]) if var.group == "l" else new
    design = model.design.replace(design_updates) if design_updates else model.design
    return model.with_state(design, as_coordinates(coords)), normalised, changed


def propagate(
    model: Model,
    changes: Mapping[str, object] | None = None,
    free: Sequence[str] = ("q",),
    *,
    tol: float = 1e-10,
    max_iter: int = 50,
    weights: Mapping[str, float] | None = None,
) -> Propagation:
    """Apply ``changes`` (address -> value) and re-assemble, moving only ``free`` variables.

    ``free`` holds groups (``q``, ``s``, ``C``, ``l``) and/or addresses (``J.s_i``, ``J.q``,
    ``J.s_i[2]``). ``weights`` maps addresses or groups to positive weights of a weighted
    minimum-norm step (a larger weight lets a variable move more).
    """
    changes = changes or {}
    start, normalised, changed = apply_changes(model, changes)
    asm = assembly_for(model.mechanism)
    layout = asm.layout
    cols = layout.columns(list(free), exclude=changed)
    w = None
    if weights:
        wfull = np.ones(layout.n)
        for sel, val in weights.items():
            if not val > 0:
                raise AddressError(f"weight for {sel!r} must be positive, found {val}")
            wfull[layout.columns([sel])] = float(val)
        w = wfull[cols]

    def evaluate(state):
        return asm.evaluate(*state)

    def step(state, dx):
        return retract(layout, state[0], state[1], dx)

    options = SolveOptions(tol, max_iter, floor=roundoff_floor(start))
    result = newton(evaluate, step, (start.design, start.coordinates), cols, layout.n, options, w)
    design, coords = result.state
    after = start.with_state(design, coords)
    ratio = float("nan")
    if result.converged and cols.size:
        ratio = conditioning(asm, result.jacobian[:, cols])
        warn_if_singular(ratio)
    return Propagation(model, after, result, normalised, tuple(free), ratio)


def assemble(model: Model, free: Sequence[str] = ("q",), *, tol: float = 1e-10, max_iter: int = 50) -> Propagation:
    """Solve for an assembled configuration from the model's estimates (no design change)."""
    return propagate(model, {}, free, tol=tol, max_iter=max_iter)
