"""A workbench session: the current model, its undo/redo stacks and the last change.

Sessions live in memory only (one per browser tab or script, keyed by the
``X-Kinprop-Session`` header); every one starts from the model the server loaded.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field

from kinprop.model import Model
from kinprop.propagation import Propagation

#: most undo steps kept per session
HISTORY = 200


@dataclass
class Session:
    """The current model, undo/redo stacks of models, and the last applied propagation."""

    start: Model
    model: Model
    undo_stack: list[Model] = field(default_factory=list)
    redo_stack: list[Model] = field(default_factory=list)
    #: the last applied propagation (before/after shown on the page); None after undo/redo
    last: Propagation | None = None
    #: the last propagation asked for, applied or not (the downloads' results)
    result: Propagation | None = None
    result_json: dict | None = None
    warnings: list[str] = field(default_factory=list)
    #: the key of a single-coordinate change (a slider), so a drag is one undo step
    _coalesce: str | None = None
    #: the status line of each model in the history: the change that produced it (by ``id``)
    notes: dict[int, str] = field(default_factory=dict)
    #: the last history action (``undo``, ``redo``, ``reset``) since the last applied change
    action: str = ""
    lock: threading.Lock = field(default_factory=threading.Lock)

    def apply(self, prop: Propagation, note: str = "") -> None:
        """Make ``prop.after`` the current model (one undo step; repeated moves of one slider
        coordinate coalesce into one step); ``note`` is its status line."""
        keys = list(prop.changes)
        key = keys[0] if len(keys) == 1 and keys[0].split("[")[0].endswith(".q") else None
        if not (key is not None and key == self._coalesce and self.undo_stack):
            self.undo_stack.append(self.model)
            del self.undo_stack[:-HISTORY]
        self._coalesce = key
        self.redo_stack.clear()
        self.model = prop.after
        self.last = prop
        self.action = ""
        alive = {id(m) for m in (*self.undo_stack, self.start)}
        self.notes = {k: v for k, v in self.notes.items() if k in alive}
        self.notes[id(self.model)] = note

    def status_line(self) -> str:
        """What the current model is: the change that made it (after an undo/redo, said so)."""
        note = self.notes.get(id(self.model), "the loaded model")
        return f"{self.action}: {note}" if self.action else note

    def undo(self) -> bool:
        if not self.undo_stack:
            return False
        self.redo_stack.append(self.model)
        self.model = self.undo_stack.pop()
        self.last, self._coalesce, self.action = None, None, "undo"
        return True

    def redo(self) -> bool:
        if not self.redo_stack:
            return False
        self.undo_stack.append(self.model)
        self.model = self.redo_stack.pop()
        self.last, self._coalesce, self.action = None, None, "redo"
        return True

    def reset(self) -> None:
        """Back to the loaded model (itself one undo step)."""
        if self.model is not self.start:
            self.undo_stack.append(self.model)
            self.redo_stack.clear()
            self.model = self.start
        self.last, self._coalesce, self.action = None, None, "reset"


class Sessions:
    """Sessions by id, created on first use from the loaded model."""

    def __init__(self, start: Model, limit: int = 64):
        self.start = start
        self.limit = limit
        self._by_id: dict[str, Session] = {}
        self._lock = threading.Lock()

    def get(self, sid: str) -> Session:
        with self._lock:
            s = self._by_id.get(sid)
            if s is None:
                if len(self._by_id) >= self.limit:  # forget the oldest
                    self._by_id.pop(next(iter(self._by_id)))
                s = self._by_id[sid] = Session(self.start, self.start)
            return s
