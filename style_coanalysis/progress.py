"""Progress reports and cancellation shared by every long stage.

Long stages call `progress.step(stage, done, total)` between units of work; the Blender operator
passes a callback that updates its progress bar and a `cancel` that reads the Esc flag, so a run
can stop between units and leave nothing half-written.
"""
from __future__ import annotations

from typing import Callable


class Cancelled(Exception):
    """The person asked to stop; raised between units of work."""


class Progress:
    """`callback(stage, done, total)` is optional; `cancel()` returning True stops the run."""

    def __init__(self, callback: Callable[[str, int, int], None] | None = None,
                 cancel: Callable[[], bool] | None = None):
        self.callback = callback
        self.cancel = cancel

    def step(self, stage: str, done: int, total: int) -> None:
        if self.callback is not None:
            self.callback(stage, int(done), int(total))
        if self.cancel is not None and self.cancel():
            raise Cancelled(f"cancelled during '{stage}'")

    @classmethod
    def wrap(cls, progress=None, cancel=None) -> "Progress":
        """Accept a Progress, a bare callback, or nothing."""
        if isinstance(progress, Progress):
            return progress if cancel is None else cls(progress.callback, cancel)
        return cls(progress, cancel)
