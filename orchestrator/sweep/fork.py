"""``[sweep] fork_at = T``: the points share their common prefix (docs/sweeps.md). Points
differing only in what a fork may change (:data:`orchestrator.resume.FORK_MAY_CHANGE`) form a
group with ONE parent run of the base's controller (``run.checkpoint_every_s = T``); every point
is ``suscosim run --fork PARENT@T``: rows < k = T / h are the parent's and **each law acts only
from T on** (said at the start, in ``fork.json`` and the results). Saved steps and wall time are
in ``fork.json``. Local executor only, without ``--external``/``--serve``.
"""

from __future__ import annotations

import copy
import math
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from cosim import scenario as sc
from cosim.checkpoint import CHECKPOINTS_DIR, MANIFEST, checkpoint_steps, step_folder
from cosim.errors import SuscosimError
from cosim.run_folder import read_json

from ..resume import FORK_MAY_CHANGE, _changes, _get
from .phases import run_ok
from .spec import Point, Sweep, SweepError, _absolute_paths, fingerprint, point_id, toml_value

BOOKKEEPING = ("run.id", "run.dir", "run.resume")  # a fork always differs in these
SEMANTICS = ("each point's controller acts only from t = fork_at on; before, every point of "
             "a group ran its parent's (the base's) controller, and its rows < k = fork_at / h "
             "are the parent's")


def fork_key(key: str) -> bool:
    return key.startswith(FORK_MAY_CHANGE)


def _only_fork_changes(a: dict[str, Any], b: dict[str, Any]) -> list[str]:
    return [c for c in _changes(a, b) if not c.startswith(BOOKKEEPING) and not fork_key(c)]


@dataclass
class Parent:
    """One group's parent run (as a Point) and the checkpoint k its forks start from."""

    point: Point
    k: int
    h: float
    members: list[Point] = field(default_factory=list)
    law: str = ""
    resolved: dict[str, Any] = field(default_factory=dict, repr=False)

    @property
    def id(self) -> str:
        return self.point.id

    @property
    def t(self) -> float:
        return self.k * self.h


@dataclass
class ForkPlan:
    """The parents and, per point, its parent and its fork's ``--set`` (without the run id)."""

    at: float
    parents: list[Parent]
    parent_of: dict[str, Parent]
    fork_sets: dict[str, list[str]]

    def parent_dir(self, out: Path, parent: Parent) -> Path:
        return out / "parents" / parent.id

    def spec(self, out: Path, p: Point) -> str:
        parent = self.parent_of[p.id]
        return f"{self.parent_dir(out, parent)}@{parent.t!r}"


def parse_fork_at(value: Any) -> float | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float) or \
            not math.isfinite(value) or value <= 0:
        raise SweepError(f"[sweep] fork_at = {value!r}: a time in seconds > 0 (the points fork "
                         "from their parent's checkpoint at that time)")
    return float(value)


def _parent_overrides(sweep: Sweep, member: Point) -> dict[str, Any]:
    """The member's overrides without the axes' fork-changeable ones (``[sweep.set]``'s stay)."""
    fixed = _absolute_paths(sweep.fixed, sweep.path.resolve().parent)
    return {k: fixed[k] if fork_key(k) else v for k, v in member.overrides.items()
            if not fork_key(k) or k in fixed}


def _fork_sets(point: dict[str, Any], parent: dict[str, Any]) -> list[str]:
    """The fork's ``--set``: every key a fork may change as the point has it, but id/folder."""
    sets: list[str] = []
    for key in FORK_MAY_CHANGE:
        if key.startswith(BOOKKEEPING):
            continue
        value = _get(point, key)
        if value is not None:
            sets.append(f"{key}={toml_value(value)}")
    # run.checkpoint_every_s: the point's own (a parent's T is not the point's)
    if _get(point, "run.checkpoint_every_s") is None:
        sets.append("run.checkpoint_every_s=0.0")
    source = parent["run"].get("t_end_source")
    if source is not None:  # orchestrator.resume pops it, then refuses it as a change: kept
        sets.append(f"run.t_end_source={toml_value(source)}")
    return sets


def _simulated_fork(parent: dict[str, Any], sets: list[str], out: Path) -> dict[str, Any]:
    """What :func:`orchestrator.resume.fork_scenario` resolves for a fork of ``parent``."""
    from ..runner import resolve

    child = copy.deepcopy(parent)
    for key in sc.RESOLVED_RUN_KEYS:
        child["run"].pop(key, None)
    child["run"]["id"] = ""
    for assignment in sets:
        sc.apply_override(child, assignment)
    return resolve(sc.validate_common(child), out)


def plan_forks(sweep: Sweep, out: Path, resolved: dict[str, dict[str, Any]]) -> ForkPlan:
    """Group the points under parents and check every fork; SweepError (exit 2) else."""
    from ..runner import resolve

    at = sweep.fork_at
    assert at is not None
    groups: list[list[Point]] = []
    for p in sweep.points:
        for g in groups:
            if not _only_fork_changes(resolved[g[0].id], resolved[p.id]):
                g.append(p)
                break
        else:
            groups.append([p])
    parents: list[Parent] = []
    parent_of: dict[str, Parent] = {}
    fork_sets: dict[str, list[str]] = {}
    ids: set[str] = set()
    for g in groups:
        first = g[0]
        # the id: the sweep name, "parent" and the labels of the axes that set something a
        # fork may not change for this group (e.g. the road)
        labels = ["parent"] + [first.params[a.name] for a in sweep.axes
                               if a.bases is not None or any(
                                   not fork_key(k) for k in a.overrides[a.labels.index(
                                       first.params[a.name])])]
        pid = point_id(sweep.name, labels)
        if pid in ids:
            pid = point_id(sweep.name, [*labels, len(parents)])
        ids.add(pid)
        overrides = _parent_overrides(sweep, first)
        run_h = float(resolved[first.id]["run"]["h"])
        n = int(resolved[first.id]["run"]["n_steps"])
        where = f"[sweep] fork_at = {at:g} s (point '{first.id}', h = {run_h:g} s, " \
                f"t_end = {n * run_h:g} s)"
        try:
            checkpoint_steps(at, run_h, 0)  # the check of run.checkpoint_every_s
        except ValueError:
            raise SweepError(f"{where}: not a whole number of steps of h = {run_h:g} s: the "
                             "points fork from a checkpoint at a step boundary") from None
        k = round(at / run_h)
        if k >= n:
            raise SweepError(f"{where}: not before the end of the run: a fork at or after "
                             "t_end simulates nothing")
        overrides["run.checkpoint_every_s"] = at
        ppoint = Point(-1, pid, {"parent of": len(g)}, first.base, overrides)
        try:
            loaded = sc.load(ppoint.base, ppoint.fingerprint_args)
            ppoint.fingerprint = fingerprint(loaded)
            presolved = resolve(copy.deepcopy(loaded), out / "parents" / pid)
        except SuscosimError as exc:
            raise SweepError(f"{where}: the parent run {pid} (the base's controller, "
                             f"{len(g)} point(s)): {exc}") from None
        ppoint.n_steps = int(presolved["run"]["n_steps"])
        bad = _only_fork_changes(presolved, resolved[first.id])
        if bad:
            raise SweepError(f"{where}: the parent run {pid} (the base's controller) differs "
                             f"from its points in {bad[0]}, which a fork cannot change: a "
                             "controller that changes it cannot be forked to")
        law = str((presolved.get("controller") or {}).get("law", "?"))
        parent = Parent(ppoint, k, run_h, list(g), law, presolved)
        parents.append(parent)
        for p in g:
            sets = _fork_sets(resolved[p.id], presolved)
            try:
                child = _simulated_fork(presolved, sets, out / "runs" / p.id)
            except SuscosimError as exc:
                raise SweepError(f"sweep point '{p.id}': its fork of {pid} at t = "
                                 f"{parent.t:g} s: {exc}") from None
            bad = _only_fork_changes(presolved, child)
            differs = [c for c in _changes(resolved[p.id], child)
                       if not c.startswith(("run.id", "run.dir", "run.checkpoint_every_s",
                                            "run.t_end_source", "run.resume"))]
            if bad or differs:
                raise SweepError(f"sweep point '{p.id}': {where}: its fork of {pid} would "
                                 f"not run its scenario ({(bad or differs)[0]} differs)")
            p.fingerprint = fingerprint([p.fingerprint, at, ppoint.fingerprint])
            parent_of[p.id] = parent
            fork_sets[p.id] = sets
    return ForkPlan(at, parents, parent_of, fork_sets)


def parent_state(parent: Parent, run_dir: Path) -> str:
    """``done`` (an ok run of this parent with its checkpoint at k) or ``todo``."""
    done = run_ok(run_dir, parent.point.fingerprint) and \
        (step_folder(run_dir, parent.k) / MANIFEST).is_file()
    return "done" if done else "todo"


def keep_only_fork_checkpoint(parent: Parent, run_dir: Path) -> None:
    keep = step_folder(run_dir, parent.k).name
    root = run_dir / CHECKPOINTS_DIR
    for sub in sorted(root.glob("k*")) if root.is_dir() else []:
        if sub.is_dir() and sub.name != keep:
            shutil.rmtree(sub, ignore_errors=True)


def _wall(run_dir: Path) -> float | None:
    s = read_json(run_dir / "summary.json")
    if isinstance(s, dict) and s.get("status") == "ok" and isinstance(s.get("wall_s"), int | float):
        return float(s["wall_s"])
    return None


def fork_report(sweep: Sweep, plan: ForkPlan, out: Path) -> dict[str, Any]:
    """``fork.json``: the semantics, the parents, the steps and wall time saved."""
    plain = simulated = prefix = n_ok = 0
    parents_doc = []
    wall_parents = wall_forks = wall_plain = 0.0
    wall_ok = True
    for parent in plan.parents:
        n, k = parent.point.n_steps, parent.k
        pdir = plan.parent_dir(out, parent)
        pw = _wall(pdir)
        simulated += n
        for p in parent.members:
            plain += p.n_steps
            simulated += p.n_steps - k
            prefix += k
            fw = _wall(sweep.run_dir(out, p))
            n_ok += fw is not None
            if pw is None or fw is None:
                wall_ok = False
            else:
                wall_forks += fw
                wall_plain += pw * p.n_steps / max(1, n)
        wall_parents += pw or 0.0
        parents_doc.append({"id": parent.id, "run_dir": f"parents/{parent.id}",
                            "controller": parent.law, "k": k, "t": parent.t, "n_steps": n,
                            "wall_s": pw, "points": [p.id for p in parent.members]})
    saved = plain - simulated
    doc: dict[str, Any] = {
        "fork_at": plan.at, "semantics": SEMANTICS,
        "parents": parents_doc, "points": sum(len(pa.members) for pa in plan.parents),
        "points_ok": n_ok, "steps": {"plain": plain, "simulated": simulated,
                  "prefix_not_simulated_again": prefix,
                  "prefix_share": prefix / plain if plain else 0.0,
                  "saved": saved, "saved_share": saved / plain if plain else 0.0,
                  "how": "plain: the sum of the points' n_steps (each run from t = 0); "
                         "simulated: the parents' n_steps plus each fork's n_steps - k; "
                         "saved = plain - simulated (the parents' own runs counted)"},
    }
    if wall_ok:
        actual = wall_parents + wall_forks
        doc["wall_s"] = {"parents": wall_parents, "forks": wall_forks, "total": actual,
                         "plain_estimate": wall_plain, "saved_estimate": wall_plain - actual,
                         "how": "the runs' summary.json wall_s (summed, not elapsed: runs "
                                "go side by side); plain_estimate: each point's plain run "
                                "taken as long as its parent's (the same steps from t = 0; "
                                "the laws' own costs aside)"}
    return doc


def fork_header(plan: ForkPlan) -> str:
    lines = [f"  fork_at = {plan.at:g} s: {len(plan.parents)} parent run(s) from t = 0 with "
             f"the base's controller, then every point forks at t = {plan.at:g} s: "
             "its own controller acts only from there on"]
    for parent in plan.parents:
        lines.append(f"    {parent.id}: {parent.law}, {parent.point.n_steps} steps, k = "
                     f"{parent.k}; {len(parent.members)} fork(s)"
                     + (" (one point: forking costs n - k steps more than a plain run)"
                        if len(parent.members) == 1 else ""))
    return "\n".join(lines)


def fork_text(doc: dict[str, Any]) -> str:
    st = doc["steps"]
    planned = "" if doc["points_ok"] == doc["points"] else \
        f" [as planned: {doc['points'] - doc['points_ok']} of {doc['points']} forks not ok]"
    text = (f"fork at t = {doc['fork_at']:g} s ({len(doc['parents'])} parent(s)){planned}: "
            f"{st['prefix_not_simulated_again']} prefix steps not simulated again "
            f"({100 * st['prefix_share']:.1f} % of {st['plain']}); net of the parents: "
            f"{st['simulated']} steps simulated instead of {st['plain']}, {st['saved']} saved "
            f"({100 * st['saved_share']:.1f} %)")
    w = doc.get("wall_s")
    if w:
        text += (f"; run wall {w['total']:.1f} s (parents {w['parents']:.1f} s + forks "
                 f"{w['forks']:.1f} s) against about {w['plain_estimate']:.1f} s for plain "
                 f"runs (estimated), {w['saved_estimate']:.1f} s saved")
    return text + f"\n  semantics: {doc['semantics']}"
