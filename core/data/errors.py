"""The errors a user reads. The CLI prints ``str(error)`` on one line and exits 2."""

from __future__ import annotations


class RemapError(Exception):
    """Base class: everything the tool reports to the user instead of a traceback. Keeps its parts:
    ``message`` (what happened) and ``where`` (what it happened to: a file and field, a renderer),
    shown as "where: message"."""

    def __init__(self, message: str, *, where: str | None = None):
        self.message = message
        self.where = where
        super().__init__(f"{where}: {message}" if where else message)


class ConfigError(RemapError):
    """Bad input: a file, a field or a parameter. The message names where and how to fix it."""

    def __init__(self, message: str, *, file: str | None = None, field: str | None = None):
        self.file = file
        self.field = field
        super().__init__(message, where=": ".join(part for part in (file, field) if part) or None)


class AdapterUnavailableError(RemapError):
    """An adapter is known but cannot run here (a missing package, a broken install)."""


class RenderError(RemapError):
    """A renderer failed to produce an image, or produced an invalid one."""


class RenderTimeoutError(RenderError):
    """A render that did not finish within its time limit, ``seconds``, and was stopped: a fact
    `remap check` diagnoses (a renderer that does not honour its sample count renders until halted).
    ``seconds`` has a default so that it unpickles (pickle rebuilds it from its message; its attributes
    come back after), as it crosses a process pool."""

    def __init__(self, message: str, *, seconds: float = 0.0, where: str | None = None):
        self.seconds = seconds
        super().__init__(message, where=where)


class OptimisationError(RemapError):
    """The fit could not run (for example, residuals not finite at the start)."""
