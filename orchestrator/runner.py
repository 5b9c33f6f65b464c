"""Run one scenario: resolve it, start the nodes, run the clock, write the run folder
(``scenario.json`` as resolved, ``journal.msgpack``, ``table.csv``/``.parquet``,
``summary.json``, ``logs/``). ``run.mode``: ``distributed`` (a process per node on Zenoh,
embedded peers on loopback or through ``--connect``'s router); ``monolithic`` (= ``run.transport
= "inprocess"``: the node models stepped in one thread, no bus, :mod:`orchestrator.inprocess`,
tables bit-identical to the distributed run's); ``reference`` (the lumped model by SciPy
``solve_ivp`` at tight tolerance).
"""

from __future__ import annotations

import datetime as _dt
import errno
import json
import math
import os
import secrets
import sys
import time
from contextlib import suppress
from pathlib import Path
from typing import Any, NoReturn

from cosim import auth as au
from cosim import channels as ch
from cosim import node_kinds as nk
from cosim import run_folder
from cosim import scenario as sc
from cosim.bus import free_loopback_endpoint
from cosim.errors import InputFileError, RunError, ScenarioError, SuscosimError
from cosim.run_lock import RunLock
from cosim.table_batches import warm_pyarrow

from . import run_modes
from .clock import Clock, ClockResult, NodeStatus
from .local_nodes import LocalNodes
from .progress import ProgressBar
from .run_recovery import recover_table


def new_run_id(name: str) -> str:
    stamp = _dt.datetime.now().strftime("%Y%m%d-%H%M%S")
    return f"{name}-{stamp}-{secrets.token_hex(2)}"


def resolve(scenario: dict[str, Any], out: str | Path | None = None) -> dict[str, Any]:
    """Preflight every node kind's check (the registry, :mod:`cosim.node_kinds`: the model
    sections, the implementations ``[nodes]`` picks) and fill the derived run keys (id, dir,
    t_end, N, the run's nodes)."""
    run = scenario["run"]
    nodes, facts = nk.run_preflight(scenario)
    duration = facts.get("duration_s")
    if run["t_end"] == 0:
        if duration is None:
            raise ScenarioError("run.t_end", 0, "a duration > 0 s (or a road with length_m "
                                "and speed_kmh to derive it from)")
        run["t_end"], run["t_end_source"] = float(duration), "road length / speed"
    if run.get("adaptive"):
        if run["exchange"] != "sequential":
            raise ScenarioError("run.exchange", run["exchange"], "\"sequential\" with run.h "
                                "= \"auto\" (the step is chosen from the last step's "
                                "residual, which the parallel exchange has a step late)")
        if run.get("checkpoint_every_s"):
            raise ScenarioError("run.checkpoint_every_s", run["checkpoint_every_s"],
                                "0 with run.h = \"auto\" (checkpoints fall on fixed steps)")
    run["n_steps"] = sc.n_steps(run["t_end"], run["h"])
    run["t_end"] = run["n_steps"] * run["h"]  # what is simulated: a whole number of steps
    if run.get("checkpoint_every_s"):  # a whole number of steps, else ScenarioError
        from cosim.checkpoint import checkpoint_steps

        try:
            checkpoint_steps(run["checkpoint_every_s"], run["h"], run["n_steps"])
        except ValueError as exc:
            raise ScenarioError("run.checkpoint_every_s", run["checkpoint_every_s"],
                                str(exc)) from None
    run["id"] = run["id"] or new_run_id(run["name"])
    run["dir"] = str(Path(out) if out else Path("runs") / run["id"])
    run["nodes"] = nodes
    if run["mode"] == "monolithic":  # what the one-process engine cannot run: said here
        from .inprocess import refusal

        refusal(scenario)
    return scenario


def _summary(scenario: dict[str, Any], result: ClockResult | None, wall_s: float,
             rec: dict[str, Any], status: str, error: str = "") -> dict[str, Any]:
    run = scenario["run"]
    n = run["n_steps"]
    if run.get("adaptive") and rec.get("rows"):  # N is known once the run got to t_end
        n = int(rec["rows"]) - 1
    return {
        "status": status, "error": error, "run_id": run["id"], "mode": run["mode"],
        "exchange": run["exchange"], "coupling": run["coupling"], "h": run["h"],
        "substeps": run["substeps"], "t_end": run["t_end"], "n_steps": n,
        "nodes": run["nodes"] if run["mode"] != "reference" else ["reference"],
        "wall_s": wall_s,
        "run_wall_s": result.run_wall_s if result else wall_s,
        "step_wall_s": result.step_wall_s if result else wall_s,
        "steps_per_s": (n / result.step_wall_s) if result and result.step_wall_s > 0 else
        (n / wall_s if status == "ok" and wall_s > 0 else 0.0),
        "rejected_messages": ({k: v.rejected for k, v in result.nodes.items()}
                              | {"orchestrator": result.rejected}) if result else {},
        "rows": rec.get("rows", 0), "files": _relative(rec.get("files", {}), run.get("dir", ".")),
        "channels": rec.get("stats", {}),
    } | ({"table_note": rec["note"]} if rec.get("note") else {}) \
      | _coupling_summary(scenario, rec, status) | _adaptive_summary(scenario, rec) \
      | _resume_summary(run)


def _relative(files: dict[str, str], folder: str) -> dict[str, str]:
    """The table files relative to the run folder (a handed folder names no local path)."""
    base = Path(folder).resolve()
    out = {}
    for kind, name in files.items():
        path = Path(name).resolve()
        out[kind] = str(path.relative_to(base)) if path.is_relative_to(base) else name
    return out


def _coupling_summary(scenario: dict[str, Any], rec: dict[str, Any],
                      status: str) -> dict[str, Any]:
    """``coupling_energy_residual`` of a finished co-simulated run's table, else nothing."""
    run = scenario["run"]
    parquet = (rec.get("files") or {}).get("parquet")
    if status != "ok" or run["mode"] == "reference" or not parquet:
        return {}
    from cosim.coupling_stream import summary_of_table_file

    try:  # by row groups (#32): the orchestrator's memory does not grow with the run
        res = summary_of_table_file(parquet, None if run.get("adaptive") else float(run["h"]),
                                    run["coupling"], run["exchange"])
    except (OSError, SuscosimError, KeyError, ValueError):
        return {}
    return {"coupling_energy_residual": res} if res else {}


def _resume_summary(run: dict[str, Any]) -> dict[str, Any]:
    """``resumed_from`` of a resumed or forked run (checkpoint, source folder, fresh nodes)."""
    res = run.get("resume")
    if not res:
        return {}
    return {"resumed_from": {"k": res["k"], "t": res["t"],
                             "run_dir": res.get("parent") or run["dir"],
                             "fork": bool(res.get("parent")), "fresh": list(res.get("fresh", []))}}


def _adaptive_summary(scenario: dict[str, Any], rec: dict[str, Any]) -> dict[str, Any]:
    """``adaptive_step`` of a ``run.h = "auto"`` run: its settings and the steps taken."""
    run = scenario["run"]
    parquet = (rec.get("files") or {}).get("parquet")
    if not run.get("adaptive"):
        return {}
    out: dict[str, Any] = {"h_min": run["h_min"], "h_max": run["h_max"], "h_tol": run["h_tol"]}
    if parquet:
        import numpy as np
        import pyarrow.parquet as pq

        from cosim.table_batches import numpy_column

        try:
            t = numpy_column(pq.ParquetFile(parquet).read(columns=["t"]).column("t"))
        except (OSError, KeyError, ValueError):
            return {"adaptive_step": out}
        if t.size > 1:
            h = np.diff(t)
            out.update(steps=int(h.size), h_mean=float(h.mean()), h_smallest=float(h.min()),
                       h_largest=float(h.max()),
                       fixed_steps_at_h_min=int(round((t[-1] - t[0]) / run["h_min"])))
    return {"adaptive_step": out}


def strict_json(obj: Any, key: str = "", nulled: list[str] | None = None) -> Any:
    """``obj`` with NaN/inf replaced by None, their dotted keys appended to ``nulled``."""
    if isinstance(obj, float) and not math.isfinite(obj):
        if nulled is not None:
            nulled.append(key)
        return None
    if isinstance(obj, dict):
        return {k: strict_json(v, f"{key}.{k}" if key else str(k), nulled) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [strict_json(v, f"{key}[{i}]", nulled) for i, v in enumerate(obj)]
    return obj


def write_summary(folder: Path, summary: dict[str, Any]) -> None:
    """Write ``summary.json`` as strict JSON (NaN null, listed in ``non_finite``), atomically."""
    nulled: list[str] = []
    clean = strict_json(summary, nulled=nulled)
    if nulled:
        summary["non_finite"] = clean["non_finite"] = nulled
        shown = ", ".join(nulled[:5]) + (f" and {len(nulled) - 5} more" if len(nulled) > 5 else "")
        print(f"suscosim: warning: {folder / 'summary.json'}: {len(nulled)} non-finite "
              f"value(s) written as null: {shown}", file=sys.stderr)
    text = json.dumps(clean, indent=2, sort_keys=True, allow_nan=False)
    path, tmp = folder / "summary.json", folder / ".summary.json.tmp"
    try:
        tmp.write_text(text)
        os.replace(tmp, path)
        run_folder.mark_run_ended(folder, str(summary.get("status", "ended")))
    except OSError as exc:
        with suppress(OSError):
            tmp.unlink(missing_ok=True)
        raise SummaryWriteError(path, exc) from None


class SummaryWriteError(RunError):
    """``summary.json`` could not be written (a full disk, an unwritable folder)."""

    def __init__(self, path: Path, exc: OSError) -> None:
        super().__init__(f"cannot write {path}: {exc.strerror or exc}"
                         + (" (the disk is full)" if exc.errno == errno.ENOSPC else ""))


def _folder_error(exc: OSError, folder: Path) -> InputFileError:
    full = " (the disk is full)" if exc.errno == errno.ENOSPC else ""
    return InputFileError(str(exc.filename or folder),
                          f"cannot write the run folder: {exc.strerror or exc}{full}")


def run_key_for(run: dict[str, Any], folder: Path, external: list[str]) -> bytes:
    """The run's key (:mod:`cosim.auth`) from ``SUSCOSIM_KEY[_FILE]``'s secret, the run
    folder's ``run.key`` (a resume), or a fresh one, written to ``run.key`` (0600) for nodes
    started elsewhere (their ``--key-file``) and for checkpoints (their MACs)."""
    secret = au.secret_from_env()
    if secret is None and (folder / au.KEY_FILE_NAME).is_file():
        secret = au.read_secret_file(folder / au.KEY_FILE_NAME)
    elif secret is None:
        secret = au.new_secret()
        if run.get("checkpoint_every_s") and not external:
            au.write_secret_file(folder / au.KEY_FILE_NAME, secret)
        if external:
            path = au.write_secret_file(folder / au.KEY_FILE_NAME, secret)
            print(f"suscosim: the run key of '{run['id']}' is in {path}: start the nodes "
                  f"{', '.join(external)} with --key-file {path} (or set "
                  f"{au.ENV_KEY_FILE} for the orchestrator and every node)", file=sys.stderr)
    return au.derive_run_key(secret, run["id"])


LOWLATENCY_DEFAULT = True
"""The local nodes' sessions use Zenoh's low-latency transport unless told (``--no-lowlatency``;
with ``--zenoh-config`` off unless ``--lowlatency``): 12-38 % more coupled steps/s than
universal. Safe since they link as an explicit mesh with gossip off (:mod:`.local_mesh`); with
gossip it wedged one start in ~700 (eclipse-zenoh/zenoh#2581 family, docs/cosim.md "A wedged
start"). The orchestrator's own session is always universal."""


def run_scenario(scenario: dict[str, Any], connect: list[str] | None = None,
                 external: list[str] | None = None, quiet: bool = False,
                 zenoh_config_file: str | None = None, listen: list[str] | None = None,
                 lowlatency: bool | None = None, pin_mode: str = "auto") -> dict[str, Any]:
    """Run a resolved scenario; write and return the summary. Raises SuscosimError on failure
    (after writing a ``failed`` summary). ``lowlatency`` None: :data:`LOWLATENCY_DEFAULT`;
    ``pin_mode``: :mod:`orchestrator.placement`. The run folder is locked
    (:class:`cosim.run_lock.RunLock`: a second run on it is exit 2)."""
    folder = Path(scenario["run"]["dir"])
    try:
        folder.mkdir(parents=True, exist_ok=True)
        lock = RunLock(folder)
    except OSError as exc:
        raise _folder_error(exc, folder) from None
    try:
        return _run_locked(scenario, connect, external, quiet, zenoh_config_file, listen,
                           lowlatency, pin_mode)
    finally:
        lock.release()


def _run_locked(scenario: dict[str, Any], connect: list[str] | None,
                external: list[str] | None, quiet: bool, zenoh_config_file: str | None,
                listen: list[str] | None, lowlatency: bool | None,
                pin_mode: str) -> dict[str, Any]:
    if lowlatency is None:  # a config file's run gossips: low-latency there only if asked
        lowlatency = LOWLATENCY_DEFAULT and not zenoh_config_file
    run = scenario["run"]
    folder = Path(run["dir"])
    bus_eps = run["mode"] == "distributed"  # the other modes open no Zenoh session
    if bus_eps:  # chosen here so that run.json can tell taps where to go
        # every node elsewhere behind a router (compose): the orchestrator is its client too
        as_client = bool(connect) and not listen and all(n in (external or [])
                                                         for n in run["nodes"])
        listen = [] if as_client else list(listen or [free_loopback_endpoint()])
    try:  # before any node or bus: an unwritable folder or a full disk ends it here
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "scenario.json").write_text(json.dumps(scenario, indent=2, sort_keys=True))
        if bus_eps:
            (folder / "logs").mkdir(exist_ok=True)
        run_folder.write_run_json(folder, run["id"], listen if bus_eps else [],
                                  connect if bus_eps else [], lowlatency)
        run_key = run_key_for(run, folder, [n for n in run["nodes"] if n in (external or [])]
                              if bus_eps else [])
    except OSError as exc:
        raise _folder_error(exc, folder) from None
    auth = au.RunKey(run_key, au.new_nonce())  # this instance of the run (issue #30 item 11)
    t0, started = time.monotonic(), time.time()
    if run["mode"] == "reference":
        from .reference import run_reference

        rec = run_reference(scenario, folder)
        summary = _summary(scenario, None, time.monotonic() - t0, rec, "ok")
        write_summary(folder, summary)
        return summary
    bar = ProgressBar(run["id"], quiet=quiet)
    if run["mode"] == "monolithic":
        return _run_inprocess(scenario, bar, started, t0)
    nodes = run_modes.distributed(run, folder, connect, external, listen or [], lowlatency,
                                  zenoh_config_file, pin_mode, run_key, as_client)
    warm_pyarrow()  # the coupling summary reads the table after the last step
    clock: Clock | None = None
    try:  # from here on every error path stops the nodes and closes the bus
        clock = Clock(nodes.bus, run["id"], list(run["nodes"]), scenario, on_progress=bar,
                      check_processes=nodes.dead, auth=auth, on_started=nodes.started)
        result = clock.run()
    except BaseException as exc:
        _fail(exc, scenario, nodes, clock, bar, external, started, t0, lowlatency)
    bar.close()
    nodes.stop()
    nodes.bus.close()
    rec = result.nodes[ch.RECORDER].result
    summary = _summary(scenario, result, time.monotonic() - t0, rec, "ok")
    summary.update(_transport(nodes.local, lowlatency))
    summary["sinks"] = _sink_lags(result)
    if ch.PLANT in result.nodes:  # the chain's wait for a sink beyond run.sink_window_s
        summary["sink_window_held_s"] = result.nodes[ch.PLANT].result.get("sink_held_s", 0.0)
    if ch.FATIGUE in result.nodes:  # the live fatigue node's headline (files in fatigue/)
        summary["fatigue"] = {k: v for k, v in result.nodes[ch.FATIGUE].result.items()
                              if k != "rejected"}
    write_summary(folder, summary)
    return summary


def _sink_lags(result: ClockResult) -> dict[str, dict[str, float]]:
    """Each sink's largest lag [steps] and its work after the chain's last step [s]."""
    ends = [st.done_at for n, st in result.nodes.items()
            if n in ch.COUPLED and st.done_at is not None]
    end = max(ends) if ends else None
    return {n: {"max_lag_steps": st.max_lag,
                "drain_s": max(0.0, st.done_at - end) if end and st.done_at else 0.0}
            for n, st in result.nodes.items() if n not in ch.COUPLED}


def _error_text(exc: BaseException) -> str:
    if isinstance(exc, KeyboardInterrupt):
        return "interrupted (Ctrl-C or SIGTERM)"
    return str(exc) or type(exc).__name__


def _raise_failure(exc: BaseException, unwritten: SummaryWriteError | None,
                   where: str) -> NoReturn:
    """Raise a failed run's error (``unwritten``, a full disk: both said)."""
    if unwritten is not None:
        if isinstance(exc, KeyboardInterrupt):
            print(f"suscosim: {unwritten}", file=sys.stderr)
            raise exc
        raise RunError(f"{_error_text(exc)}; and {unwritten}") from exc
    if not isinstance(exc, SuscosimError | KeyboardInterrupt):
        raise RunError(f"internal error in {where}: {type(exc).__name__}: {exc}") from exc
    raise exc


def _run_inprocess(scenario: dict[str, Any], bar: ProgressBar, started: float,
                   t0: float) -> dict[str, Any]:
    from .inprocess import Engine

    folder = Path(scenario["run"]["dir"])
    try:
        res = Engine(scenario, on_progress=bar).execute()
    except BaseException as exc:
        bar.close()
        unwritten = None
        try:
            rec = recover_table(folder, interrupted=isinstance(exc, KeyboardInterrupt),
                                since=started)
            write_summary(folder, _summary(scenario, None, time.monotonic() - t0, rec,
                                           "failed", _error_text(exc))
                          | {"transport": "inprocess"})
        except SummaryWriteError as werr:
            unwritten = werr
        _raise_failure(exc, unwritten, "the in-process engine")
    bar.close()
    nodes = {ch.RECORDER: NodeStatus(done=True, result=res.recorder)}
    if res.fatigue is not None:
        nodes[ch.FATIGUE] = NodeStatus(done=True, result=res.fatigue)
    wall = time.monotonic() - t0
    summary = _summary(scenario, ClockResult(nodes, wall, res.run_wall_s, res.step_wall_s),
                       wall, res.recorder, "ok") | {"transport": "inprocess"}
    chain = res.step_wall_s - res.sink_s  # the coupled chain alone: the sinks taken out
    summary["inprocess"] = {"sink_s": res.sink_s, "step_cpu_s": res.step_cpu_s,
                            "chain_steps_per_s": summary["n_steps"] / chain if chain > 0
                            else 0.0}
    if res.fatigue is not None:
        summary["fatigue"] = res.fatigue
    write_summary(folder, summary)
    return summary


def _fail(exc: BaseException, scenario: dict[str, Any], nodes: run_modes.Nodes,
          clock: Clock | None, bar: ProgressBar, external: list[str] | None, started: float,
          t0: float, lowlatency: bool) -> NoReturn:
    """A failed run: stop the nodes, close the bus, recover the table, write the summary."""
    folder = Path(scenario["run"]["dir"])
    if isinstance(exc, KeyboardInterrupt) and clock is not None:  # Ctrl-C or SIGTERM
        with suppress(Exception):
            clock.announce_abort("the orchestrator was interrupted")
    error = _error_text(exc)
    unwritten: SummaryWriteError | None = None
    bus_open = True
    try:
        bar.close()

        def say_abort() -> None:  # to a node that joined after it was first said
            if clock is not None:
                with suppress(Exception):
                    clock.announce_abort(error)

        nodes.stop(grace_s=3.0, tick=say_abort)
        say_abort()  # once more, the nodes stopped: then the bus is closed
        _close(nodes.bus)  # before the table: what follows is the run folder's, not the bus's
        bus_open = False
        elsewhere = (ch.RECORDER in (external or []) and clock is not None
                     and ch.RECORDER in clock.status and clock.status[ch.RECORDER].alive)
        rec = recover_table(folder, interrupted=isinstance(exc, KeyboardInterrupt),
                            since=started, recorder_elsewhere=elsewhere)
        summary = _summary(scenario, None, time.monotonic() - t0, rec, "failed", error)
        summary.update(_transport(nodes.local, lowlatency))
        write_summary(folder, summary)
        if rec.get("note") and (not rec.get("files") or "table.recovered" in rec["note"]):
            print(f"suscosim: {rec['note']}", file=sys.stderr)
    except SummaryWriteError as werr:  # a full disk: say both, still end promptly
        unwritten = werr
    finally:
        if bus_open:
            _close(nodes.bus)  # else the session's threads keep the orchestrator alive
    _raise_failure(exc, unwritten, "the orchestrator")


_close = run_modes.close_quietly


def _transport(local: LocalNodes | None, lowlatency: bool) -> dict[str, Any]:
    if local is None:
        return {}
    return {"lowlatency": bool(lowlatency), "cores": dict(local.cores),
            "background": list(local.background), "batch": list(local.batch),
            "zenoh_cores": dict(local.zenoh_cores),
            "background_starved": list(local.guard.moved)}

