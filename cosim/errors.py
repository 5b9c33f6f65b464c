"""Errors every suscosim component raises for bad input; the CLI turns a
:class:`SuscosimError` into a one-line message and its ``exit_code``."""

from __future__ import annotations


class SuscosimError(Exception):
    """An error that reaches the user as a clear message, not a traceback."""

    exit_code = 1


class ScenarioError(SuscosimError, ValueError):
    """A scenario (or configuration) key has a bad value: ``key`` dotted, ``value`` (None:
    missing), ``expected`` in words."""

    exit_code = 2

    def __init__(self, key: str, value: object, expected: str) -> None:
        self.key, self.value, self.expected = key, value, expected
        super().__init__(f"scenario key '{key}': got {value!r}, expected {expected}")

    def with_hint(self, hint: str) -> ScenarioError:
        """A copy of this error with ``hint`` appended to its message."""
        new = type(self).__new__(type(self))
        new.__dict__.update(self.__dict__)
        new.args = (f"{self.args[0]}; {hint}",)
        return new


class UnknownKeyError(ScenarioError):
    """A key a table does not take (a typo, or a key left over from another model when
    ``--set`` changed one key of a table); ``accepted``: the keys it takes."""

    def __init__(self, key: str, value: object, accepted: list[str], hint: str = "") -> None:
        self.accepted = list(accepted)
        super().__init__(key, value, f"one of the keys {self.accepted}{hint}")


class InputFileError(SuscosimError, ValueError):
    """A user's file is malformed: the message names the file, the line (if known), the fault."""

    exit_code = 2

    def __init__(self, path: str, problem: str, line: int | None = None) -> None:
        self.path, self.problem, self.line = path, problem, line
        where = f"{path}:{line}" if line is not None else path
        super().__init__(f"{where}: {problem}")


class WireError(SuscosimError):
    """A bus message that does not decode or fit the schema (counted, logged, not fatal)."""


class RunError(SuscosimError):
    """A run that had to stop: dead node, stall, abort. The message names the node."""


class InputLate(RunError):
    """A node's input did not come within the stall timeout; ``late``: the nodes to blame."""

    def __init__(self, message: str, late: list[str]) -> None:
        super().__init__(message)
        self.late = list(late)
