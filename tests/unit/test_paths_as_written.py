"""#46 item 3: a path read from a file is taken as written: no environment variable and no
``~`` expanded (the product's source has no expandvars/expanduser), an OpenCRG file's
``$ROAD_CRG_FILE`` reference resolves inside the CRG file's folder only, and an error shows
the reference as written (a secret in an environment variable never reaches it)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from cosim.errors import InputFileError
from nodes.tyre_road.measured import read_crg
from tests.conftest import ROOT, suscosim

SECRET = "s3cr3t-do-not-print"


def _referencing(folder: Path, ref: str) -> Path:
    path = folder / "road.crg"
    path.write_text(f"$CT\nthe data is in another file\n$\n$ROAD_CRG_FILE\n{ref}\n$\n"
                    + "$" * 72 + "\n")
    return path


def test_the_product_expands_no_variable_nor_home_in_a_path() -> None:
    hits = [f"{p.relative_to(ROOT)}:{i}" for folder in ("cosim", "nodes", "orchestrator")
            for p in sorted((ROOT / folder).rglob("*.py"))
            for i, line in enumerate(p.read_text().splitlines(), start=1)
            if re.search(r"\b(expandvars|expanduser)\b", line)]
    assert hits == []


def test_a_crg_reference_to_a_variable_is_refused_and_not_expanded(tmp_path: Path,
                                                                    monkeypatch) -> None:
    road = _referencing(tmp_path, "./$SUSCOSIM_KEY.crg")
    (tmp_path / f"{SECRET}.crg").write_text("not read\n")
    monkeypatch.setenv("SUSCOSIM_KEY", SECRET)
    res = suscosim("check", str(ROOT / "scenarios" / "ch3_step_quarter_car.toml"), "--set",
                   f'road={{ type = "opencrg", path = "{road}", speed_kmh = 36.0 }}',
                   timeout=60)
    assert res.returncode == 2, res.stdout + res.stderr
    assert "./$SUSCOSIM_KEY.crg" in res.stderr and SECRET not in res.stdout + res.stderr


@pytest.mark.parametrize("ref, words", [
    ("/etc/hostname", "not absolute"),
    ("~/road.crg", "no ~"),
    ("../outside/data.crg", "leaves the folder"),
    ("missing.crg", "file not found"),
])
def test_a_crg_reference_outside_its_folder_is_refused(tmp_path: Path, ref: str,
                                                      words: str) -> None:
    folder = tmp_path / "road"
    folder.mkdir()
    (tmp_path / "outside").mkdir()
    (tmp_path / "outside" / "data.crg").write_text("x\n")
    with pytest.raises(InputFileError, match=re.escape(words)):
        read_crg(_referencing(folder, ref))


def test_a_crg_reference_inside_its_folder_is_read(tmp_path: Path) -> None:
    import pyopencrg

    u, v = np.arange(0.0, 5.0001, 0.05), np.linspace(-1.0, 1.0, 41)
    z = 0.002 * np.sin(2 * np.pi * u[:, None] / 2.0) + 0.0 * v[None, :]
    pyopencrg.CrgRoad(z, u_inc=0.05, v=v).save(tmp_path / "data.crg", fmt="LDFI")
    road = read_crg(_referencing(tmp_path, "data.crg"))
    assert road is not None
