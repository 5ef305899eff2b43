"""Exception and warning hierarchy.

Every user-facing error subclasses a matching built-in so callers can catch either.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Problem:
    """One validation problem: where it is and what was expected versus found."""

    location: str
    message: str
    file: str | None = None

    def __str__(self) -> str:
        where = f"{self.file}: " if self.file else ""
        return f"{where}{self.location}: {self.message}"


class KinpropError(Exception):
    """Base class of kinprop's errors."""


class ModelError(KinpropError, ValueError):
    """An invalid mechanism or model file; carries every problem found, not just the first."""

    def __init__(self, problems: list[Problem] | Problem | str, file: str | None = None):
        if isinstance(problems, str):
            problems = [Problem("model", problems, file)]
        elif isinstance(problems, Problem):
            problems = [problems]
        self.problems = [p if p.file or not file else Problem(p.location, p.message, file) for p in problems]
        super().__init__("\n".join(str(p) for p in self.problems))


class AddressError(KinpropError, KeyError):
    """A design-variable address or group that the model does not define."""

    def __str__(self) -> str:  # KeyError quotes its message; keep it readable
        return str(self.args[0]) if self.args else "unknown address"


class ConvergenceError(KinpropError, RuntimeError):
    """Raised only on request (``result.raise_for_status()``) when a solve did not converge."""


class UnitsWarning(UserWarning):
    """A number that is valid but implausible in the declared unit (millimetre numbers under
    ``length: m``, a tyre radius in the wrong unit): the results would be off by 1000."""


class SingularityWarning(UserWarning):
    """The free-variable Jacobian is close to singular at a solved configuration."""
