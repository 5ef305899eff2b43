"""The ``ADDRESS=VALUE`` texts of the command line and the HTTP API, parsed once.

``--set J12.s_j=-2.8,0.2,0.1``, ``--weight q=2``, ``--tolerance hardpoint:TR.i[z]=0.5``: the
same parsing and the same messages for ``kinprop`` and the workbench (:mod:`kinprop.serve`).
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from kinprop.errors import AddressError
from kinprop.model.design import parse_address


def parse_assignment(text: str, option: str = "--set") -> tuple[str, np.ndarray]:
    """``ADDRESS=v1,v2,...`` -> (address, values)."""
    if "=" not in text:
        raise AddressError(f"{option} {text!r}: expected ADDRESS=VALUE (e.g. J12.s_j=-2.8,0.2,0.1)")
    addr, _, value = text.partition("=")
    try:
        nums = np.array([float(x) for x in value.replace(";", ",").split(",") if x.strip()], dtype=float)
    except ValueError:
        raise AddressError(f"{option} {text!r}: values must be comma-separated numbers") from None
    if nums.size == 0:
        raise AddressError(f"{option} {text!r}: no value given")
    return addr.strip(), nums


def parse_weight(text: str) -> tuple[str, float]:
    addr, nums = parse_assignment(text)
    if nums.size != 1:
        raise AddressError(f"--weight {text!r}: expected one number")
    return addr, float(nums[0])


def parse_assignments(option: str, texts: Iterable[str] | None) -> dict[str, np.ndarray]:
    """``ADDRESS=VALUES`` options -> {address: values}; an address given twice is refused."""
    out: dict[str, np.ndarray] = {}
    seen: dict[tuple[str, int | None], str] = {}
    for text in texts or []:
        addr, values = parse_assignment(text, option)
        if not np.all(np.isfinite(values)):
            raise AddressError(f"{option} {text!r}: values must be finite numbers")
        key = address_key(addr)
        clash = [t for (k, i), t in seen.items() if k == key[0] and (i is None or key[1] is None or i == key[1])]
        if clash:
            raise AddressError(f"{option} {text!r}: {addr} is already given by {option} {clash[0]!r}")
        seen[key] = text
        out[addr] = values
    return out


def parse_weights(texts: Iterable[str] | None) -> dict[str, float] | None:
    """``--weight ADDRESS_OR_GROUP=W`` options: one positive number each, no address twice."""
    out = {}
    for addr, values in parse_assignments("--weight", texts).items():
        if values.size != 1 or not values[0] > 0:
            found = ", ".join(map(str, values))
            raise AddressError(f"--weight {addr}: expected one number, and weights must be positive; found {found}")
        out[addr] = float(values[0])
    return out or None


def address_key(address: str) -> tuple[str, int | None]:
    try:
        a = parse_address(address)
    except AddressError:
        return address, None
    return a.key, a.index


__all__ = ["address_key", "parse_assignment", "parse_assignments", "parse_weight", "parse_weights"]
