"""Exceptions raised by pacs.

Every error pacs raises is a :class:`Error`; each also subclasses the built-in exception a
Python user expects (``ValueError`` for a bad value or shape, ``TypeError`` for a wrong type),
so ``except ValueError`` keeps working. Messages name the argument (or file, line and field)
and the offending value.
"""


class Error(Exception):
    """Base class of every pacs error."""


class InputError(Error, ValueError):
    """An invalid value: wrong shape, NaN/inf, an unknown name, a model or log that is invalid."""


class ArgumentTypeError(Error, TypeError):
    """An argument of the wrong type (e.g. a string where an array of numbers is expected)."""


class NotStartedError(Error, RuntimeError):
    """The call needs another state: ``start(t, q)`` first, or a ShieldLoop owns the shield."""


class ChunkRejected(InputError):
    """The chunk could not be planned (e.g. a waypoint outside the joint limits); the robot
    keeps its verified motion."""


class OutputError(Error, OSError):
    """A file (log, report) cannot be written."""


__all__ = [
    "Error",
    "InputError",
    "ArgumentTypeError",
    "NotStartedError",
    "ChunkRejected",
    "OutputError",
]
