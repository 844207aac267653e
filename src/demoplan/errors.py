"""The exceptions demoplan raises; each carries the exit code of docs/cli.md.

The library never prints or exits: the command line turns one of these into a
single line on stderr and the exit code below.
"""

from __future__ import annotations

__all__ = [
    "DemoplanError",
    "InputError",
    "LimitReachedError",
    "NoPlanError",
    "NotFittedError",
    "UsageError",
    "error_line",
]


class DemoplanError(Exception):
    """Base class of every error demoplan raises on purpose."""

    exit_code: int = 1


class InputError(DemoplanError, ValueError):
    """A file or value is not what was expected (exit code 1).

    The message names the file, the field and what was expected.
    """

    exit_code = 1

    def __init__(self, message: str, *, source: str | None = None, field: str | None = None):
        self.source = source
        self.field = field
        self.message = message
        parts = [p for p in (source, field) if p]
        prefix = ": ".join(parts)
        super().__init__(f"{prefix}: {message}" if prefix else message)


class UsageError(DemoplanError):
    """The command was called wrongly (exit code 2)."""

    exit_code = 2


class NoPlanError(DemoplanError):
    """No plan exists for the problem (exit code 3)."""

    exit_code = 3


class LimitReachedError(DemoplanError):
    """A search or time budget ran out (exit code 4)."""

    exit_code = 4


class NotFittedError(DemoplanError, AttributeError):
    """A learned attribute (ending in ``_``) was read before ``fit``."""

    exit_code = 2


def error_line(exc: DemoplanError) -> str:
    """The one line ``demoplan`` prints on stderr for ``exc`` (docs/cli.md): runs
    of whitespace as one space, control characters (an escape sequence in a
    name read from a file) written as escapes, never sent to the terminal."""
    text = " ".join(str(exc).split())
    return "demoplan: error: " + "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)
