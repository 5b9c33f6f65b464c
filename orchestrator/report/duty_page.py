"""The duty-cycle page (``suscosim report duty/<name>``) from duty.json and damage_per_node.csv:
events and their shares of the critical node's damage, totals, certainty, laws, damage map."""

from __future__ import annotations

import csv
import datetime as _dt
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from cosim.safe_open import open_user_text, read_user_text

from .markup import cmd, esc, kv_table, nav, note, page, section, table_html
from .plots import fig_uri, img, new_figure
from .stream import BadInput


def _load(d: Path) -> tuple[dict[str, Any], dict[str, np.ndarray] | None, str]:
    try:
        duty = json.loads(read_user_text(d / "duty.json", "report", inside=d))
    except (OSError, ValueError) as exc:
        raise BadInput(f"{d / 'duty.json'}: not a duty result ({exc})") from None
    if not isinstance(duty, dict) or not isinstance(duty.get("events"), list):
        raise BadInput(f"{d / 'duty.json'}: not a duty result (no 'events' list)")
    path = d / "damage_per_node.csv"
    try:
        with open_user_text(path, "report", inside=d) as fh:
            rows = list(csv.reader(fh))
        head, body = rows[0], rows[1:]
        cols = {h: np.array([float(r[i]) for r in body]) for i, h in enumerate(head)}
        for need in ("x_m", "y_m", "damage_per_schedule"):
            if need not in cols:
                return duty, None, f"{path}: no column {need!r}"
    except (OSError, IndexError, ValueError) as exc:
        return duty, None, f"{path}: unreadable ({exc})"
    return duty, cols, ""


def _life(v: Any) -> Any:
    return "∞" if v == "inf" or (isinstance(v, float) and math.isinf(v)) else v


def events_section(duty: dict[str, Any]) -> str:
    header = ["event", "repeats", "pass [m]", "km per schedule", "max damage per pass",
              "its own critical node", "damage per schedule at the critical node",
              "share at the critical node [%]", "source run"]
    rows = [[e.get("name"), e.get("repeats"), e.get("pass_length_m"), e.get("distance_km"),
             e.get("max_damage_per_pass"), e.get("own_critical_node_id"),
             e.get("damage_per_schedule_at_critical"),
             100.0 * float(e.get("share_at_critical", float("nan"))), e.get("run_dir")]
            for e in duty["events"]]
    body = table_html(header, rows)
    names = [str(e.get("name")) for e in duty["events"]]
    shares = [100.0 * float(e.get("share_at_critical", 0.0)) for e in duty["events"]]
    if names:
        fig, (ax,) = new_figure(1, width=7.5, row_h=0.45 * len(names) + 1.4)
        ax.barh(names[::-1], shares[::-1], color="#4472c4")
        ax.set_xlabel(f"share of the damage at node {duty.get('critical_node_id')} [%]")
        ax.set_xlim(0, 100)
        for y, v in enumerate(shares[::-1]):
            ax.text(min(v + 1.0, 88.0), y, f"{v:.1f} %", va="center", fontsize=8)
        body += img(fig_uri(fig), "each event's share of the critical node's damage")
    return section("events", "Events", body)


def laws_section(duty: dict[str, Any]) -> str:
    """The schedule under each damper law (duty.json's ``laws``), or ""."""
    laws = duty.get("laws")
    if not isinstance(laws, dict) or not laws.get("laws"):
        return ""
    names = [str(law.get("name")) for law in laws["laws"]]
    header = ["event", *(f"{n}: damage per schedule at node {laws.get('node_id')}"
                         for n in names), *(f"{n} / {laws.get('reference')}" for n in names[1:])]
    rows = []
    for j, ev in enumerate(laws.get("events", [])):
        d = [law["damage_per_schedule_at_node"][j] for law in laws["laws"]]
        r = [law["ratio_to_reference"][j] for law in laws["laws"][1:]]
        rows.append([ev, *d, *r])
    rows.append(["total at the node", *(law.get("damage_per_schedule_at_node_total")
                                        for law in laws["laws"]),
                 *(_ratio(law, laws["laws"][0]) for law in laws["laws"][1:])])
    body = note(f"Every event run under each law; the damages at one node, the "
                f"{esc(str(laws.get('reference')))} schedule's critical node "
                f"{esc(str(laws.get('node_id')))}, so that a ratio compares the same place.")
    body += table_html(header, rows)
    body += table_html(["law", "life [schedules]", "life [km]", "its critical node",
                        "dominant event"],
                       [[law.get("name"), _life(law.get("life_schedules")),
                         _life(law.get("life_km")), law.get("critical_node_id"),
                         f"{law.get('dominant_event')} "
                         f"({100.0 * float(law.get('dominant_share', 0.0)):.1f} %)"]
                        for law in laws["laws"]])
    return section("laws", "Damper laws", body)


def _ratio(law: dict[str, Any], ref: dict[str, Any]) -> Any:
    a, b = law.get("damage_per_schedule_at_node_total"), ref.get(
        "damage_per_schedule_at_node_total")
    return a / b if isinstance(a, float) and isinstance(b, float) and b > 0 else "?"


def totals_section(duty: dict[str, Any]) -> str:
    xyz = duty.get("critical_node_xyz_m") or []
    pos = ", ".join(f"{1e3 * float(v):.0f}" for v in xyz) if xyz else "?"
    pairs = [("km per schedule", duty.get("schedule_distance_km")),
             ("critical node", f"{duty.get('critical_node_id')} at ({pos}) mm, arm frame"),
             ("damage per schedule (max over nodes)", duty.get("max_damage_per_schedule")),
             ("life [schedules] (median S-N curve)", _life(duty.get("life_schedules"))),
             ("life [km]", _life(duty.get("life_km"))),
             ("dominant event", f"{duty.get('dominant_event')} "
                                f"({100.0 * float(duty.get('dominant_share', 0.0)):.1f} %)")]
    cert = duty.get("certainty")
    body = kv_table(pairs)
    if isinstance(cert, dict):
        p = 100.0 * float(cert.get("survival_probability", float("nan")))
        band = cert.get("scatter_band")
        spread = f"s = {cert.get('log10_std'):.4g} (std of log10 N)" + \
            (f", scatter band T_N = {band}" if band else "")
        body += kv_table([(f"life at {p:.4g} % survival [schedules]",
                           _life(cert.get("life_schedules"))),
                          (f"life at {p:.4g} % survival [km]", _life(cert.get("life_km"))),
                          ("life factor (life_P / life_50)", cert.get("life_factor")),
                          ("S-N scatter", spread)], title="Certainty of survival")
    else:
        body += note("no S-N scatter given in the duty file: the lives are median lives.")
    return section("totals", "Totals", body)


def map_section(duty: dict[str, Any], cols: dict[str, np.ndarray] | None, problem: str) -> str:
    """The damage of one schedule, drawn by nodes/fatigue/map_render.py."""
    if cols is None:
        return section("map", "Damage map", note(esc(problem or "no damage_per_node.csv")))
    d = cols["damage_per_schedule"]
    if not np.any(d > 0) or "z_m" not in cols:
        return section("map", "Damage map", note("no damage in this schedule" if "z_m" in cols
                                                 else "damage_per_node.csv has no z_m"))
    from matplotlib.figure import Figure

    from cosim import lower_arm as geo
    from nodes.fatigue.map_render import draw

    fig = Figure(figsize=(12, 5.2))
    xyz = np.column_stack([cols["x_m"], cols["y_m"], cols["z_m"]])
    ids = cols["node_id"].astype(int) if "node_id" in cols else None
    draw(fig, xyz, d, node_ids=ids, hardpoints=geo.HARDPOINTS, label="damage per schedule")
    fig.suptitle("lower arm: damage of one schedule (all events)")
    return section("map", "Damage map", img(fig_uri(fig), "damage map of one schedule"))


def render_duty(d: Path) -> str:
    duty, cols, problem = _load(d)
    name = str(duty.get("name") or d.name)
    head = [f"<h1>Duty cycle {esc(name)}</h1>",
            f'<p class="meta">folder {cmd(str(d.resolve()))} · duty file '
            f"{cmd(str(duty.get('duty_file')))} · report written "
            f"{esc(_dt.datetime.now().strftime('%Y-%m-%d %H:%M:%S'))}</p>"]
    navs = [("totals", "Totals"), ("events", "Events"), ("map", "Damage map")]
    try:  # duty.json is a handed file: a value of the wrong type is its named error
        laws = laws_section(duty)
        sections = totals_section(duty) + events_section(duty) + laws
        sections += map_section(duty, cols, problem)
    except (TypeError, ValueError, KeyError, AttributeError) as exc:
        raise BadInput(f"{d / 'duty.json'}: not a duty result (a value of the wrong type: "
                       f"{type(exc).__name__}: {exc})") from None
    if laws:
        navs.insert(2, ("laws", "Damper laws"))
    body = "".join(head) + nav(navs) + sections
    return page(f"suscosim duty {name}", body)
