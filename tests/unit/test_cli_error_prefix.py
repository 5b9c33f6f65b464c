"""#30: every command's bad-input error is one line ``suscosim: error: <command>: ...`` and
exit 2 (duty, cluster, sweep, pseudo-damage, corner and fatigue had prefixes of their own)."""

from __future__ import annotations

import pytest

from tests.conftest import suscosim


@pytest.mark.parametrize("args, command, words", [
    (["sweep", "/nonexist.toml", "--jobs", "0"], "sweep", "--jobs must be >= 1"),
    (["sweep", "/nonexist.toml"], "sweep", "sweep file: file not found"),
    (["duty", "/nonexist.toml"], "duty", "duty file: file not found"),
    (["cluster", "--workers", "0"], "cluster", "--workers must be >= 1"),
    (["pseudo-damage", "--k", "0", "/tmp"], "pseudo-damage", "--k and --n-ref must be > 0"),
    (["pseudo-damage", "/nonexist"], "pseudo-damage", "no such run folder or load file"),
    (["corner", "check", "/nonexist.toml"], "corner", "corner file: file not found"),
])
def test_a_bad_input_gets_the_common_prefix_and_exit_2(args, command, words) -> None:
    res = suscosim(*args, timeout=60)
    assert res.returncode == 2, res.stdout + res.stderr
    last = res.stderr.strip().splitlines()[-1]
    assert last.startswith(f"suscosim: error: {command}: "), last
    assert words in last and "Traceback" not in res.stderr
