"""``suscosim duty DUTY.toml``: damage and life of the lower arm over a proving-ground schedule
(docs/data_formats.md "duty cycles"). Each ``[[events]]`` entry is a scenario (run once into
``<out>/runs/<event>``, reused unless ``--rerun``) or a finished run folder, with ``repeats`` or
``distance_km`` per schedule; ``[[laws]]`` run every event under each damper law
(``runs/<law>/<event>``, ``laws/<law>/``; the first is the reference, also in ``<out>/``) and
compare them at the reference's critical node (``laws.csv``). Exit 2 for a bad duty file (key
named), 1 if a run fails.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from cosim.config import ConfigReader
from cosim.errors import InputFileError, ScenarioError, SuscosimError
from cosim.keys import check_name
from cosim.run_folder import read_json, replaced
from cosim.safe_open import open_user_text, read_user_text, read_user_toml

from .cli_util import fail, num

DUTY_KEYS = ("name", "out", "survival_probability", "log10_std", "scatter_band")
EVENT_KEYS = ("name", "scenario", "run", "set", "repeats", "distance_km")
LAW_KEYS = ("name", "set")
SAME_CONFIG_SKIP = ("track_length_m", "repeats_basis_m", "block_samples", "live")
"""Fatigue keys that may differ between events (they do not change a pass's damage)."""
MAX_DUTY_NUMBER = 1e9  # largest repeats, distance [km] or scatter figure (a life: ~3e5 km)


def _number(v: Any, key: str, expected: str, lo: float = 0.0, lo_open: bool = False) -> float:
    ok = isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and \
        (v > lo if lo_open else v >= lo) and v <= MAX_DUTY_NUMBER
    if not ok:
        raise ScenarioError(key, v, f"{expected}, at most {MAX_DUTY_NUMBER:g}")
    return float(v)


def load_duty(path: str | Path) -> dict[str, Any]:
    """Read and validate a duty file; paths made absolute (relative to its folder)."""
    path = Path(path)
    data = read_user_toml(path, "scenario", "duty file")
    base = path.resolve().parent
    ConfigReader(data, "", ("duty", "events", "laws"))  # a typo: "did you mean"
    duty = data.get("duty", {})
    ConfigReader(duty, "duty", DUTY_KEYS)
    name = check_name("duty.name", duty.get("name", path.stem))  # names become folders
    out: dict[str, Any] = {"name": name, "file": str(path)}
    if "out" in duty:
        if not isinstance(duty["out"], str) or not duty["out"]:
            raise ScenarioError("duty.out", duty["out"], "a folder path")
        out["out"] = str(base / duty["out"])
    if "log10_std" in duty and "scatter_band" in duty:
        raise ScenarioError("duty.scatter_band", duty["scatter_band"],
                            "either log10_std or scatter_band, not both")
    from nodes.fatigue.lib.duty_cycle import log10_std_from_scatter_band

    if "log10_std" in duty:
        out["log10_std"] = _number(duty["log10_std"], "duty.log10_std",
                                   "a standard deviation of log10 N >= 0")
    elif "scatter_band" in duty:
        t_n = _number(duty["scatter_band"], "duty.scatter_band",
                      "a scatter band T_N = N10/N90 >= 1", lo=1.0)
        out["scatter_band"] = t_n
        out["log10_std"] = log10_std_from_scatter_band(t_n)
    if "survival_probability" in duty:
        p = duty["survival_probability"]
        _number(p, "duty.survival_probability", "a probability in (0, 1)", lo_open=True)
        if not p < 1:
            raise ScenarioError("duty.survival_probability", p, "a probability in (0, 1)")
        if "log10_std" not in out:
            raise ScenarioError("duty.log10_std", None, "the S-N scatter (log10_std or "
                                "scatter_band) for a survival_probability")
        out["survival_probability"] = float(p)
    elif "log10_std" in out:
        out["survival_probability"] = 0.9
    events = data.get("events")
    if not isinstance(events, list) or not events:
        raise ScenarioError("events", events, "a non-empty list of [[events]] tables")
    seen: set[str] = set()
    out["events"] = []
    for i, ev in enumerate(events):
        q = f"events[{i}]"
        ConfigReader(ev, q, EVENT_KEYS)
        if ("scenario" in ev) == ("run" in ev):
            raise ScenarioError(f"{q}.scenario", ev.get("scenario"),
                                "either scenario (a TOML to run) or run (a run folder)")
        src_key = "scenario" if "scenario" in ev else "run"
        src = ev[src_key]
        if not isinstance(src, str) or not src:
            raise ScenarioError(f"{q}.{src_key}", src, "a path")
        src_path = base / src
        if src_key == "scenario" and not src_path.is_file():
            raise InputFileError(str(src_path), f"{q}.scenario: scenario file not found")
        if src_key == "run" and not src_path.is_dir():
            raise InputFileError(str(src_path), f"{q}.run: run folder not found")
        name_e = ev.get("name", src_path.resolve().stem or f"event{i}")
        check_name(f"{q}.name", name_e)
        if name_e in seen:
            raise ScenarioError(f"{q}.name", name_e, "a unique event name")
        seen.add(name_e)
        sets = _sets(ev, q)
        if sets and src_key == "run":
            raise ScenarioError(f"{q}.set", sets, "no overrides for a finished run")
        if ("repeats" in ev) == ("distance_km" in ev):
            raise ScenarioError(f"{q}.repeats", ev.get("repeats"),
                                "either repeats (passes per schedule) or distance_km")
        e: dict[str, Any] = {"name": name_e, src_key: str(src_path), "set": sets}
        if "repeats" in ev:
            e["repeats"] = _number(ev["repeats"], f"{q}.repeats", "a number of passes >= 0")
        else:
            e["distance_km"] = _number(ev["distance_km"], f"{q}.distance_km",
                                       "a distance > 0 (km)", lo_open=True)
        out["events"].append(e)
    if "laws" in data:
        out["laws"] = _load_laws(data["laws"], out["events"])
    return out


def _sets(table: dict[str, Any], q: str) -> list[str]:
    sets = table.get("set", [])
    if not isinstance(sets, list) or not all(isinstance(s, str) for s in sets):
        raise ScenarioError(f"{q}.set", sets, "a list of 'KEY=VALUE' strings")
    return sets


def _load_laws(laws: Any, events: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The ``[[laws]]`` tables; every event must be a scenario (a run cannot run again)."""
    if not isinstance(laws, list) or not laws:
        raise ScenarioError("laws", laws, "a non-empty list of [[laws]] tables")
    for i, ev in enumerate(events):
        if "run" in ev:
            raise ScenarioError(f"events[{i}].run", ev["run"], "a scenario (with [[laws]] "
                                "every event is run under each law)")
    out: list[dict[str, Any]] = []
    for i, law in enumerate(laws):
        q = f"laws[{i}]"
        ConfigReader(law, q, LAW_KEYS)
        name = law.get("name")
        if check_name(f"{q}.name", name) in {x["name"] for x in out}:
            raise ScenarioError(f"{q}.name", name, "a unique law name")
        out.append({"name": name, "set": _sets(law, q)})
    return out


def _run_event(ev: dict[str, Any], folder: Path, mode: str | None, rerun: bool,
               sets: Sequence[str] = (), law_sets: Sequence[str] = ()) -> Path:
    """Run a scenario event into ``folder`` (a finished one reused unless ``rerun``)."""
    done = read_json(folder / "summary.json")
    if not rerun and isinstance(done, dict) and done.get("status") == "ok" and \
            (folder / "fatigue" / "damage_per_node.csv").is_file():
        return folder
    from cosim import scenario as sc

    from .runner import resolve, run_scenario

    overrides = list(sets) + list(ev["set"]) + list(law_sets) + \
        ([f'run.mode="{mode}"'] if mode else [])
    scenario = resolve(sc.load(ev["scenario"], overrides), folder)
    print(f"suscosim duty: event {ev['name']}: run {scenario['run']['id']} -> {folder}",
          flush=True)
    run_scenario(scenario, quiet=True)
    return folder


def _event_fatigue(run_dir: Path, batch_into: Path) -> dict[str, Any]:
    """A run folder's ``fatigue/`` results (when absent: computed into ``batch_into``)."""
    fat = run_dir / "fatigue"
    if not (fat / "damage_per_node.csv").is_file() or not (fat / "summary.json").is_file():
        from nodes.fatigue.run_dir import fatigue_run_dir

        fatigue_run_dir(run_dir, out=batch_into)
        run_dir = fat = batch_into
    try:
        summary = json.loads(read_user_text(fat / "summary.json", "scenario", inside=run_dir))
        with open_user_text(fat / "damage_per_node.csv", "influence", inside=run_dir) as fh:
            rows = list(csv.DictReader(fh))
        ids = [int(r["node_id"]) for r in rows]
        damage = [float(r["damage_per_pass"]) for r in rows]
        xyz = [[float(r[k]) for k in ("x_m", "y_m", "z_m")] for r in rows]
    except (OSError, json.JSONDecodeError, KeyError, ValueError) as exc:
        raise InputFileError(str(fat), f"fatigue results not readable ({exc})") from None
    return {"summary": summary, "ids": ids, "damage": damage, "xyz": xyz}


def _same_config(a: dict, b: dict) -> bool:
    strip = lambda c: {k: v for k, v in c.items() if k not in SAME_CONFIG_SKIP}  # noqa: E731
    return strip(a) == strip(b)


def run_duty(duty: dict[str, Any], out: Path, mode: str | None = None,
             rerun: bool = False, sets: Sequence[str] = ()) -> dict[str, Any]:
    """Run/collect every event (under every law), sum the damage, write ``out/``."""
    laws = duty.get("laws")
    if not laws:
        return _schedule(duty, out, out / "runs", mode, rerun, sets)[0]
    done = [(law["name"], *_schedule(duty, out / "laws" / law["name"],
                                     out / "runs" / law["name"], mode, rerun, sets,
                                     law["set"])) for law in laws]
    result, res, first = done[0][1:]
    result = {**result, "laws": _compare_laws(done, first)}
    _write(out, result, res, first)
    _write_laws(out, result["laws"])
    return result


def _compare_laws(done: list, first: dict) -> dict[str, Any]:
    """duty.json's ``laws``: each law's damages at the reference's critical node, ratios."""
    from nodes.fatigue.lib.duty_cycle import law_matrix

    for name, _, _, fat in done[1:]:
        if fat["ids"] != first["ids"]:
            raise InputFileError(name, "this law's runs have other nodes than the first law's")
    try:
        c, D = law_matrix([r for _, _, r, _ in done])
    except ValueError as exc:
        raise ScenarioError("laws", [n for n, *_ in done], str(exc)) from None
    ref = D[0]
    names = done[0][2].names
    return {
        "reference": done[0][0], "node_id": int(first["ids"][c]), "events": names,
        "laws": [{
            "name": n, "damage_per_schedule_at_node": [float(x) for x in D[i]],
            "ratio_to_reference": [float(x / y) if y > 0 else (1.0 if x == 0 else "inf")
                                   for x, y in zip(D[i], ref, strict=True)],
            "max_damage_per_pass": [float(e["max_damage_per_pass"]) for e in r["events"]],
            "damage_per_schedule_at_node_total": float(D[i].sum()),
            "max_damage_per_schedule": r["max_damage_per_schedule"],
            "critical_node_id": r["critical_node_id"], "life_schedules": r["life_schedules"],
            "life_km": r["life_km"], "dominant_event": r["dominant_event"],
            "dominant_share": r["dominant_share"],
        } for i, (n, r, _, _) in enumerate(done)]}


def _write_laws(out: Path, laws: dict[str, Any]) -> None:
    with replaced(out / "laws.csv", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["law", "event", "max_damage_per_pass", "damage_per_schedule_at_node",
                    "node_id", "ratio_to_reference"])
        for law in laws["laws"]:
            for j, ev in enumerate(laws["events"]):
                w.writerow([law["name"], ev, law["max_damage_per_pass"][j],
                            law["damage_per_schedule_at_node"][j], laws["node_id"],
                            law["ratio_to_reference"][j]])


def _schedule(duty: dict[str, Any], out: Path, runs: Path, mode: str | None, rerun: bool,
              sets: Sequence[str], law_sets: Sequence[str] = ()) -> tuple[dict, Any, dict]:
    """One schedule into ``runs/<event>`` and ``out/``: (duty.json, DutyResult, first fatigue)."""
    import numpy as np

    from nodes.fatigue.lib.duty_cycle import Event, life_factor, schedule_damage

    out.mkdir(parents=True, exist_ok=True)
    infos: list[dict[str, Any]] = []  # name, run_dir, fat (_event_fatigue) per event
    events: list[Event] = []
    for ev in duty["events"]:
        run_dir = Path(ev["run"]) if "run" in ev else \
            _run_event(ev, runs / ev["name"], mode, rerun, sets, law_sets)
        fat = _event_fatigue(run_dir, runs / ev["name"] / "fatigue")
        length = float(fat["summary"]["track_length_m"])
        if not (length > 0 and math.isfinite(length)):
            raise InputFileError(str(run_dir / "fatigue" / "summary.json"),
                                 f"track_length_m {length!r}: a pass length > 0 is needed")
        if infos:
            first = infos[0]
            if fat["ids"] != first["fat"]["ids"]:
                raise InputFileError(str(run_dir / "fatigue"), f"event {ev['name']!r} has "
                                     f"other nodes than {first['name']!r}")
            if not _same_config(fat["summary"]["config"], first["fat"]["summary"]["config"]):
                raise InputFileError(str(run_dir / "fatigue"), f"event {ev['name']!r} has other "
                                     f"fatigue settings than {first['name']!r}")
        repeats = ev["repeats"] if "repeats" in ev else ev["distance_km"] * 1000.0 / length
        infos.append({"name": ev["name"], "run_dir": str(run_dir), "fat": fat})
        events.append(Event(ev["name"], np.asarray(fat["damage"]), length, repeats))
    try:
        res = schedule_damage(events)
    except ValueError as exc:
        raise ScenarioError("events", duty["file"], str(exc)) from None
    c = res.critical
    shares = res.shares()
    first = infos[0]["fat"]

    def num(x: float) -> float | str:
        return x if math.isfinite(x) else "inf"

    result: dict[str, Any] = {
        "name": duty["name"], "duty_file": duty["file"],
        "events": [{
            "name": e.name, "run_dir": info["run_dir"], "repeats": e.repeats,
            "pass_length_m": e.length_m, "distance_km": e.repeats * e.length_m / 1000.0,
            "max_damage_per_pass": float(e.damage.max()),
            "own_critical_node_id": int(first["ids"][int(np.argmax(e.damage))]),
            "damage_per_pass_at_critical": float(e.damage[c]),
            "damage_per_schedule_at_critical": float(res.per_event[i, c]),
            "share_at_critical": float(shares[i]),
        } for i, (e, info) in enumerate(zip(events, infos, strict=True))],
        "schedule_distance_km": res.distance_m / 1000.0,
        "max_damage_per_schedule": res.max_damage,
        "critical_node_id": int(first["ids"][c]),
        "critical_node_xyz_m": first["xyz"][c],
        "life_schedules": num(res.life_schedules),
        "life_km": num(res.life_km),
        "dominant_event": res.names[res.dominant],
        "dominant_share": float(shares[res.dominant]),
        "fatigue_config": first["summary"]["config"],
    }
    if "log10_std" in duty:
        reliability = (first["summary"]["config"].get("component") or {}).get("reliability",
                                                                              0.5)
        if reliability != 0.5:
            raise ScenarioError("duty.survival_probability", duty["survival_probability"],
                                f"events on the median S-N curve (their fatigue.component."
                                f"reliability is {reliability}, not 0.5)")
        f = life_factor(duty["survival_probability"], duty["log10_std"])
        result["certainty"] = {
            "survival_probability": duty["survival_probability"],
            "log10_std": duty["log10_std"], "scatter_band": duty.get("scatter_band"),
            "life_factor": f, "life_schedules": num(res.life_schedules * f),
            "life_km": num(res.life_km * f),
        }
    _write(out, result, res, first)
    return result, res, first


def _write(out: Path, result: dict, res, first: dict) -> None:
    with replaced(out / "duty.json") as fh:
        fh.write(json.dumps(result, indent=2) + "\n")
    with replaced(out / "events.csv", newline="") as fh:
        w = csv.writer(fh)
        cols = ["name", "repeats", "pass_length_m", "distance_km", "max_damage_per_pass",
                "own_critical_node_id", "damage_per_schedule_at_critical", "share_at_critical",
                "run_dir"]
        w.writerow(cols)
        for e in result["events"]:
            w.writerow([e[k] for k in cols])
    with replaced(out / "damage_per_node.csv", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["node_id", "x_m", "y_m", "z_m", *(f"damage_{n}" for n in res.names),
                    "damage_per_schedule", "life_schedules", "life_km"])
        for j, nid in enumerate(first["ids"]):
            d = float(res.total[j])
            life = 1.0 / d if d > 0 else math.inf
            w.writerow([nid, *first["xyz"][j], *(f"{v:.6e}" for v in res.per_event[:, j]),
                        f"{d:.6e}", f"{life:.6e}", f"{life * res.distance_m / 1000:.6e}"])


def _print(result: dict) -> None:
    print(f"duty {result['name']}: {len(result['events'])} events, "
          f"{result['schedule_distance_km']:.4g} km per schedule")
    print(f"  {'event':<16} {'repeats':>9} {'km':>9} {'D/pass max':>11} "
          f"{'D/schedule @crit':>17} {'share':>7}")
    for e in result["events"]:
        print(f"  {e['name']:<16} {e['repeats']:>9.4g} {e['distance_km']:>9.4g} "
              f"{e['max_damage_per_pass']:>11.3e} {e['damage_per_schedule_at_critical']:>17.3e} "
              f"{100 * e['share_at_critical']:>6.1f}%")
    print(f"  critical node {result['critical_node_id']}: D = "
          f"{result['max_damage_per_schedule']:.3e} per schedule, life "
          f"{num(result['life_schedules'])} schedules = {num(result['life_km'])} km; dominant "
          f"event {result['dominant_event']} "
          f"({100 * result['dominant_share']:.1f} %)")
    cert = result.get("certainty")
    if cert:
        print(f"  at {100 * cert['survival_probability']:g} % survival (s = "
              f"{cert['log10_std']:.3g} in log10 N): {num(cert['life_schedules'])} schedules = "
              f"{num(cert['life_km'])} km (x {cert['life_factor']:.3g})")
    laws = result.get("laws")
    if laws:
        names = [law["name"] for law in laws["laws"]]
        print(f"  damage per schedule at node {laws['node_id']} (the {laws['reference']} "
              f"schedule's critical node) by law; (x) = ratio to {laws['reference']}:")
        print(f"  {'event':<16} " + " ".join(f"{n:>26}" for n in names))
        for j, ev in enumerate(laws["events"]):
            cells = [f"{law['damage_per_schedule_at_node'][j]:.3e} "
                     f"(x{num(law['ratio_to_reference'][j], '.3g')})" for law in laws["laws"]]
            print(f"  {ev:<16} " + " ".join(f"{c:>26}" for c in cells))
        print(f"  {'life [km]':<16} " + " ".join(f"{num(law['life_km']):>26}"
                                                 for law in laws["laws"]))


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="suscosim duty", description=__doc__.splitlines()[0])
    p.add_argument("duty", metavar="DUTY.toml", type=Path)
    p.add_argument("--out", type=Path, help="results folder (default duty/<name>)")
    p.add_argument("--mode", choices=("distributed", "monolithic"),
                   help="mode of the scenario events' runs (default: their scenario's)")
    p.add_argument("--rerun", action="store_true",
                   help="run the scenario events again even if finished runs are there")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override a key of every scenario event (before the event's own set)")
    p.add_argument("--json", action="store_true", help="print duty.json instead of a table")
    args = p.parse_args(argv)
    try:
        duty = load_duty(args.duty)
        out = args.out or Path(duty.get("out") or Path("duty") / duty["name"])
        result = run_duty(duty, out, args.mode, args.rerun, args.set)
    except (SuscosimError, OSError) as exc:
        return fail("suscosim duty", str(exc), getattr(exc, "exit_code", 2))
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        _print(result)
        print(f"  results in {out}")
    return 0
