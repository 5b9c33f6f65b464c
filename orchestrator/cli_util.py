"""What the commands' ``main`` functions share: arguments parsed into an exit code instead of
``SystemExit`` (so a test or ``suscosim`` can call them), error lines starting
``suscosim: error: <command>:`` (:func:`error_line`, :func:`fail`, :class:`ArgumentParser`),
and the pace options of the commands that replay a journal (``replay``, ``scope``).
"""

from __future__ import annotations

import argparse
import signal
import sys
from collections.abc import Sequence
from typing import Any, NoReturn

ERROR_PREFIX = "suscosim: error: "


def error_line(prog: str, message: str) -> str:
    """``suscosim: error: <command>: message`` (the command left out for ``suscosim``)."""
    cmd = prog.removeprefix("suscosim").strip()
    return f"{ERROR_PREFIX}{cmd + ': ' if cmd else ''}{message}"


class ArgumentParser(argparse.ArgumentParser):
    """An ``argparse.ArgumentParser`` whose usage errors start with :data:`ERROR_PREFIX`."""

    def error(self, message: str) -> NoReturn:
        self.print_usage(sys.stderr)
        self.exit(2, error_line(self.prog, message) + "\n")


def unify_errors(ap: argparse.ArgumentParser) -> None:
    """Make a plain ``ap`` (and its subparsers) an :class:`ArgumentParser`."""
    parsers = [ap]
    while parsers:
        p = parsers.pop()
        if type(p) is argparse.ArgumentParser:  # a subclass of its own is left as it is
            p.__class__ = ArgumentParser
        for action in p._actions:
            if isinstance(action, argparse._SubParsersAction):
                parsers.extend(action.choices.values())


def parse_args(ap: argparse.ArgumentParser, argv: Sequence[str] | None) -> argparse.Namespace | int:
    """``ap``'s arguments from ``argv``, or the exit code (0 after ``--help``, 2 a usage error)."""
    unify_errors(ap)
    try:
        return ap.parse_args(list(sys.argv[1:] if argv is None else argv))
    except SystemExit as exc:
        return 0 if exc.code == 0 else 2


def num(x: float | str, spec: str = ".4g") -> str:
    """A number as ``spec``; a text (``"inf"``, a note) as it is."""
    return x if isinstance(x, str) else format(x, spec)


def _interrupt(_signum: int, _frame: object) -> None:
    raise KeyboardInterrupt


def interrupt_on_sigterm() -> Any:
    """SIGTERM raises KeyboardInterrupt from now on, as Ctrl-C; the previous handler."""
    return signal.signal(signal.SIGTERM, _interrupt)


def fail(prog: str, message: str, code: int = 2) -> int:
    """Print :func:`error_line` on stderr; return ``code`` (default 2, bad input)."""
    print(error_line(prog, message), file=sys.stderr)
    return code


class _Factor(argparse.Action):
    """Store a float option that must be > 0; else a usage error naming it (exit 2)."""

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: Any, option_string: str | None = None) -> None:
        if not values > 0:
            parser.error(f"{option_string} {values:g}: expected a factor > 0")
        setattr(namespace, self.dest, values)


def add_pace_arguments(ap: argparse.ArgumentParser, *, speed_help: str, fast_help: str) -> None:
    """``--speed X`` (a factor > 0 against the recorded time, default 1) or ``--fast``."""
    pace = ap.add_mutually_exclusive_group()
    pace.add_argument("--speed", type=float, default=1.0, metavar="X", action=_Factor,
                      help=speed_help)
    pace.add_argument("--fast", action="store_true", help=fast_help)


def pace_factor(args: argparse.Namespace) -> float | None:
    """None (as fast as possible) with ``--fast``, else ``--speed``."""
    return None if args.fast else float(args.speed)
