"""Checkpoints of a whole run, the storage layer: what each node writes, the manifest the
orchestrator writes last, and how ``--resume`` finds and checks the last complete one.

Layout inside a run folder::

    checkpoints/k000123/<node>.ckpt     one file per node: its whole state at step boundary k
    checkpoints/k000123/manifest.json   written LAST, by the orchestrator, once every node's
                                        file is in place: {"k", "t", "scenario_sha256",
                                        "nodes": {node: {"file", "sha256", "bytes"}}}

A node file is ``MAGIC`` + the payload's SHA-256 + a 32-byte MAC (HMAC-SHA256 of step, node
and payload with :func:`checkpoint_key`; zeros without a run key) + the payload: the node's
state as plain data (:mod:`cosim.plaindata`; never a pickle); the manifest carries the MAC of
its canonical JSON (``mac``). Every file is written aside, fsynced and renamed into place. A
fault is a :class:`CheckpointError` (exit 2) naming the node, the file and the fault.
"""

from __future__ import annotations

import hashlib
import hmac
import json
import math
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from . import plaindata
from .errors import SuscosimError

CHECKPOINTS_DIR = "checkpoints"
MANIFEST = "manifest.json"
MAGIC = b"SUSCKPT2"  # version 2, plain data (version 1, a pickle, is refused)
MAC_BYTES = 32
_HEAD = len(MAGIC) + 32 + MAC_BYTES
_NODE = re.compile(r"^[A-Za-z0-9_.-]+$")
EXIT_CODE = 2
_STEP_DIR = re.compile(r"^k(\d{6,})$")


class CheckpointError(SuscosimError):
    """A checkpoint that cannot be used or made (exit 2)."""

    exit_code = EXIT_CODE


@dataclass(frozen=True)
class Checkpoint:
    """A complete checkpoint at step boundary ``k`` (steps 0..k-1 done), t = k h [s]."""

    k: int
    t: float
    folder: Path
    manifest: dict[str, Any]


RESUME_KEY = "resume"  # run.resume (cosim.run_checkpoint): not in the scenario hash


def scenario_sha256(scenario: dict[str, Any]) -> str:
    """The SHA-256 of the resolved scenario's canonical JSON, without ``run.resume``."""
    run = scenario.get("run")
    if isinstance(run, dict) and RESUME_KEY in run:
        scenario = {**scenario, "run": {k: v for k, v in run.items() if k != RESUME_KEY}}
    text = json.dumps(scenario, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def step_folder(run_dir: Path, k: int) -> Path:
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


def checkpoint_key(run_key: bytes | None) -> bytes | None:
    """The checkpoint MAC key derived from a run key (never a message signature); or None."""
    if not run_key:
        return None
    return hmac.new(run_key, b"suscosim-checkpoint-v2", hashlib.sha256).digest()


def _node_mac(key: bytes, k: int, node: str, payload: bytes) -> bytes:
    return hmac.new(key, f"{k}\0{node}\0".encode() + payload, hashlib.sha256).digest()


def _manifest_mac(key: bytes, doc: dict[str, Any]) -> str:
    body = json.dumps({f: v for f, v in doc.items() if f != "mac"}, sort_keys=True,
                      separators=(",", ":"))
    return hmac.new(key, body.encode(), hashlib.sha256).hexdigest()


def write_node_state(run_dir: Path, k: int, node: str, state: dict[str, Any],
                     key: bytes | None = None) -> dict[str, Any]:
    """Save ``node``'s ``state`` at boundary ``k`` (MAC with ``key``); its manifest entry.
    CheckpointError when the state is not plain data (naming what is not)."""
    if not _NODE.match(node):
        raise ValueError(f"checkpoint node name {node!r}: letters, digits, _ . - only")
    try:
        payload = plaindata.encode(state)
    except plaindata.PlainDataError as exc:
        raise CheckpointError(f"{node}: its state at k={k} cannot be checkpointed: {exc}") \
            from None
    digest = hashlib.sha256(payload).digest()
    mac = _node_mac(key, k, node, payload) if key else bytes(MAC_BYTES)
    name = f"{node}.ckpt"
    _write_atomic(step_folder(run_dir, k) / name, MAGIC + digest + mac + payload)
    return {"file": name, "sha256": digest.hex(), "bytes": len(payload)}


def write_manifest(run_dir: Path, k: int, t: float, scenario: dict[str, Any],
                   entries: dict[str, dict[str, Any]], key: bytes | None = None) -> Path:
    """Write the manifest LAST (MAC with ``key``): the checkpoint is complete."""
    folder = step_folder(run_dir, k)
    for node, entry in entries.items():
        if not (folder / entry["file"]).is_file():
            raise CheckpointError(f"checkpoint k={k}: node {node!r} file {entry['file']} missing")
    doc: dict[str, Any] = {"k": int(k), "t": float(t), "scenario_sha256": scenario_sha256(scenario),
                           "nodes": dict(sorted(entries.items()))}
    if key:
        doc["mac"] = _manifest_mac(key, doc)
    path = folder / MANIFEST
    _write_atomic(path, json.dumps(doc, indent=1, sort_keys=True).encode())
    return path


def _hex(v: Any, n: int) -> bool:
    return type(v) is str and len(v) == n and all(c in "0123456789abcdef" for c in v)


def _checked(doc: dict[str, Any], path: Path) -> Checkpoint:
    """The checkpoint a parsed manifest describes; CheckpointError naming the field."""
    def bad(what: str) -> CheckpointError:
        return CheckpointError(f"{path}: not a checkpoint manifest: {what}")

    if type(doc.get("k")) is not int or doc["k"] < 0:
        raise bad(f"'k' = {doc.get('k')!r:.40} is not a step number")
    t: Any = doc.get("t")
    if type(t) not in (int, float) or not math.isfinite(t) or t < 0:
        raise bad(f"'t' = {t!r:.40} is not a time in seconds")
    if not _hex(doc.get("scenario_sha256"), 64):
        raise bad("'scenario_sha256' is not 64 hex digits")
    if "mac" in doc and not _hex(doc["mac"], 64):
        raise bad("'mac' is not 64 hex digits")
    nodes = doc.get("nodes")
    if not isinstance(nodes, dict) or not nodes:
        raise bad(f"'nodes' = {nodes!r:.40} is not a table of the nodes' files")
    for node, entry in nodes.items():
        if not _NODE.match(node):
            raise bad(f"node name {node!r:.40}: letters, digits, _ . - only")
        if not isinstance(entry, dict) or entry.get("file") != f"{node}.ckpt":
            got = entry.get("file") if isinstance(entry, dict) else entry
            raise bad(f"nodes.{node}.file = {got!r:.60}: must be {node}.ckpt in the "
                      "checkpoint's folder")
        if not _hex(entry.get("sha256"), 64) or type(entry.get("bytes")) is not int:
            raise bad(f"nodes.{node}: 'sha256' (64 hex digits) and 'bytes' (an integer) needed")
    return Checkpoint(doc["k"], float(t), path.parent, doc)


def complete_checkpoints(run_dir: Path) -> list[Checkpoint]:
    """The complete checkpoints of ``run_dir``, oldest first (a non-JSON manifest: skipped)."""
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
        found.append(_checked(doc, sub / MANIFEST))
    return sorted(found, key=lambda c: c.k)


def read_node_state(ckpt: Checkpoint, node: str, key: bytes | None = None,
                    sha256: str | None = None, lenient: bool = False) -> dict[str, Any]:
    """``node``'s state from ``ckpt``, its hash checked (and against ``sha256``, its MAC with
    ``key``, when given); CheckpointError naming what is wrong."""
    entry = ckpt.manifest.get("nodes", {}).get(node)
    if entry is None:
        raise CheckpointError(f"checkpoint k={ckpt.k} has no state for node {node!r}")
    path = ckpt.folder / f"{node}.ckpt"

    def bad(what: str) -> CheckpointError:
        return CheckpointError(f"checkpoint k={ckpt.k}: node {node!r}: {path} {what}")

    try:
        data = path.read_bytes()
    except OSError as exc:
        raise bad(f"cannot be read ({exc.strerror or exc})") from None
    if data.startswith(b"SUSCKPT1"):
        raise bad("is of the old format (version 1, a Python pickle): refused, never loaded "
                  "(a pickle can run code); rerun the run to make new checkpoints")
    if len(data) < _HEAD or not data.startswith(MAGIC):
        raise bad("is damaged or not a checkpoint (bad header)")
    digest, mac, payload = data[len(MAGIC):len(MAGIC) + 32], data[_HEAD - MAC_BYTES:_HEAD], \
        data[_HEAD:]
    if hashlib.sha256(payload).digest() != digest or digest.hex() != entry["sha256"] \
            or (sha256 is not None and digest.hex() != sha256):
        raise bad("is damaged (SHA-256 differs)")
    if key is not None and not hmac.compare_digest(mac, _node_mac(key, ckpt.k, node, payload)):
        raise bad("is not signed with the run's key (MAC differs)")
    try:
        state = plaindata.decode(payload, lenient)
    except plaindata.PlainDataError as exc:
        raise bad(f"does not hold plain data: {exc}") from None
    if not isinstance(state, dict):
        raise bad("does not hold a state dict")
    return state


def load_for_resume(run_dir: Path, scenario: dict[str, Any], at_t: float | None = None,
                    key: bytes | None = None) -> Checkpoint:
    """The checkpoint to resume (the last) or fork (at ``at_t`` [s]), of ``scenario``'s hash,
    every node file and (``key``; without one a signed one is refused) MAC checked."""
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
    for node in ck.manifest["nodes"]:
        read_node_state(ck, node, key, lenient=True)
    where = ck.folder / MANIFEST
    if key is None and "mac" in ck.manifest:
        raise CheckpointError(f"{where} is signed with the run's key and no key is given to "
                              f"check it (the run folder's run.key, or SUSCOSIM_KEY_FILE / "
                              "SUSCOSIM_KEY as the run had)")
    if key is not None and not hmac.compare_digest(str(ck.manifest.get("mac", "")),
                                                   _manifest_mac(key, ck.manifest)):
        raise CheckpointError(f"{where} is not signed with the run's key ("
                              + ("MAC differs)" if "mac" in ck.manifest else "no MAC)"))
    return ck


def prune_checkpoints(run_dir: Path, keep: int) -> list[int]:
    """Delete all complete checkpoints but the ``keep`` newest (manifest first); the k deleted."""
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
    """The complete checkpoint in ``folder``; CheckpointError if none."""
    folder = Path(folder)
    try:
        doc = json.loads((folder / MANIFEST).read_text())
    except (OSError, ValueError) as exc:
        raise CheckpointError(f"{folder}: not a complete checkpoint ({exc})") from None
    if not isinstance(doc, dict):
        raise CheckpointError(f"{folder / MANIFEST}: not a checkpoint manifest (not a table)")
    return _checked(doc, folder / MANIFEST)


def checkpoint_steps(every_s: float, h: float, n_steps: int) -> list[int]:
    """The step boundaries k of ``run.checkpoint_every_s`` = ``every_s`` [s]: every
    round(every_s / h) steps, the last excluded (every node computes them alike)."""
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
