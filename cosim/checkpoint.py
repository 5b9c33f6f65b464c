"""Checkpoints of a whole run, the storage layer (issue #29 item 4): what each node writes, the
manifest the orchestrator writes last, and how ``--resume`` finds and checks the last complete one.

Layout inside a run folder::

    checkpoints/k000123/<node>.ckpt     one file per node: its whole state at step boundary k
    checkpoints/k000123/manifest.json   written LAST, by the orchestrator, once every node's
                                        file is in place: {"k", "t", "scenario_sha256",
                                        "nodes": {node: {"file", "sha256", "bytes"}}}

A node file is ``MAGIC`` + 32-byte SHA-256 of the payload + the payload (a pickle of the node's
state dict). Every file is written aside (``.tmp`` in the same folder), flushed, fsynced and
renamed into place, so a reader sees either no file or a whole one. A checkpoint without a
manifest is incomplete (a kill between the nodes' writes and the manifest) and is ignored.

:func:`load_for_resume` refuses, with :class:`CheckpointError` (exit code 2, the reason named):
a folder with no complete checkpoint, a scenario that differs from the checkpoint's (other than
the keys a fork is allowed to change), a node file missing, truncated or whose hash differs.

Pure file I/O with no bus: the clock's checkpoint message and the nodes' shells call this.
"""

from __future__ import annotations

import hashlib
import json
import os
import pickle
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .errors import SuscosimError

CHECKPOINTS_DIR = "checkpoints"
MANIFEST = "manifest.json"
MAGIC = b"SUSCKPT1"
EXIT_CODE = 2
_STEP_DIR = re.compile(r"^k(\d{6,})$")


class CheckpointError(SuscosimError):
    """A checkpoint that cannot be used or made; ``exit_code`` is what ``suscosim run
    --resume`` exits (and a node that cannot checkpoint what the scenario asks)."""

    exit_code = EXIT_CODE


@dataclass(frozen=True)
class Checkpoint:
    """A complete checkpoint at step boundary ``k`` (the start of step k: steps 0..k-1 done),
    time ``t`` = k h [s], its folder."""

    k: int
    t: float
    folder: Path
    manifest: dict[str, Any]


RESUME_KEY = "resume"
"""``run.resume``: where a resumed or forked run starts (set by the orchestrator, never by a
user: :mod:`cosim.run_checkpoint`); not part of what a checkpoint's scenario hash covers."""


def scenario_sha256(scenario: dict[str, Any]) -> str:
    """The SHA-256 of the resolved scenario's canonical JSON (sorted keys, no spaces), without
    ``run.resume`` (a resumed run is the same scenario as the run it continues)."""
    run = scenario.get("run")
    if isinstance(run, dict) and RESUME_KEY in run:
        scenario = {**scenario, "run": {k: v for k, v in run.items() if k != RESUME_KEY}}
    text = json.dumps(scenario, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def step_folder(run_dir: Path, k: int) -> Path:
    """The folder of the checkpoint at step boundary ``k``."""
    return Path(run_dir) / CHECKPOINTS_DIR / f"k{k:06d}"


def _write_atomic(path: Path, data: bytes) -> None:
    """Write ``data`` aside, fsync, rename into place, fsync the folder."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "wb") as fh:
        fh.write(data)
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)
    fd = os.open(path.parent, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def write_node_state(run_dir: Path, k: int, node: str, state: dict[str, Any]) -> dict[str, Any]:
    """Save ``node``'s whole ``state`` at step boundary ``k``; return its manifest entry."""
    if not re.fullmatch(r"[A-Za-z0-9_.-]+", node):
        raise ValueError(f"checkpoint node name {node!r}: letters, digits, _ . - only")
    payload = pickle.dumps(state, protocol=pickle.HIGHEST_PROTOCOL)
    digest = hashlib.sha256(payload).digest()
    name = f"{node}.ckpt"
    _write_atomic(step_folder(run_dir, k) / name, MAGIC + digest + payload)
    return {"file": name, "sha256": digest.hex(), "bytes": len(payload)}


def write_manifest(run_dir: Path, k: int, t: float, scenario: dict[str, Any],
                   entries: dict[str, dict[str, Any]]) -> Path:
    """Write the manifest LAST, once every node's file is in place: the checkpoint is complete.

    Raises :class:`CheckpointError` when a listed node file is not there (never a manifest for
    an incomplete checkpoint)."""
    folder = step_folder(run_dir, k)
    for node, entry in entries.items():
        if not (folder / entry["file"]).is_file():
            raise CheckpointError(f"checkpoint k={k}: node {node!r} file {entry['file']} missing")
    doc = {"k": int(k), "t": float(t), "scenario_sha256": scenario_sha256(scenario),
           "nodes": dict(sorted(entries.items()))}
    path = folder / MANIFEST
    _write_atomic(path, json.dumps(doc, indent=1, sort_keys=True).encode())
    return path


def complete_checkpoints(run_dir: Path) -> list[Checkpoint]:
    """The complete checkpoints of ``run_dir`` (a readable manifest), oldest first."""
    root = Path(run_dir) / CHECKPOINTS_DIR
    found: list[Checkpoint] = []
    if not root.is_dir():
        return found
    for sub in root.iterdir():
        m = _STEP_DIR.match(sub.name)
        if not m or not (sub / MANIFEST).is_file():
            continue
        try:
            doc = json.loads((sub / MANIFEST).read_text())
        except (OSError, ValueError):
            continue
        if not isinstance(doc, dict) or doc.get("k") != int(m.group(1)):
            continue
        found.append(Checkpoint(int(doc["k"]), float(doc["t"]), sub, doc))
    return sorted(found, key=lambda c: c.k)


def read_node_state(ckpt: Checkpoint, node: str) -> dict[str, Any]:
    """``node``'s state from ``ckpt``, its hash checked against the file and the manifest."""
    entry = ckpt.manifest.get("nodes", {}).get(node)
    if entry is None:
        raise CheckpointError(f"checkpoint k={ckpt.k} has no state for node {node!r}")
    path = ckpt.folder / entry["file"]
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise CheckpointError(f"checkpoint k={ckpt.k}: cannot read {path}: {exc}") from exc
    head = len(MAGIC) + 32
    if len(data) < head or not data.startswith(MAGIC):
        raise CheckpointError(f"checkpoint k={ckpt.k}: {path} is damaged (bad header)")
    digest, payload = data[len(MAGIC):head], data[head:]
    if hashlib.sha256(payload).digest() != digest or digest.hex() != entry["sha256"]:
        raise CheckpointError(f"checkpoint k={ckpt.k}: {path} is damaged (SHA-256 differs)")
    state = pickle.loads(payload)
    if not isinstance(state, dict):
        raise CheckpointError(f"checkpoint k={ckpt.k}: {path} does not hold a state dict")
    return state


def load_for_resume(run_dir: Path, scenario: dict[str, Any],
                    at_t: float | None = None) -> Checkpoint:
    """The checkpoint to resume (the last complete one) or fork (the one at ``at_t`` [s]).

    ``scenario`` is the parent's resolved scenario for a fork (its ``--set`` keys applied after)
    or the scenario to run now for a resume: it must hash equal to the checkpoint's. Every node
    file is checked. Raises :class:`CheckpointError` naming what is wrong."""
    cks = complete_checkpoints(run_dir)
    if not cks:
        raise CheckpointError(f"{run_dir}: no complete checkpoint (no {CHECKPOINTS_DIR}/k*/"
                              f"{MANIFEST}); set run.checkpoint_every_s and rerun")
    if at_t is None:
        ck = cks[-1]
    else:
        near = [c for c in cks if abs(c.t - at_t) <= 1e-9 * max(1.0, abs(at_t))]
        if not near:
            have = ", ".join(f"{c.t:g}" for c in cks)
            raise CheckpointError(f"{run_dir}: no checkpoint at t={at_t:g} s (have: {have})")
        ck = near[0]
    if ck.manifest.get("scenario_sha256") != scenario_sha256(scenario):
        raise CheckpointError(f"{run_dir}: the scenario differs from the one checkpoint k={ck.k} "
                              "was taken with (resume runs the same scenario; use --fork to "
                              "change settings)")
    for node in ck.manifest.get("nodes", {}):
        read_node_state(ck, node)
    return ck


def prune_checkpoints(run_dir: Path, keep: int) -> list[int]:
    """Delete every complete checkpoint of ``run_dir`` but the ``keep`` newest (``run.
    checkpoint_keep``): the manifest first (the checkpoint is then incomplete, never half a
    complete one), then its folder. Returns the k deleted; a folder that cannot be removed
    is left (the next prune tries again)."""
    import shutil

    gone: list[int] = []
    for ck in complete_checkpoints(run_dir)[:-keep] if keep > 0 else []:
        try:
            (ck.folder / MANIFEST).unlink()
        except OSError:
            continue
        shutil.rmtree(ck.folder, ignore_errors=True)
        gone.append(ck.k)
    return gone


def read_checkpoint(folder: Path) -> Checkpoint:
    """The complete checkpoint in ``folder`` (its manifest read); CheckpointError if none."""
    folder = Path(folder)
    try:
        doc = json.loads((folder / MANIFEST).read_text())
        return Checkpoint(int(doc["k"]), float(doc["t"]), folder, doc)
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise CheckpointError(f"{folder}: not a complete checkpoint ({exc})") from None


def checkpoint_steps(every_s: float, h: float, n_steps: int) -> list[int]:
    """The step boundaries k (a checkpoint at the start of step k, t = k h [s]: steps 0..k-1
    are done, a resumed run starts with step k) of
    ``run.checkpoint_every_s`` = ``every_s`` [s]: every round(every_s / h) steps, the last
    step excluded (the run's end is its own result). Every node computes the same list from
    the scenario alone, so the boundary needs no negotiation; the clock's checkpoint message
    only collects that each node has written its file."""
    if not every_s > 0 or not h > 0:
        raise ValueError(f"run.checkpoint_every_s = {every_s!r}: a positive number of seconds")
    every = round(every_s / h)
    if every < 1 or abs(every * h - every_s) > 1e-9 * every_s:
        raise ValueError(f"run.checkpoint_every_s = {every_s:g} s: a whole number of steps "
                         f"of h = {h:g} s")
    return list(range(every, n_steps, every))


def parse_fork(spec: str) -> tuple[Path, float]:
    """``RUN_DIR@T`` of ``suscosim run --fork`` as (run folder, T [s]); ValueError naming it."""
    folder, sep, t = spec.rpartition("@")
    if not sep or not folder:
        raise ValueError(f"--fork {spec!r}: expected RUN_DIR@T (T in seconds)")
    try:
        at = float(t)
    except ValueError:
        raise ValueError(f"--fork {spec!r}: T = {t!r} is not a number of seconds") from None
    if not at >= 0:
        raise ValueError(f"--fork {spec!r}: T must be >= 0 s")
    return Path(folder), at
