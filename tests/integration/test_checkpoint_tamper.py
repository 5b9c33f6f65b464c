"""A run folder is untrusted input (issue #43): a checkpoint whose node file was replaced by a
pickle that writes a file, its hashes recomputed in the header and the manifest, is refused by
``suscosim run --resume`` and ``--fork`` with exit 2 naming the file, and the payload never runs;
a manifest whose fields are wrong is refused the same way."""

from __future__ import annotations

import hashlib
import json
import pickle
import shutil
from pathlib import Path

import pytest

from cosim import checkpoint as ck

from ..conftest import ROOT, suscosim

CH3 = ROOT / "scenarios" / "ch3_step_quarter_car.toml"


@pytest.fixture(scope="module")
def parent(tmp_path_factory) -> Path:
    """A short real run with checkpoints every 0.1 s (signed: its run.key)."""
    out = tmp_path_factory.mktemp("tamper") / "run"
    r = suscosim("run", str(CH3), "--out", str(out), "--quiet", "--set", "run.t_end=0.3",
                 "--set", "run.checkpoint_every_s=0.1", timeout=240)
    assert r.returncode == 0, r.stdout + r.stderr
    assert (out / "run.key").is_file()
    return out


class _Payload:
    """What the attacker's pickle runs when loaded: writes ``path``."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def __reduce__(self):
        return (Path.write_text, (self.path, "pwned"))


def _last(run: Path) -> Path:
    return max((run / "checkpoints").glob("k*/manifest.json")).parent


def _forge(run: Path, node: str, payload: bytes, magic: bytes, mac: bool) -> None:
    """Replace ``node``'s file of the last checkpoint by ``payload`` with its SHA-256
    recomputed in the header and the manifest (and a zero MAC when ``mac``)."""
    folder = _last(run)
    digest = hashlib.sha256(payload).digest()
    (folder / f"{node}.ckpt").write_bytes(magic + digest + (bytes(32) if mac else b"")
                                          + payload)
    doc = json.loads((folder / "manifest.json").read_text())
    doc["nodes"][node].update(sha256=digest.hex(), bytes=len(payload))
    doc.pop("mac", None)
    (folder / "manifest.json").write_text(json.dumps(doc))


def _copy(parent: Path, tmp_path: Path) -> Path:
    run = tmp_path / "run"
    shutil.copytree(parent, run)
    return run


def _refused(r, *names: str) -> None:
    out = r.stdout + r.stderr
    assert r.returncode == 2, out
    assert "internal error" not in out, out
    for name in names:
        assert name in out, out


@pytest.mark.parametrize("case", ["v1-pickle", "v2-pickle", "v2-pickle-no-key"])
def test_a_pickle_in_a_checkpoint_is_refused_and_never_runs(parent, tmp_path, case):
    run = _copy(parent, tmp_path)
    victim = tmp_path / "pwned.txt"
    payload = pickle.dumps(_Payload(victim))
    if case == "v1-pickle":  # the old format, the attack as it was
        _forge(run, "controller", payload, b"SUSCKPT1", mac=False)
        why = "old format"
    else:
        _forge(run, "controller", payload, ck.MAGIC, mac=True)
        why = "signed with the run's key"
        if case == "v2-pickle-no-key":  # no key to check it: the format alone refuses it
            (run / "run.key").unlink()
            why = "plain data"
    r = suscosim("run", "--resume", str(run), timeout=120)
    _refused(r, "controller.ckpt", why)
    assert not victim.exists()
    t = json.loads((_last(run) / "manifest.json").read_text())["t"]
    child = tmp_path / "child"
    r = suscosim("run", "--fork", f"{run}@{t}", "--out", str(child), timeout=120)
    _refused(r, "controller.ckpt")
    assert not victim.exists()
    assert not (child / "table.csv").exists()


def test_a_file_signed_with_another_key_is_refused(parent, tmp_path):
    run = _copy(parent, tmp_path)
    folder = _last(run)
    good = ck.read_node_state(ck.read_checkpoint(folder), "plant", lenient=True)
    other = ck.checkpoint_key(b"x" * 32)
    entry = ck.write_node_state(run, int(folder.name[1:]), "plant", good, other)
    doc = json.loads((folder / "manifest.json").read_text())
    doc["nodes"]["plant"] = entry
    (folder / "manifest.json").write_text(json.dumps(doc))
    _refused(suscosim("run", "--resume", str(run), timeout=120), "plant.ckpt", "MAC differs")


@pytest.mark.parametrize("field,value,named", [
    ("t", "later", "'t'"),
    ("nodes", ["plant"], "'nodes'"),
    ("nodes.plant.file", "../../x", "../../x"),
])
def test_a_manifest_with_wrong_fields_is_refused(parent, tmp_path, field, value, named):
    run = _copy(parent, tmp_path)
    path = _last(run) / "manifest.json"
    doc = json.loads(path.read_text())
    *head, last = field.split(".")
    where = doc
    for part in head:
        where = where[part]
    where[last] = value
    path.write_text(json.dumps(doc))
    _refused(suscosim("run", "--resume", str(run), timeout=120), "manifest.json", named)


@pytest.mark.parametrize("node,state", [
    ("controller", {"law": None, "attrs": {}, "rebuilt": []}),  # the "law None"
    ("plant", {"model": {"model": "another"}, "before": None, "prev": {}, "st": {}}),
    ("tyre_road", {"_s0": 1.0}),
])
def test_plain_data_that_does_not_fit_its_node_is_exit_2_named(parent, tmp_path, node,
                                                                state):
    """An unsigned folder (run.key gone) with well-formed plain data of the wrong shape: the
    node refuses it with a CheckpointError, exit 2, never an internal error."""
    run = _copy(parent, tmp_path)
    (run / "run.key").unlink()
    folder = _last(run)
    entry = ck.write_node_state(run, int(folder.name[1:]), node, state)
    doc = json.loads((folder / "manifest.json").read_text())
    doc["nodes"][node] = entry
    doc.pop("mac")
    (folder / "manifest.json").write_text(json.dumps(doc))
    r = suscosim("run", "--resume", str(run), timeout=120)
    _refused(r, node, "checkpoint")
