"""#46 item 4: names from a file that become folders follow the run id's rule; references
inside a handed folder stay inside it; a run folder a duty file points at is read, never
written; an .inp *INCLUDE resolves inside the mesh's folder and an error never echoes
another file's content."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cosim.errors import InputFileError, ScenarioError
from tests.conftest import ROOT, suscosim

SCENARIO = ROOT / "scenarios" / "ch3_step_quarter_car.toml"


@pytest.mark.parametrize("where, name", [("event", ".."), ("law", ".."), ("duty", ".."),
                                         ("event", ".hidden"), ("law", "a b")])
def test_a_duty_name_that_is_not_a_plain_folder_name_is_refused(tmp_path: Path, where: str,
                                                               name: str) -> None:
    duty = {"duty": f'name = "{name if where == "duty" else "d"}"',
            "event": f'name = "{name if where == "event" else "e"}"',
            "law": f'name = "{name if where == "law" else "passive"}"'}
    path = tmp_path / "duty.toml"
    path.write_text(f"[duty]\n{duty['duty']}\n\n[[events]]\n{duty['event']}\n"
                    f'scenario = "{SCENARIO}"\nrepeats = 1\n\n[[laws]]\n{duty["law"]}\n')
    out = tmp_path / "out" / "duty"
    res = suscosim("duty", str(path), "--out", str(out), timeout=60)
    assert res.returncode == 2, res.stdout + res.stderr
    key = {"duty": "duty.name", "event": "events[0].name", "law": "laws[0].name"}[where]
    assert f"'{key}'" in res.stderr and "letters, digits" in res.stderr, res.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["duty.toml"]  # nothing written


def test_a_run_event_batch_goes_under_out_not_into_the_run_folder(tmp_path: Path,
                                                                 monkeypatch) -> None:
    from orchestrator import duty

    run_dir = tmp_path / "finished_run"
    run_dir.mkdir()
    batch_into = tmp_path / "out" / "runs" / "e" / "fatigue"
    asked: list = []

    def fake_batch(run: Path, overrides=None, out=None, progress=None) -> None:
        asked.append((run, out))
        out.mkdir(parents=True)
        (out / "summary.json").write_text(json.dumps({"track_length_m": 10.0}))
        (out / "damage_per_node.csv").write_text("node_id,damage_per_pass,x_m,y_m,z_m\n"
                                                  "7,1e-9,0,0,0\n")

    monkeypatch.setattr("nodes.fatigue.run_dir.fatigue_run_dir", fake_batch)
    fat = duty._event_fatigue(run_dir, batch_into)
    assert asked == [(run_dir, batch_into)] and fat["ids"] == [7]
    assert list(run_dir.iterdir()) == []


def test_a_sweep_json_run_dir_outside_the_sweep_folder_is_refused(tmp_path: Path) -> None:
    other = tmp_path / "someone_elses_run"
    other.mkdir()
    (other / "summary.json").write_text(json.dumps({"status": "ok"}))
    sweep = tmp_path / "sweep"
    sweep.mkdir()
    for run_dir in ("../someone_elses_run", str(other)):
        (sweep / "sweep.json").write_text(json.dumps(
            {"name": "s", "points": [{"id": "p0", "params": {}, "run_dir": run_dir}]}))
        res = suscosim("report", str(sweep), timeout=60)
        assert res.returncode == 2, res.stdout + res.stderr
        assert "leaves the sweep folder" in res.stderr and run_dir in res.stderr, res.stderr
        assert not (sweep / "report.html").exists()
    # a shared runs folder the user names on the command line is read (suscosim sweep
    # --runs-dir on shared storage writes such run_dirs); another folder still is not
    res = suscosim("report", str(sweep), "--runs-dir", str(tmp_path / "elsewhere"), timeout=60)
    assert res.returncode == 2 and "leaves the sweep folder" in res.stderr, res.stderr
    res = suscosim("report", str(sweep), "--runs-dir", str(tmp_path), timeout=60)
    assert res.returncode == 0, res.stdout + res.stderr
    assert (sweep / "report.html").exists()


TET = ("*NODE\n1, 0.0, 0.0, 0.0\n2, 1.0, 0.0, 0.0\n3, 0.0, 1.0, 0.0\n4, 0.0, 0.0, 1.0\n"
       "*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4\n")


@pytest.mark.parametrize("ref, words", [
    ("/etc/hostname", "a file inside the mesh's folder"),
    ("../outside.inp", "leaves the folder"),
])
def test_an_inp_include_outside_the_mesh_folder_is_refused(tmp_path: Path, ref: str,
                                                           words: str) -> None:
    from nodes.fatigue.parts.mesh import read_mesh

    folder = tmp_path / "part"
    folder.mkdir()
    (tmp_path / "outside.inp").write_text("SECRET LINE, not a mesh\n")
    mesh = folder / "arm.inp"
    mesh.write_text(f"*HEADING\n*INCLUDE, INPUT={ref}\n")
    with pytest.raises(InputFileError, match=words) as err:
        read_mesh(mesh)
    assert "SECRET" not in str(err.value)


def test_an_inp_include_inside_the_folder_is_read_and_its_content_not_echoed(
        tmp_path: Path) -> None:
    from nodes.fatigue.parts.mesh import read_mesh

    (tmp_path / "tets.inp").write_text(TET)
    mesh = tmp_path / "arm.inp"
    mesh.write_text("*HEADING\n*INCLUDE, INPUT=tets.inp\n")
    assert read_mesh(mesh).t.shape == (1, 4)
    (tmp_path / "tets.inp").write_text("*NODE\nSECRET LINE, x, y\n")
    with pytest.raises(InputFileError) as err:
        read_mesh(mesh)
    assert "SECRET" not in str(err.value) and "arm.inp" in str(err.value)


@pytest.mark.parametrize("name", ["../../escape", ".hidden", "a b"])
def test_a_part_name_that_is_not_a_plain_file_name_is_refused(tmp_path: Path,
                                                             name: str) -> None:
    from nodes.fatigue.parts.schema import load_part

    path = tmp_path / "p.toml"
    path.write_text(f'[part]\nname = "{name}"\ngeometry = "builtin:lower_arm"\n')
    with pytest.raises(InputFileError, match="part.name"):
        load_part(path)


def test_a_sweep_of_a_million_points_is_refused_before_it_is_enumerated(tmp_path: Path,
                                                                        ) -> None:
    from orchestrator.sweep.spec import load_sweep

    values = ", ".join(str(1000.0 + i) for i in range(1000))
    path = tmp_path / "big.toml"
    path.write_text(f'[sweep]\nname = "big"\nbase = "{SCENARIO}"\n\n[sweep.grid]\n'
                    f'"vehicle.sprung_mass" = [{values}]\n"tyre.stiffness" = [{values}]\n')
    res = suscosim("sweep", str(path), "--list", "--out", str(tmp_path / "out"), timeout=60)
    assert res.returncode == 2, res.stdout + res.stderr
    assert "1000 x 1000 = 1000000 points" in res.stderr and "--max-points" in res.stderr
    small = ", ".join(str(1000.0 + i) for i in range(101))
    path.write_text(f'[sweep]\nname = "big"\nbase = "{SCENARIO}"\n\n[sweep.grid]\n'
                    f'"vehicle.sprung_mass" = [{small}]\n"tyre.stiffness" = [{small}]\n')
    with pytest.raises(ScenarioError, match="101 x 101 = 10201 points"):
        load_sweep(path)
    assert len(load_sweep(path, max_points=10201).points) == 10201


def test_the_report_embeds_no_image_from_outside_the_handed_folder(tmp_path: Path) -> None:
    import os

    from orchestrator.report.plots import file_uri
    from tests.unit.test_bounded_reads import _in_thread

    png = b"\x89PNG\r\n\x1a\n" + b"outside"
    (tmp_path / "outside.png").write_bytes(png)
    fat = tmp_path / "run" / "fatigue"
    fat.mkdir(parents=True)
    (fat / "damage_map.png").symlink_to(tmp_path / "outside.png")
    assert file_uri(fat / "damage_map.png") is None
    os.mkfifo(fat / "sn_curve.png")
    assert _in_thread(file_uri, fat / "sn_curve.png") == {"value": None}
    (fat / "own.png").write_bytes(png)
    assert (file_uri(fat / "own.png") or "").startswith("data:image/png;base64,")


def test_out_wins_over_a_sweep_files_runs_dir(tmp_path: Path) -> None:
    path = tmp_path / "s.toml"
    path.write_text(f'[sweep]\nname = "tiny"\nbase = "{SCENARIO}"\n'
                    f'runs_dir = "{tmp_path / "elsewhere"}"\n[sweep.grid]\n"run.t_end" = [0.1]\n')
    out = tmp_path / "out"
    res = suscosim("sweep", str(path), "--out", str(out), "--no-fatigue", "--jobs", "1",
                   timeout=180)
    assert res.returncode == 0, res.stdout + res.stderr
    assert f"runs under {out / 'runs'} (--out), not the sweep file's runs_dir" in res.stdout
    assert (out / "runs" / "tiny-0.1" / "summary.json").is_file()
    assert not (tmp_path / "elsewhere").exists()
