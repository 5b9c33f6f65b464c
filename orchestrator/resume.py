"""``suscosim run --resume RUN_DIR`` and ``--fork RUN_DIR@T --set ...`` (docs/checkpoints.md).
Resume: the same scenario (hash checked), folder and id from the last complete checkpoint; the
killed run's journal is set aside as ``checkpoints/journal-k<k>.msgpack`` and the steps < k
journalled again (the files end equal to the uninterrupted run's). Fork: a new run from the
parent's checkpoint at T with ``--set``; only :data:`FORK_MAY_CHANGE` may change (else a
ScenarioError naming the key); a changed controller starts afresh, the other nodes continue.
"""

from __future__ import annotations

import copy
import json
import os
from pathlib import Path
from typing import Any

from cosim import auth as au
from cosim import checkpoint as cp
from cosim import scenario as sc
from cosim.errors import InputFileError, ScenarioError
from cosim.safe_open import read_user_text

JOURNAL = "journal.msgpack"
FORK_MAY_CHANGE = ("controller", "report", "nodes.controller", "run.id", "run.name",
                   "run.dir", "run.mode", "run.checkpoint_every_s", "run.stall_timeout_s",
                   "run.start_timeout_s", "run.resume")
RESTARTED_BY = {"controller": ("controller", "nodes.controller")}  # fresh when these changed


def parent_scenario(run_dir: Path) -> dict[str, Any]:
    """A run folder's ``scenario.json`` without its own ``run.resume``."""
    path = Path(run_dir) / "scenario.json"
    try:
        scenario = json.loads(read_user_text(path, "scenario", "the run's scenario.json",
                                             inside=run_dir))
    except ValueError as exc:
        raise InputFileError(str(path), f"not valid JSON ({exc})") from None
    if not isinstance(scenario, dict) or not isinstance(scenario.get("run"), dict):
        raise InputFileError(str(path), "not a run's resolved scenario (no [run] table)")
    scenario["run"].pop(cp.RESUME_KEY, None)
    return scenario


def key_of(run_dir: Path, scenario: dict[str, Any]) -> bytes | None:
    """The checkpoint MAC key (``SUSCOSIM_KEY[_FILE]``, else ``run.key``; None: unsigned)."""
    secret = au.secret_from_env()
    path = Path(run_dir) / au.KEY_FILE_NAME
    if secret is None and path.is_file():
        secret = au.read_secret_file(path)
    run_id = scenario["run"].get("id")
    if secret is None or not isinstance(run_id, str):
        return None
    return cp.checkpoint_key(au.derive_run_key(secret, run_id))


def checked_files(ck: cp.Checkpoint) -> dict[str, str]:
    return {node: str(e["sha256"]) for node, e in ck.manifest["nodes"].items()}


TRUST_CODE_ENV = "SUSCOSIM_TRUST_RUN_CODE"  # 1: resume/fork a folder that names code


def code_named(scenario: dict[str, Any], run_dir: Path) -> list[str]:
    """What a run folder's scenario names to run as code (``module:attr``, an FMU in it)."""
    found = [f"nodes.{kind} = {v!r}" for kind, v in (scenario.get("nodes") or {}).items()
             if isinstance(v, str) and ":" in v]
    got = scenario.get("controller")
    ctl: dict[str, Any] = got if isinstance(got, dict) else {}
    if isinstance(ctl.get("law"), str) and ":" in ctl["law"]:
        found.append(f"controller.law = {ctl['law']!r}")
    fmu = ctl.get("fmu")
    if isinstance(fmu, str) and Path(run_dir).resolve() in Path(fmu).resolve().parents:
        found.append(f"controller.fmu = {fmu!r} (inside the run folder)")
    return found


def _refuse_code(scenario: dict[str, Any], run_dir: Path) -> None:
    named = code_named(scenario, run_dir)
    if named and os.environ.get(TRUST_CODE_ENV) != "1":
        raise cp.CheckpointError(f"{Path(run_dir) / 'scenario.json'} names code to run ("
                              + "; ".join(named) + "): a run folder is data, and resuming or "
                              f"forking it would run that code; set {TRUST_CODE_ENV}=1 if "
                              "you trust whoever made the folder")


def journal_for(run_dir: Path, k: int) -> Path:
    """The journal holding every step < ``k`` (one set aside by a resume, else the run's)."""
    root = Path(run_dir) / cp.CHECKPOINTS_DIR
    aside = sorted((int(p.stem.split("-k")[1]), p) for p in root.glob("journal-k*.msgpack")
                   if p.stem.split("-k")[1].isdigit())
    for kk, path in aside:
        if kk >= k:
            return path
    path = Path(run_dir) / JOURNAL
    if not path.is_file():
        raise cp.CheckpointError(f"{run_dir}: no journal ({JOURNAL}) to resume the steps < {k} "
                              "from")
    return path


def resume_scenario(run_dir: str | Path) -> tuple[dict[str, Any], cp.Checkpoint]:
    """The scenario resuming ``run_dir``; CheckpointError (exit 2) naming what is wrong."""
    run_dir = Path(run_dir)
    scenario = parent_scenario(run_dir)
    _refuse_code(scenario, run_dir)
    ck = cp.load_for_resume(run_dir, scenario, key=key_of(run_dir, scenario))
    if Path(scenario["run"]["dir"]).resolve() != run_dir.resolve():
        scenario["run"]["dir"] = str(run_dir)  # a run folder moved since: it is here now
    aside = run_dir / cp.CHECKPOINTS_DIR / f"journal-k{ck.k:06d}.msgpack"
    if not aside.exists():
        current = run_dir / JOURNAL
        if not current.is_file():
            raise cp.CheckpointError(f"{run_dir}: no journal ({JOURNAL}) to resume from")
        current.replace(aside)
    scenario["run"][cp.RESUME_KEY] = {"k": ck.k, "t": ck.t, "folder": str(ck.folder),
                                   "journal": str(aside), "fresh": [],
                                   "sha256": checked_files(ck)}
    return scenario, ck


def fork_scenario(spec: str, overrides: list[str], out: str | None,
                  resolve: Any) -> tuple[dict[str, Any], cp.Checkpoint, list[str]]:
    """(scenario, checkpoint, changed keys) of a fork ``RUN_DIR@T`` with ``overrides``."""
    try:
        parent_dir, at = cp.parse_fork(spec)
    except ValueError as exc:
        raise ScenarioError("--fork", spec, str(exc)) from None
    parent = parent_scenario(parent_dir)
    _refuse_code(parent, parent_dir)
    ck = cp.load_for_resume(parent_dir, parent, at_t=at, key=key_of(parent_dir, parent))
    child = copy.deepcopy(parent)
    run = child["run"]
    for key in sc.RESOLVED_RUN_KEYS:
        if key != "t_end_source":  # t_end stays the parent's: resolve would not set it again
            run.pop(key, None)
    run["id"] = ""
    for assignment in overrides:
        sc.apply_override(child, assignment)
    child = resolve(sc.validate_common(child), out)
    run = child["run"]
    changed = [c for c in _changes(parent, child)  # a fork's own id and folder aside
               if not c.startswith(("run.id", "run.dir", "run.resume"))]
    bad = [key for key in changed if not key.startswith(FORK_MAY_CHANGE)]
    if bad:
        raise ScenarioError(bad[0], _get(child, bad[0]),
                            f"the parent's value ({_get(parent, bad[0])!r}): a fork continues "
                            "the parent's vehicle, tyre, road, step and fatigue model from "
                            f"its state at t = {ck.t:g} s and may change only "
                            + ", ".join(FORK_MAY_CHANGE[:3]))
    if Path(run["dir"]).resolve() == Path(parent_dir).resolve():
        raise ScenarioError("--out", run["dir"], "a folder other than the parent run's")
    fresh = [node for node, keys in RESTARTED_BY.items()
             if any(c.startswith(keys) for c in changed)]
    run[cp.RESUME_KEY] = {"k": ck.k, "t": ck.t, "folder": str(ck.folder),
                       "journal": str(journal_for(parent_dir, ck.k)), "fresh": fresh,
                       "parent": str(parent_dir), "sha256": checked_files(ck)}
    return child, ck, changed


def _changes(a: Any, b: Any, key: str = "") -> list[str]:
    """Dotted keys differing between ``a`` and ``b`` (a new ``run`` key at its default: none)."""
    if isinstance(a, dict) and isinstance(b, dict):
        out: list[str] = []
        for k in sorted(set(a) | set(b)):
            sub = f"{key}.{k}" if key else str(k)
            if key == "run" and k not in a and k in sc.RUN_KEYS and b[k] == sc.RUN_KEYS[k].default:
                continue
            if k not in a or k not in b:
                out.append(sub)
            else:
                out += _changes(a[k], b[k], sub)
        return out
    return [] if a == b else [key]


def _get(d: Any, dotted: str) -> Any:
    for part in dotted.split("."):
        if not isinstance(d, dict) or part not in d:
            return None
        d = d[part]
    return d
