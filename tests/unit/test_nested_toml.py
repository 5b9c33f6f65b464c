"""#46 item 6: a TOML file nested past any real one (a RecursionError in the parser or in a
reader walking it) and random bytes are the file's named error with exit 2, for every kind of
TOML file the CLI takes: scenario, part, corner, sweep, duty."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from cosim.errors import InputFileError
from cosim.safe_open import MAX_TOML_DEPTH, parse_user_toml
from tests.conftest import suscosim

DEEP = 5000  # past Python's recursion limit


def _nested(prefix: str, depth: int = DEEP) -> str:
    return prefix + "[" * depth + "]" * depth + "\n"


COMMANDS = {  # kind: (file text before the nested value, command before the file)
    "scenario": ("[run]\nt_end = ", ("check",)),
    "part": ("x = ", ("part", "check")),
    "corner": ("x = ", ("corner", "check")),
    "sweep": ("[sweep]\nx = ", ("sweep", "--list")),
    "duty": ("[duty]\nx = ", ("duty",)),
}


@pytest.mark.parametrize("kind", sorted(COMMANDS))
def test_nested_and_random_toml_is_exit_2_naming_the_file(tmp_path: Path, kind: str) -> None:
    head, command = COMMANDS[kind]
    for name, data in ((f"deep_{kind}.toml", _nested(head).encode()),
                       (f"random_{kind}.toml", os.urandom(512))):
        path = tmp_path / name
        path.write_bytes(data)
        res = suscosim(*command, str(path), timeout=60)
        assert res.returncode == 2, res.stdout + res.stderr
        assert name in res.stderr and "internal error" not in res.stderr, res.stderr
        assert "Traceback" not in res.stderr


def test_the_depth_limit_is_a_limit_not_a_recursion(tmp_path: Path) -> None:
    path = tmp_path / "s.toml"
    ok = _nested("x = ", MAX_TOML_DEPTH - 1)  # the top table is a level too
    assert parse_user_toml(ok, path)["x"] is not None
    for depth in (MAX_TOML_DEPTH, 300, DEEP):  # deeper than the limit; past the parser's
        with pytest.raises(InputFileError, match=r"s\.toml.*nested deeper than 64"):
            parse_user_toml(_nested("x = ", depth), path)
    with pytest.raises(InputFileError, match=r"s\.toml.*not valid TOML"):
        parse_user_toml("x = [", path)
