"""The run page's fatigue section: the lower arm's life and damage from the fatigue folder's
``summary.json`` (results, most damaged nodes, the life under each S-N method, settings, the
damage map and the S-N plot), and with ``[fatigue] parts`` every part's life side by side and
each more part's damage map; :func:`fatigue_numbers` is the sweep page's too."""

from __future__ import annotations

import re
from typing import Any

from .markup import cmd, esc, flatten, fmt, is_num, kv_table, note, row, section, table_html
from .plots import file_uri, img
from .stream import RunData


def fatigue_numbers(fs: dict) -> list[tuple[str, Any]]:
    pairs: list[tuple[str, Any]] = []
    if fs.get("fails_first_cycle"):
        pairs.append(("verdict", "fails on the first cycle (life 0 km)"))
    rng = (fs.get("sn_methods") or {}).get("life_range_km")
    if isinstance(rng, list) and len(rng) == 2:
        pairs.append(("life range over the S-N methods and probabilities [km]", rng))
    elif fs.get("source") == "live":  # the live node computes the primary method only
        pairs.append(("life under both S-N methods (Shigley, FKM) at P50 / P97.5",
                      "not computed live: `suscosim fatigue RUN_DIR` adds them"))
    pairs += [
        ("minimum life [km]", fs.get("min_life_km")),
        ("minimum life from", life_from(fs.get("config") or {})),
        (f"minimum life [repeats of the {fmt(fs.get('track_length_m'))} m track]",
         fs.get("min_life_repeats")),
    ]
    if fs.get("min_life_repeats_basis") is not None:
        pairs.append((f"minimum life [repeats of {fmt(fs.get('repeats_basis_m'))} m]",
                      fs.get("min_life_repeats_basis")))
    xyz = fs.get("critical_node_xyz_m")
    pairs += [
        ("max damage per pass [-]", fs.get("max_damage_per_pass")),
        ("critical node", fs.get("critical_node_id")),
        ("critical node at [mm]",
         [1e3 * v for v in xyz] if isinstance(xyz, list) and all(map(is_num, xyz)) else xyz),
    ]
    if is_num(fs.get("critical_eq_range_max_pa")):
        pairs.append(("critical node: largest equivalent stress range [MPa]",
                      fs["critical_eq_range_max_pa"] / 1e6))
    if is_num(fs.get("eq_stress_max_pa")) and is_num(fs.get("eq_stress_min_pa")):
        pairs.append(("equivalent stress, max / min over the arm [MPa]",
                      [fs["eq_stress_max_pa"] / 1e6, fs["eq_stress_min_pa"] / 1e6]))
    if fs.get("source"):
        pairs.append(("computed", f"{fs['source']} (live: during the run; batch: "
                                  "suscosim fatigue)"))
    for k, lab in (("n_nodes", "nodes analysed"), ("n_samples", "samples"),
                   ("duration_s", "duration [s]"), ("track_length_m", "track length [m]")):
        if k in fs:
            pairs.append((lab, fs[k]))
    if fs.get("missing_channels"):
        pairs.append(("load channels missing (taken as 0)", fs["missing_channels"]))
    unmapped = [u.get("channel") for u in fs.get("unmapped_channels") or []
                if isinstance(u, dict) and u.get("peak_abs")]
    if unmapped:
        pairs.append(("loaded channels no influence case maps (not in the stresses)", unmapped))
    return pairs


MEAN_STRESS_NAMES = {"fkm": "FKM Haigh diagram", "goodman": "Goodman", "gerber": "Gerber",
                     "morrow": "Morrow", "swt": "SWT", "none": "none"}


def life_from(cfg: dict) -> str | None:
    """The S-N curve, probability and mean-stress rule of the headline life (or None)."""
    rule = cfg.get("mean_stress_applied")
    if rule is None:
        return None
    comp = cfg.get("component") or {}
    curve = "data curve (sn_curve)" if cfg.get("sn_curve") else \
        f"S-N {cfg.get('sn_method')} at P = {comp.get('reliability')}" if comp.get("enabled") \
        else "the material's line"
    return f"{curve}, mean stress {MEAN_STRESS_NAMES.get(rule, rule)}"


def sn_methods_table(fs: dict) -> str:
    """The life under each named S-N method at each survival probability (#26 item 4)."""
    methods = (fs.get("sn_methods") or {}).get("methods") or {}
    rows = []
    for m, by_p in methods.items():
        if not isinstance(by_p, dict):
            continue
        for p, v in by_p.items():
            if isinstance(v, dict):
                se = v.get("Se_pa")
                ms = v.get("mean_stress")
                rows.append((m, p, se / 1e6 if is_num(se) else se, v.get("k"),
                             v.get("life_km"), MEAN_STRESS_NAMES.get(str(ms), ms),
                             v.get("critical_node_id")))
    if not rows:
        return ""
    left = (fs.get("sn_methods") or {}).get("left_out") or {}
    return ("<div><h3>Life by S-N method</h3>" + "".join(
        note(f"{esc(m)}: not computed ({esc(why)})") for m, why in left.items()) + table_html(
        ["method", "survival probability", "Se at the knee [MPa]", "slope k",
         "min life [km]", "mean stress (of that life)", "critical node"], rows)
        + '<p class="meta">Shigley: the Marin chain (Shigley 9th ed.); FKM: the FKM '
          "guideline, non-welded, always with its Haigh diagram; the minimum life above is "
          "this table's entry of the run's method at its reliability. The spread is the S-N "
          "model's uncertainty: read the range, not one number (docs/fatigue.md).</p></div>")


def parts_block(r: RunData, fs: dict) -> str:
    """With ``[fatigue] parts``: every part's life side by side, each more one's map."""
    parts = [p for p in fs.get("parts") or [] if isinstance(p, dict)]
    if len(parts) < 2:
        return ""
    rows = [(p.get("name"), p.get("load_channel"), p.get("min_life_km"),
             p.get("life_range_km"), p.get("min_life_repeats"), p.get("max_damage_per_pass"),
             p.get("critical_node_id"), "fatigue/" if p.get("folder") == "."
             else f"fatigue/{p.get('folder')}/") for p in parts]
    body = ("<div><h3>Parts</h3>" + table_html(
        ["part", "load channel", "min life [km]", "life range over the S-N methods [km]",
         "min life [repeats]", "max damage per pass", "critical node", "results"], rows)
        + '<p class="meta">Each part under its own joint loads from the plant, with the '
          "same fatigue settings (docs/parts.md).</p></div>")
    for p in parts[1:]:
        name = str(p.get("folder"))  # a folder of fatigue/, never a path out of it (#43)
        folder = r.path / "fatigue" / (name if re.fullmatch(r"\w[\w.-]*", name) else "?")
        body += (f'<h3 id="damage-map-{esc(p.get("folder"))}">Damage map: '
                 f'{esc(p.get("name"))}</h3>')
        uri = file_uri(folder / "damage_map.png")
        body += img(uri, f"damage map of {p.get('name')}") if uri else note(
            f"no damage map ({cmd(str(folder / 'damage_map.png'))})")
    return body


def fatigue_section(r: RunData) -> str:
    d = cmd(f"suscosim fatigue {r.path}")
    if r.fatigue is None:
        if r.source is not None and not r.has_arm():
            text = ("no fatigue results: this run has no lower-arm loads (the fatigue analysis "
                    "needs the double-wishbone corner).")
        else:
            text = f"no fatigue results: run {d}"
        return section("fatigue", "Fatigue of the lower arm", note(text))
    fs = r.fatigue
    blocks = [kv_table(fatigue_numbers(fs), "Results")]
    top = fs.get("top_nodes") or []
    if top:
        blocks.append("<div><h3>Most damaged nodes</h3>" + table_html(
            ["node", "damage per pass", "life [km]"],
            [(n.get("node_id"), n.get("damage"), n.get("life_km")) for n in top]) + "</div>")
    methods = sn_methods_table(fs)
    if methods:
        blocks.append(methods)
    body = row(*blocks)
    body += parts_block(r, fs)
    cfg = fs.get("config") or {}
    inf = fs.get("influence") or {}
    body += row(kv_table(flatten(cfg), "Settings") if cfg else "",
                kv_table(flatten(inf), "Stress influence model") if inf else "")
    body += '<h3 id="damage-map">Damage map</h3>'
    uri = file_uri(r.damage_map) if r.damage_map else None
    if uri:
        body += img(uri, "damage map of the lower arm")
    else:
        body += note(f"no damage map (fatigue/damage_map.png): run {d}")
    body += '<h3 id="sn-plot">S-N curves and the critical node\'s cycles</h3>'
    sn_uri = file_uri(r.sn_plot) if r.sn_plot else None
    if sn_uri:
        body += img(sn_uri, "S-N curves with the critical node's cycles")
    else:
        body += note(f"no S-N plot (fatigue/sn_plot.png, written by batch fatigue): run {d}")
    csv_path = r.path / "fatigue" / "damage_per_node.csv"
    body += f'<p class="meta">Per-node results: {cmd(str(csv_path))}'
    outs = [o for o in fs.get("outputs") or [] if isinstance(o, str)]
    if outs:
        body += "; also " + ", ".join(cmd(str(r.path / "fatigue" / o)) for o in outs)
    body += "</p>"
    return section("fatigue", "Fatigue of the lower arm", body)
