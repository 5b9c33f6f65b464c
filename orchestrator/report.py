"""``suscosim report``: a self-contained HTML page of a run or a sweep.

    suscosim report RUN_OR_SWEEP_DIR [--out FILE.html] [--open]

The page (default ``<DIR>/report.html``) needs no server, no network and no JavaScript: the
plots are PNG images drawn with matplotlib (Agg) and embedded as ``data:`` URIs, the CSS is
inline, and every link is an anchor in the page or a relative path to a file next to it.

A **run folder** (``scenario.json``, ``summary.json``, ``table.parquet``/``table.csv``,
``journal.msgpack``, optional ``fatigue/``) gives: the scenario and the run's status, wall
time and steps per second; time histories (body/wheel displacement and acceleration,
suspension travel, tyre and damper force: whichever the table has); PSDs (Welch) of the body
acceleration and the tyre force; the RMS/peak table of every channel; ride metrics
(:mod:`nodes.recorder.ride_metrics`); the tyre and lower-arm load histories; the fatigue
results and the damage map of the arm. A failed run renders too (its error and whatever data
exists: a table rebuilt from the journal if the run left none). Every missing piece is named
in the page with the command that makes it.

A **sweep folder** (``sweep.json`` with its points, ``runs/<id>/`` run folders, optional
``results.json``/``results.csv``) gives: a results table, the minimum life of the arm per
point (and its change against the passive point of the same grid cell when the grid has
``controller.law``), overlaid PSDs and time histories of the points, the damage maps side by
side, and a section per point.

Exit codes: 0 written, 2 bad input (not a run or sweep folder, unreadable sweep.json, output
not writable).
"""

from __future__ import annotations

import argparse
import base64
import csv
import datetime as _dt
import html
import io
import json
import math
import re
import sys
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

MAX_PLOT_POINTS = 40000
"""Longer signals are decimated (min/max per bucket) before plotting."""
PSD_F_MAX_HZ = 50.0
"""Upper end of the PSD plots [Hz] (or Nyquist, if lower)."""
LAW_KEY = "controller.law"
PASSIVE = "passive"
CORNERS = ("FL", "FR", "RL", "RR")

CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,Helvetica,Arial,sans-serif;
 margin:0;background:#f4f5f7;color:#1d2330;font-size:15px;line-height:1.45}
main{max-width:1180px;margin:0 auto;padding:18px 26px 60px;background:#fff;
 box-shadow:0 0 8px rgba(0,0,0,.08)}
h1{font-size:1.6em;margin:.3em 0 .2em}h2{font-size:1.3em;margin:1.6em 0 .5em;
 border-bottom:2px solid #d7dbe3;padding-bottom:.2em}h3{font-size:1.08em;margin:1.1em 0 .4em}
table{border-collapse:collapse;margin:.4em 0 .8em;font-size:.88em}
th,td{border:1px solid #d7dbe3;padding:3px 8px;text-align:left;vertical-align:top}
th{background:#eef1f6}td.num{text-align:right;font-variant-numeric:tabular-nums}
.scroll{overflow-x:auto;max-width:100%}
.kv td:first-child{color:#4a5568;white-space:nowrap}
.badge{display:inline-block;padding:1px 10px;border-radius:10px;font-weight:600;color:#fff}
.ok{background:#2f855a}.failed{background:#c53030}.unknown{background:#718096}
.note{background:#fffbea;border-left:4px solid #d69e2e;padding:6px 12px;margin:.6em 0}
.error{background:#fff5f5;border-left:4px solid #c53030;padding:6px 12px;margin:.6em 0;
 white-space:pre-wrap;font-family:ui-monospace,Menlo,Consolas,monospace;font-size:.9em}
code,pre{font-family:ui-monospace,Menlo,Consolas,monospace;font-size:.92em}
pre{background:#f6f8fa;padding:8px;white-space:pre-wrap;word-break:break-word}
img.plot{max-width:100%;height:auto;display:block;margin:.4em 0}
nav{font-size:.92em;margin:.4em 0 1em}nav a{margin-right:12px}
.maps{display:grid;grid-template-columns:repeat(auto-fill,minmax(520px,1fr));gap:12px}
figure{margin:0}figcaption{font-size:.88em;color:#4a5568}
.meta{color:#4a5568;font-size:.88em}
.row{display:flex;flex-wrap:wrap;gap:0 26px;align-items:flex-start}
.row>div{min-width:0}.kv td.num{text-align:left}
.glance{font-size:1.02em}.glance td:last-child{font-weight:600}
"""


# ------------------------------------------------------------------------------- helpers


def esc(x: Any) -> str:
    """HTML-escaped text of ``x``."""
    return html.escape(str(x), quote=True)


def fmt(v: Any) -> str:
    """A value for a table cell: numbers with 4 significant digits (``.4g``)."""
    if v is None:
        return "—"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return "—" if math.isnan(v) else f"{v:.4g}"
    if isinstance(v, (list, tuple)):
        if all(isinstance(i, (int, float)) and not isinstance(i, bool) for i in v):
            return "[" + ", ".join(fmt(i) for i in v) + "]"
        if all(isinstance(i, dict) for i in v):
            return "; ".join(", ".join(f"{k}={fmt(x)}" for k, x in i.items()) for i in v)
        return ", ".join(fmt(i) for i in v)
    if isinstance(v, dict):
        return ", ".join(f"{k}={fmt(x)}" for k, x in v.items()) if v else "—"
    return str(v)


def _is_num(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def table_html(header: Sequence[str], rows: Iterable[Sequence[Any]], cls: str = "",
               raw_cols: Sequence[int] = ()) -> str:
    """An HTML table; cells are formatted with :func:`fmt` and escaped, except the columns in
    ``raw_cols`` (already HTML)."""
    out = [f'<div class="scroll"><table class="{cls}"><tr>']
    out += [f"<th>{esc(h)}</th>" for h in header]
    out.append("</tr>")
    for row in rows:
        out.append("<tr>")
        for i, v in enumerate(row):
            if i in raw_cols:
                out.append(f"<td>{v}</td>")
            else:
                out.append(f'<td class="num">{esc(fmt(v))}</td>' if _is_num(v)
                           else f"<td>{esc(fmt(v))}</td>")
        out.append("</tr>")
    out.append("</table></div>")
    return "".join(out)


def kv_table(pairs: Iterable[tuple[str, Any]], title: str = "", cls: str = "kv") -> str:
    """A two-column key/value table, with an optional ``<h3>`` title above it."""
    head = f"<h3>{esc(title)}</h3>" if title else ""
    return f"<div>{head}" + table_html(["key", "value"], list(pairs), cls=cls) + "</div>"


def row(*blocks: str) -> str:
    """Blocks side by side (wrapping on a narrow page)."""
    return '<div class="row">' + "".join(blocks) + "</div>"


def flatten(d: Any, prefix: str = "") -> list[tuple[str, Any]]:
    """Dotted ``(key, value)`` pairs of a nested dict (lists are kept whole)."""
    if not isinstance(d, dict):
        return [(prefix or "value", d)]
    out: list[tuple[str, Any]] = []
    for k, v in d.items():
        key = f"{prefix}.{k}" if prefix else str(k)
        if isinstance(v, dict) and v:
            out += flatten(v, key)
        elif isinstance(v, list) and v and all(isinstance(i, dict) for i in v):
            for i, item in enumerate(v):
                out.append((f"{key}[{i}]", item))
        else:
            out.append((key, v))
    return out


def note(text_html: str) -> str:
    return f'<div class="note">{text_html}</div>'


def section(anchor: str, title: str, body: str) -> str:
    return f'<section id="{esc(anchor)}"><h2>{esc(title)}</h2>\n{body}\n</section>\n'


def badge(status: str) -> str:
    cls = status if status in ("ok", "failed") else "unknown"
    return f'<span class="badge {cls}">{esc(status)}</span>'


def anchor_id(text: str) -> str:
    """An HTML id from free text (letters, digits, ``-_.`` kept)."""
    return "point-" + (re.sub(r"[^A-Za-z0-9_.-]+", "-", str(text)).strip("-") or "x")


def cmd(text: str) -> str:
    return f"<code>{esc(text)}</code>"


def _figure(nrows: int, ncols: int = 1, width: float = 11.0, row_h: float = 2.6,
            sharex: bool = False):
    """A matplotlib Figure (no pyplot, Agg canvas) and its axes as a flat list."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, max(2.4, row_h * nrows)), layout="constrained")
    axes = fig.subplots(nrows, ncols, sharex=sharex, squeeze=False)
    return fig, [a for row in axes for a in row]


def fig_uri(fig, dpi: int = 90) -> str:
    """The figure as a ``data:image/png;base64,...`` URI."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def file_uri(path: Path) -> str | None:
    """A PNG file as a data URI (None if it is not a PNG)."""
    try:
        data = path.read_bytes()
    except OSError:
        return None
    if not data.startswith(b"\x89PNG\r\n\x1a\n"):
        return None
    return "data:image/png;base64," + base64.b64encode(data).decode("ascii")


def img(uri: str, alt: str) -> str:
    return f'<img class="plot" src="{uri}" alt="{esc(alt)}">'


def decimate(t: np.ndarray, x: np.ndarray, n_max: int = MAX_PLOT_POINTS
             ) -> tuple[np.ndarray, np.ndarray]:
    """At most ~n_max points for a line plot, keeping each bucket's min and max (peaks stay)."""
    n = x.size
    if n <= n_max:
        return t, x
    b = int(math.ceil(n / (n_max // 2)))
    m = (n // b) * b
    xb, tb = x[:m].reshape(-1, b), t[:m].reshape(-1, b)
    i_lo, i_hi = xb.argmin(axis=1), xb.argmax(axis=1)
    first = np.minimum(i_lo, i_hi)
    second = np.maximum(i_lo, i_hi)
    rows = np.arange(xb.shape[0])
    tt = np.column_stack([tb[rows, first], tb[rows, second]]).ravel()
    xx = np.column_stack([xb[rows, first], xb[rows, second]]).ravel()
    return tt, xx


# ---------------------------------------------------------------------------- run data


@dataclass
class RunData:
    """What a run folder holds (every piece optional) and what was wrong with it."""

    path: Path
    scenario: dict | None = None
    summary: dict | None = None
    table: dict[str, np.ndarray] | None = None
    table_note: str = ""
    fatigue: dict | None = None
    damage_map: Path | None = None
    problems: list[str] = field(default_factory=list)

    @property
    def status(self) -> str:
        if self.summary is None:
            return "unknown"
        return str(self.summary.get("status", "unknown"))

    @property
    def run_id(self) -> str:
        for src in (self.summary or {}, (self.scenario or {}).get("run", {}) or {}):
            if src.get("run_id") or src.get("id"):
                return str(src.get("run_id") or src.get("id"))
        return self.path.name

    def has_arm(self) -> bool:
        return self.table is not None and any(c.startswith("plant/arm/") for c in self.table)


def _read_json(path: Path, problems: list[str]) -> Any:
    if not path.is_file():
        return None
    try:
        return json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        problems.append(f"{path.name}: unreadable ({exc})")
        return None


def is_run_dir(d: Path) -> bool:
    return any((d / n).is_file() for n in ("scenario.json", "summary.json", "journal.msgpack",
                                          "table.parquet", "table.csv"))


def is_sweep_dir(d: Path) -> bool:
    return (d / "sweep.json").is_file()


def load_run(d: Path) -> RunData:
    """Read every piece of a run folder that exists; never raises for a bad piece."""
    from nodes.recorder.table import read_table

    r = RunData(path=d)
    sc = _read_json(d / "scenario.json", r.problems)
    r.scenario = sc if isinstance(sc, dict) else None
    sm = _read_json(d / "summary.json", r.problems)
    r.summary = sm if isinstance(sm, dict) else None
    for name in ("table.parquet", "table.csv"):
        p = d / name
        if p.is_file() and r.table is None:
            try:
                tab = read_table(p)
            except Exception as exc:  # a torn or foreign file: say so, try the next source
                r.problems.append(f"{name}: unreadable ({type(exc).__name__}: {exc})")
                continue
            r.table, r.table_note = tab, name
    if r.table is None and (d / "journal.msgpack").is_file():
        try:
            from nodes.recorder.journal import read_journal
            from nodes.recorder.table import build_table

            contents = read_journal(d / "journal.msgpack")
            tab, _bad = build_table(contents.records)
            extra = f"; journal: {contents.problem}" if contents.problem else ""
            if len(tab["t"]):
                r.table = tab
                r.table_note = "rebuilt from journal.msgpack (the run left no table)" + extra
            else:
                r.table_note = "journal.msgpack holds no complete step" + extra
        except Exception as exc:
            r.problems.append(f"journal.msgpack: unreadable ({type(exc).__name__}: {exc})")
    if r.table is not None:
        r.table = {k: np.asarray(v, dtype=float) for k, v in r.table.items() if k != "k"}
        if "t" not in r.table or r.table["t"].size < 2:
            r.problems.append(f"{r.table_note}: fewer than 2 samples")
            r.table = None
    fs = _read_json(d / "fatigue" / "summary.json", r.problems)
    r.fatigue = fs if isinstance(fs, dict) else None
    if (d / "fatigue" / "damage_map.png").is_file():
        r.damage_map = d / "fatigue" / "damage_map.png"
    return r


# ------------------------------------------------------------------------ signal picking


UNITS = {"z": "m", "v": "m/s", "a": "m/s²", "F": "N", "k_t": "N/m", "c_eff": "N·s/m",
         "heave": "m", "pitch": "rad", "roll": "rad", "v_heave": "m/s", "w_pitch": "rad/s",
         "w_roll": "rad/s", "arm_angle": "rad", "I": "A", "state": "-"}


def unit_of(column: str) -> str:
    """SI unit of a table column from its field name (``""`` if unknown)."""
    parts = column.split("/")
    fld = re.sub(r"\[\d+\]$", "", parts[-1])
    if len(parts) >= 2 and parts[-2] == "arm":
        return "N·m" if fld.rsplit("_", 1)[-1].startswith("m") else "N"
    if fld in UNITS:
        return UNITS[fld]
    return UNITS.get(fld.split("_", 1)[0], "")


def corner_cols(table: dict[str, np.ndarray], base: str) -> list[tuple[str, np.ndarray]]:
    """``[(corner label, values)]`` of a per-corner column (``""`` label for a quarter car)."""
    from nodes.recorder.ride_metrics import columns

    out = columns(table, base)
    if len(out) == 4:
        return [(CORNERS[i], x) for i, (_lab, x) in enumerate(out)]
    return [(lab.strip("[]"), x) for lab, x in out]


def first_present(table: dict[str, np.ndarray], bases: Sequence[str]) -> tuple[str, list]:
    for b in bases:
        cols = corner_cols(table, b)
        if cols:
            return b, cols
    return "", []


BODY_ACC = ("plant/response/a_b",)
TYRE_FORCE = ("tyre_road/force/F_t", "plant/response/F_t")
DAMPER_FORCE = ("controller/force/F_d", "plant/response/F_d")


def _label(name: str, corner: str) -> str:
    return f"{name} {corner}".strip()


def time_history_panels(table: dict[str, np.ndarray]) -> tuple[list[tuple], list[str]]:
    """The time-history panels a table allows: ``[(title, unit, [(label, y)])]``, and the
    titles of those it does not."""
    panels: list[tuple] = []
    missing: list[str] = []

    def add(title: str, unit: str, lines: list[tuple[str, np.ndarray]]) -> None:
        (panels if lines else missing).append((title, unit, lines) if lines else title)

    disp = []
    for base, name in (("plant/state/z_b", "body z_b"), ("plant/state/z_w", "wheel z_w"),
                       ("tyre_road/force/z_g", "road z_g")):
        disp += [(_label(name, c), 1e3 * x) for c, x in corner_cols(table, base)]
    add("Body and wheel displacement", "mm", disp)
    add("Body acceleration", "m/s²",
        [(_label("a_b", c), x) for c, x in corner_cols(table, "plant/response/a_b")])
    add("Wheel acceleration", "m/s²",
        [(_label("a_w", c), x) for c, x in corner_cols(table, "plant/response/a_w")])
    travel = [(_label("z_w − z_b", c), 1e3 * (w - b)) for (c, b), (_c, w) in
              zip(corner_cols(table, "plant/state/z_b"), corner_cols(table, "plant/state/z_w"),
                  strict=False)]
    travel += [(_label("damper compression", c), 1e3 * x)
               for c, x in corner_cols(table, "plant/state/z_damper")]
    add("Suspension travel (compression +)", "mm", travel)
    base, cols = first_present(table, TYRE_FORCE)
    add("Tyre force", "N", [(_label("F_t", c), x) for c, x in cols])
    base, cols = first_present(table, DAMPER_FORCE)
    add("Damper force", "N", [(_label("F_d", c), x) for c, x in cols])
    return panels, missing


def plot_panels(t: np.ndarray, panels: list[tuple], width: float = 11.0) -> str:
    fig, axes = _figure(len(panels), width=width, sharex=True)
    styles = ("-", "--", ":", "-.")
    for ax, (title, unit, lines) in zip(axes, panels, strict=True):
        quantities: list[str] = []
        for i, (lab, y) in enumerate(lines):
            head, _, last = lab.rpartition(" ")
            if last in CORNERS and head:  # full vehicle: colour = corner, style = quantity
                if head not in quantities:
                    quantities.append(head)
                style = dict(color=f"C{CORNERS.index(last)}",
                             ls=styles[quantities.index(head) % len(styles)])
            else:
                style = dict(color=f"C{i % 10}")
            ax.plot(*decimate(t, y), lw=0.9, label=lab, **style)
        ax.set_title(title, fontsize=10, loc="left")
        ax.set_ylabel(unit)
        ax.grid(alpha=0.3)
        if len(lines) > 1:
            ax.legend(fontsize=7, loc="upper right", ncol=min(4, len(lines)))
    axes[-1].set_xlabel("t [s]")
    return fig_uri(fig)


def welch_psd(x: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """One-sided Welch PSD (Hann, ~8 averages, mean removed): (f [Hz], P [unit²/Hz])."""
    from scipy.signal import welch

    n = x.size
    nperseg = int(min(n, max(256, n // 4)))
    return welch(x, fs=fs, nperseg=nperseg, detrend="constant")


def sample_rate(t: np.ndarray) -> float | None:
    from nodes.recorder.ride_metrics import sample_rate as _sr

    try:
        return _sr(t)
    except ValueError:
        return None


# ---------------------------------------------------------------------------- run page


RUN_KEYS = ("name", "id", "mode", "exchange", "coupling", "h", "substeps", "t_end",
            "t_end_source", "n_steps", "nodes")
SUMMARY_KEYS = ("status", "wall_s", "run_wall_s", "step_wall_s", "steps_per_s", "n_steps", "rows",
                "nodes")


def run_header(r: RunData, title_prefix: str = "Run") -> str:
    s = r.summary or {}
    out = [f"<h1>{esc(title_prefix)} {esc(r.run_id)} {badge(r.status)}</h1>",
           f'<p class="meta">folder {cmd(str(r.path.resolve()))} · report written '
           f"{esc(_dt.datetime.now().strftime('%Y-%m-%d %H:%M:%S'))}</p>"]
    if r.summary is None:
        out.append(note("no summary.json: the run is still going, or its orchestrator was "
                        "killed before it could write one. Shown: whatever the folder holds."))
    if s.get("error"):
        out.append(f'<div class="error">run failed: {esc(s["error"])}</div>')
    for p in r.problems:
        out.append(note(esc(p)))
    glance = kv_table(at_a_glance(r), "At a glance", cls="kv glance")
    status_tab = ""
    if r.summary is not None:
        pairs = [("status", r.status)]
        if "wall_s" in s:
            pairs.append(("wall time [s]", s.get("wall_s")))
        if "step_wall_s" in s:
            pairs.append(("stepping wall time [s]", s.get("step_wall_s")))
        if "run_wall_s" in s:
            pairs.append(("start to all nodes done [s]", s.get("run_wall_s")))
        if "steps_per_s" in s:
            pairs.append(("coupled steps per s", s.get("steps_per_s")))
        for k in ("n_steps", "rows", "mode", "exchange", "coupling", "h", "substeps", "t_end"):
            if k in s:
                pairs.append((k, s[k]))
        rej = {k: v for k, v in (s.get("rejected_messages") or {}).items() if v}
        pairs.append(("rejected messages", rej or "none"))
        status_tab = kv_table(pairs, "Run")
    out.append(row(glance, status_tab))
    return "\n".join(out)


def _scn(r: RunData, sec: str, key: str) -> Any:
    return ((r.scenario or {}).get(sec) or {}).get(key)


def at_a_glance(r: RunData) -> list[tuple[str, Any]]:
    """The few facts a reader wants first: what was simulated and what came out."""
    pairs: list[tuple[str, Any]] = []
    if r.scenario is not None:
        pairs += [("vehicle", _scn(r, "vehicle", "model")),
                  ("road", " ".join(str(x) for x in (
                      _scn(r, "road", "type"), _scn(r, "road", "class") and
                      f"class {_scn(r, 'road', 'class')}",
                      _scn(r, "road", "speed_kmh") and f"{fmt(_scn(r, 'road', 'speed_kmh'))} km/h",
                      _scn(r, "road", "length_m") and f"{fmt(_scn(r, 'road', 'length_m'))} m")
                      if x)),
                  ("tyre", _scn(r, "tyre", "model")),
                  ("controller", _scn(r, "controller", "law"))]
    s = r.summary or {}
    pairs.append(("status", r.status))
    if "t_end" in s or r.scenario:
        pairs.append(("simulated [s]", s.get("t_end", _scn(r, "run", "t_end"))))
    if "steps_per_s" in s:
        pairs.append(("coupled steps per s", s.get("steps_per_s")))
    chans = s.get("channels") or {}
    for base, lab in (("plant/response/a_b", "body acceleration rms [m/s²]"),
                      ("tyre_road/force/F_t", "tyre force peak [N]")):
        st = chans.get(base) or chans.get(f"{base}[0]")
        if st:
            pairs.append((lab + ("" if base in chans else " (FL)"),
                          st.get("rms" if "rms" in lab else "peak")))
    if r.fatigue is not None:
        pairs.append(("arm minimum life [km]", r.fatigue.get("min_life_km")))
    return pairs


def scenario_section(r: RunData) -> str:
    if r.scenario is None:
        return section("scenario", "Scenario", note("no scenario.json in the run folder."))
    parts = []
    order = ["run", "vehicle", "road", "tyre", "controller", "fatigue"]
    keys = order + [k for k in r.scenario if k not in order]
    for k in keys:
        v = r.scenario.get(k)
        if v is None:
            continue
        if k == "run":
            pairs = [(x, v[x]) for x in RUN_KEYS if x in v] + \
                    [(x, y) for x, y in flatten(v) if x not in RUN_KEYS and x != "dir"]
        else:
            pairs = flatten(v)
        parts.append(kv_table(pairs, k))
    return section("scenario", "Scenario", row(*parts))


def time_section(r: RunData) -> str:
    t = r.table["t"]
    panels, missing = time_history_panels(r.table)
    body = f'<p class="meta">from {esc(r.table_note)}: {t.size} samples, ' \
           f"t = {fmt(float(t[0]))} … {fmt(float(t[-1]))} s</p>"
    if panels:
        body += img(plot_panels(t, panels), "time histories")
    if missing:
        body += note("not in this run's table: " + esc(", ".join(missing)))
    return section("time", "Time histories", body)


def psd_section(r: RunData) -> str:
    t = r.table["t"]
    fs = sample_rate(t)
    if fs is None:
        return section("psd", "Power spectral densities",
                       note("the time column is not uniformly sampled (a run with missing "
                            "steps?): no PSD."))
    sigs = []
    _b, acc = first_present(r.table, BODY_ACC)
    if acc:
        sigs.append(("Body acceleration", "(m/s²)²/Hz", acc))
    _b, ft = first_present(r.table, TYRE_FORCE)
    if ft:
        sigs.append(("Tyre force", "N²/Hz", ft))
    if not sigs:
        return section("psd", "Power spectral densities",
                       note("no body acceleration or tyre force in the table."))
    fmax = min(fs / 2, PSD_F_MAX_HZ)
    fig, axes = _figure(1, len(sigs), row_h=3.4)
    for ax, (title, unit, cols) in zip(axes, sigs, strict=True):
        for c, x in cols:
            f, p = welch_psd(x, fs)
            keep = (f > 0) & (f <= fmax)
            ax.semilogy(f[keep], np.maximum(p[keep], 1e-30), lw=1.0, label=c or None)
        ax.set_title(title, fontsize=10, loc="left")
        ax.set_xlabel("f [Hz]")
        ax.set_ylabel(unit)
        ax.grid(alpha=0.3, which="both")
        if len(cols) > 1:
            ax.legend(fontsize=7)
    n = t.size
    body = img(fig_uri(fig), "PSDs") + (
        f'<p class="meta">Welch, Hann window, {min(n, max(256, n // 4))} samples per segment, '
        f"50 % overlap, mean removed; fs = {fmt(fs)} Hz; shown to {fmt(fmax)} Hz.</p>")
    return section("psd", "Power spectral densities", body)


def stats_section(r: RunData) -> str:
    chans = (r.summary or {}).get("channels") or {}
    src = "summary.json"
    if not chans and r.table is not None:
        from nodes.recorder.table import channel_stats

        chans = channel_stats({"t": r.table["t"], **{k: v for k, v in r.table.items()
                                                      if k != "t"}})
        src = r.table_note
    if not chans:
        return section("stats", "RMS and peak of every channel",
                       note("no channel statistics: the run recorded no complete step."))
    rows = [(name, unit_of(name), st.get("rms"), st.get("peak"), st.get("t_peak"),
             st.get("mean"), st.get("std"), st.get("min"), st.get("max"))
            for name, st in sorted(chans.items())]
    body = f'<p class="meta">from {esc(src)}; peak = the value of largest magnitude ' \
           f"(signed), at t_peak.</p>" + table_html(
               ["channel", "unit", "rms", "peak", "t_peak [s]", "mean", "std", "min", "max"],
               rows)
    return section("stats", "RMS and peak of every channel", body)


def ride_section(r: RunData) -> str:
    from nodes.recorder.ride_metrics import run_metrics

    try:
        m = run_metrics(r.table)
    except (ValueError, KeyError) as exc:
        return section("ride", "Ride metrics", note(f"no ride metrics: {esc(exc)}"))
    if not m:
        return section("ride", "Ride metrics", note("no ride channels in the table."))
    body = table_html(["metric", "value"], list(m.items()), cls="kv") + (
        '<p class="meta">nodes.recorder.ride_metrics.run_metrics: band RMS as the thesis '
        "computes it (resampled to 500 Hz, periodogram, Eq 4.8/4.9), full-band RMS at the "
        "run's own rate, ISO 2631-1 Wk weighting, suspension "
        "working space (SWS), dynamic tyre load (DTL).</p>")
    return section("ride", "Ride metrics", body)


def arm_groups(table: dict[str, np.ndarray]) -> dict[str, list[tuple[str, np.ndarray]]]:
    """``plant/arm/<point>_<axis>`` columns grouped by point: ``{point: [(axis, values)]}``."""
    groups: dict[str, list[tuple[str, np.ndarray]]] = {}
    for name in sorted(table):
        if not name.startswith("plant/arm/"):
            continue
        fld = name[len("plant/arm/"):]
        point, _, axis = fld.rpartition("_")
        groups.setdefault(point or fld, []).append((axis or fld, table[name]))
    return groups


def loads_section(r: RunData) -> str:
    t = r.table["t"]
    panels = []
    _b, ft = first_present(r.table, TYRE_FORCE)
    if ft:
        panels.append(("Tyre force (vertical, compressive +)", "N",
                       [(_label("F_t", c), x) for c, x in ft]))
    groups = arm_groups(r.table)
    for point, comps in groups.items():
        unit = "N·m" if all(a.startswith("m") for a, _ in comps) else "N"
        panels.append((f"Lower arm: {point.replace('_', ' ')} (arm frame)", unit, comps))
    body = ""
    if panels:
        body += img(plot_panels(t, panels), "load histories")
    if not groups:
        model = ((r.scenario or {}).get("vehicle") or {}).get("model", "?")
        body += note(f"no lower-arm load channels (<code>plant/arm/...</code>) in this run: the "
                     f"vehicle model {cmd(model)} has no arm. The double-wishbone corner "
                     f"({cmd('quarter_car_double_wishbone')}) reports them.")
    else:
        body += '<p class="meta">Forces on the lower arm at its joints, arm frame ' \
                "(see cosim/channels.py); these drive the fatigue analysis.</p>"
    return section("loads", "Tyre and lower-arm load histories", body)


def fatigue_numbers(fs: dict) -> list[tuple[str, Any]]:
    pairs: list[tuple[str, Any]] = [
        ("minimum life [km]", fs.get("min_life_km")),
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
         [1e3 * v for v in xyz] if isinstance(xyz, list) and all(map(_is_num, xyz)) else xyz),
    ]
    if _is_num(fs.get("critical_eq_range_max_pa")):
        pairs.append(("critical node: largest equivalent stress range [MPa]",
                      fs["critical_eq_range_max_pa"] / 1e6))
    if _is_num(fs.get("eq_stress_max_pa")) and _is_num(fs.get("eq_stress_min_pa")):
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
    return pairs


def fatigue_section(r: RunData) -> str:
    d = cmd(f"suscosim fatigue {r.path}")
    if r.fatigue is None:
        if r.table is not None and not r.has_arm():
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
    body = row(*blocks)
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
    csv_path = r.path / "fatigue" / "damage_per_node.csv"
    body += f'<p class="meta">Per-node results: {cmd(str(csv_path))}</p>'
    return section("fatigue", "Fatigue of the lower arm", body)


def logs_section(r: RunData) -> str:
    """Tails of the node logs that say something (only for a run that did not end ok)."""
    logs = sorted((r.path / "logs").glob("*.log")) if (r.path / "logs").is_dir() else []
    parts = []
    for p in logs:
        try:
            lines = p.read_text(errors="replace").splitlines()
        except OSError:
            continue
        lines = [ln for ln in lines if ln.strip() and not ln.startswith("pybullet build time")]
        if lines:
            parts.append(f"<h3>{esc(p.name)}</h3><pre>{esc(chr(10).join(lines[-25:]))}</pre>")
    if not parts:
        return ""
    return section("logs", "Node logs (last lines)", "".join(parts))


def run_body(r: RunData) -> str:
    """The sections of a run page (without the page frame)."""
    parts = [scenario_section(r)]
    if r.table is None:
        j = r.path / "journal.msgpack"
        if r.table_note:
            hint = esc(r.table_note)
        elif j.is_file():
            hint = f"run {cmd(f'suscosim export {j}')}"
        else:
            hint = "the run recorded nothing (no journal.msgpack)"
        parts.append(section("time", "Time histories",
                             note(f"no table (table.parquet / table.csv): {hint}.")))
        parts.append(stats_section(r))
    else:
        parts += [time_section(r), psd_section(r), stats_section(r), ride_section(r),
                  loads_section(r)]
    parts.append(fatigue_section(r))
    if r.status != "ok":
        parts.append(logs_section(r))
    return "".join(parts)


RUN_NAV = (("scenario", "Scenario"), ("time", "Time histories"), ("psd", "PSDs"),
           ("stats", "RMS / peak"), ("ride", "Ride metrics"), ("loads", "Loads"),
           ("fatigue", "Fatigue"), ("damage-map", "Damage map"))


def nav(items: Sequence[tuple[str, str]]) -> str:
    return "<nav>" + "".join(f'<a href="#{esc(a)}">{esc(t)}</a>' for a, t in items) + "</nav>"


def page(title: str, body: str) -> str:
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
            f"<title>{esc(title)}</title><style>{CSS}</style></head>\n<body><main>\n"
            f"{body}\n<p class=\"meta\">suscosim report · self-contained: no scripts, no "
            "external resources.</p></main></body></html>\n")


def render_run(d: Path) -> str:
    """The HTML page of a run folder."""
    r = load_run(d)
    body = run_header(r) + nav(RUN_NAV) + run_body(r)
    return page(f"suscosim run {r.run_id}", body)


# -------------------------------------------------------------------------- sweep page


class BadInput(Exception):
    """Bad input for the report (exit code 2)."""


@dataclass
class Point:
    """A sweep point: its id, parameters, run folder and what it holds."""

    id: str
    params: dict[str, Any]
    run_dir: Path
    run: RunData | None
    overrides: dict[str, Any] = field(default_factory=dict)

    @property
    def law(self) -> str | None:
        """The controller law: a ``controller.law`` parameter, else the point's overrides in
        sweep.json (a variant axis such as ``strategy``), else the run's resolved scenario."""
        if LAW_KEY in self.params:
            return str(self.params[LAW_KEY])
        ov = self.overrides
        law = ov.get(LAW_KEY)
        if law is None and isinstance(ov.get("controller"), dict):
            law = ov["controller"].get("law")
        if law is None and self.run is not None:
            law = ((self.run.scenario or {}).get("controller") or {}).get("law")
        return None if law is None else str(law)

    @property
    def short(self) -> str:
        """The point's grid values joined by '/' (its id if it has none)."""
        return "/".join(fmt(v) for v in self.params.values()) or self.id

    @property
    def status(self) -> str:
        if self.run is None:
            return "not run"
        return self.run.status

    @property
    def life_km(self) -> float | None:
        fs = self.run.fatigue if self.run else None
        v = (fs or {}).get("min_life_km")
        return float(v) if _is_num(v) else None

    @property
    def label(self) -> str:
        return ", ".join(f"{k.split('.')[-1]}={fmt(v)}" for k, v in self.params.items()) \
            or self.id


def load_sweep(d: Path) -> tuple[dict, list[Point]]:
    """sweep.json and its points (raises BadInput for an unreadable sweep.json)."""
    p = d / "sweep.json"
    try:
        spec = json.loads(p.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise BadInput(f"{p}: unreadable ({exc})") from None
    if not isinstance(spec, dict) or not isinstance(spec.get("points", []), list):
        raise BadInput(f"{p}: expected an object with a 'points' list")
    points = []
    for i, pt in enumerate(spec.get("points", [])):
        if not isinstance(pt, dict):
            raise BadInput(f"{p}: points[{i}] is not an object")
        pid = str(pt.get("id", i))
        params = pt.get("params") or {}
        if not isinstance(params, dict):
            raise BadInput(f"{p}: points[{i}].params is not an object")
        rd = d / str(pt.get("run_dir") or f"runs/{pid}")
        run = load_run(rd) if rd.is_dir() and is_run_dir(rd) else None
        ov = pt.get("overrides")
        points.append(Point(pid, params, rd, run, ov if isinstance(ov, dict) else {}))
    return spec, points


def read_results(d: Path) -> tuple[list[dict], str]:
    """Rows of results.json (list, or object with 'rows'/'points') or results.csv."""
    pj, pc = d / "results.json", d / "results.csv"
    if pj.is_file():
        try:
            data = json.loads(pj.read_text())
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            return [], f"results.json unreadable ({exc})"
        if isinstance(data, dict):
            data = data.get("rows", data.get("points", data.get("results", [])))
        if isinstance(data, list) and all(isinstance(x, dict) for x in data):
            return data, "results.json"
        return [], "results.json: not a list of rows"
    if pc.is_file():
        try:
            with open(pc, newline="") as fh:
                return list(csv.DictReader(fh)), "results.csv"
        except (OSError, UnicodeDecodeError, csv.Error) as exc:
            return [], f"results.csv unreadable ({exc})"
    return [], ""


def grid_keys(spec: dict, points: list[Point]) -> list[str]:
    grid = spec.get("grid")
    keys = list(grid) if isinstance(grid, dict) else []
    for p in points:
        keys += [k for k in p.params if k not in keys]
    return keys


def _rms_of(p: Point, bases: Sequence[str]) -> float | None:
    """RMS of the first corner of the first of ``bases`` in the point's summary (or table)."""
    if p.run is None:
        return None
    chans = (p.run.summary or {}).get("channels") or {}
    for b in bases:
        for name in (b, f"{b}[0]"):
            if name in chans and _is_num(chans[name].get("rms")):
                return float(chans[name]["rms"])
    if p.run.table is not None:
        _b, cols = first_present(p.run.table, bases)
        if cols:
            x = cols[0][1]
            return float(np.sqrt(np.mean(x * x)))
    return None


def law_axis(points: list[Point], keys: list[str]) -> str | None:
    """The grid axis that sets the controller law: ``controller.law``, or an axis of named
    variants (e.g. ``strategy``) whose every value gives one law, passive among them."""
    if LAW_KEY in keys:
        return LAW_KEY
    for k in keys:
        laws: dict[str, set] = {}
        for p in points:
            if k in p.params and p.law is not None:
                laws.setdefault(json.dumps(p.params[k], sort_keys=True, default=str),
                                set()).add(p.law)
        distinct = set().union(*laws.values()) if laws else set()
        if laws and all(len(v) == 1 for v in laws.values()) and len(distinct) > 1 \
                and PASSIVE in distinct:
            return k
    return None


def _is_passive(p: Point, axis: str) -> bool:
    return p.law == PASSIVE or p.params.get(axis) == PASSIVE


def vs_passive(points: list[Point], keys: list[str], value) -> dict[str, float]:
    """``{point id: (value / value of the passive point of its grid cell - 1) * 100}``, the
    grid cell being the values of every axis but the law axis (empty without one)."""
    axis = law_axis(points, keys)
    if axis is None:
        return {}
    others = [k for k in keys if k != axis]

    def cell(p: Point) -> tuple:
        return tuple(json.dumps(p.params.get(k), sort_keys=True, default=str) for k in others)

    base: dict[tuple, float | None] = {}
    for p in points:
        if _is_passive(p, axis) and cell(p) not in base:
            base[cell(p)] = value(p)
    out = {}
    for p in points:
        b, v = base.get(cell(p)), value(p)
        if b is not None and v is not None and b > 0:
            out[p.id] = (v / b - 1.0) * 100.0
    return out


def sweep_results_section(spec: dict, points: list[Point], keys: list[str],
                          d: Path) -> str:
    life_change = vs_passive(points, keys, lambda p: p.life_km)
    acc_change = vs_passive(points, keys, lambda p: _rms_of(p, BODY_ACC))
    header = ["point", *keys, "status", "wall [s]", "steps/s", "a_b rms [m/s²]",
              "F_t rms [N]", "min life [km]"]
    if life_change:
        header.append("life change vs passive [%]")
    if acc_change:
        header.append("a_b rms vs passive [%]")
    header.append("error")
    rows = []
    for p in points:
        s = (p.run.summary or {}) if p.run else {}
        row: list[Any] = [f'<a href="#{anchor_id(p.id)}">{esc(p.id)}</a>',
                          *[p.params.get(k) for k in keys], badge(p.status),
                          s.get("wall_s"), s.get("steps_per_s"), _rms_of(p, BODY_ACC),
                          _rms_of(p, TYRE_FORCE), p.life_km]
        if life_change:
            row.append(life_change.get(p.id))
        if acc_change:
            row.append(acc_change.get(p.id))
        err = s.get("error") or ("" if p.run else f"no run folder {p.run_dir}")
        row.append(err[:160] + ("…" if len(err) > 160 else ""))
        rows.append(row)
    status_col = 1 + len(keys)
    body = table_html(header, rows, raw_cols=(0, status_col))
    results, src = read_results(d)
    if results:
        cols: list[str] = []
        for row in results:
            cols += [k for k in row if k not in cols]
        body += (f"<details><summary>{esc(src)}: every column ({len(cols)})</summary>"
                 + table_html(cols, [[_num_or_text(r.get(c)) for c in cols] for r in results])
                 + "</details>")
    elif src:
        body += note(esc(src))
    else:
        body += note("no results.json / results.csv in the sweep folder (the sweep has not "
                     "finished); the table above is read from the run folders.")
    return section("results", "Results", body)


def _num_or_text(v: Any) -> Any:
    if isinstance(v, str):
        try:
            return float(v) if v.strip() else v
        except ValueError:
            return v
    return v


def _bars(ax, labels: list[str], values: list[float | None], title: str, ylabel: str,
          log: bool = False, colors: list[str] | None = None) -> None:
    """One bar per point; ``log`` uses a log axis only when the values span > 50x (a log
    axis cut at its lowest value would exaggerate small differences)."""
    x = np.arange(len(labels))
    vals = [v if v is not None else np.nan for v in values]
    colors = colors or [f"C{i % 10}" for i in range(len(labels))]
    bars = ax.bar(x, vals, color=colors, width=0.6)
    ax.bar_label(bars, labels=[fmt(v) if v is not None else "" for v in values], fontsize=7)
    tilt = len(labels) > 4
    ax.set_xticks(x, labels, rotation=30 if tilt else 0, ha="right" if tilt else "center",
                  fontsize=8)
    pos = [v for v in values if v is not None and v > 0]
    if log and pos and max(pos) / min(pos) > 50:
        ax.set_yscale("log")
    ax.set_xlim(-0.7, len(labels) - 0.3)
    ax.set_title(title, fontsize=10, loc="left")
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3, axis="y")
    for xi, v in zip(x, values, strict=True):
        if v is None:
            ax.annotate("n/a", (xi, 0), xytext=(0, 2), textcoords="offset points",
                        ha="center", va="bottom", fontsize=8, color="#888")


def law_colours(points: list[Point], axis: str) -> dict[str, str]:
    """A colour per value of the law axis (passive first, C0), the same in every chart."""
    vals = [fmt(x) for x in dict.fromkeys(p.params.get(axis) for p in points)]
    passive = {fmt(p.params.get(axis)) for p in points if _is_passive(p, axis)}
    vals.sort(key=lambda v: v not in passive)
    return {v: f"C{i % 10}" for i, v in enumerate(vals)}


def _point_colours(points: list[Point], keys: list[str]) -> list[str] | None:
    axis = law_axis(points, keys)
    if axis is None:
        return None
    colour = law_colours(points, axis)
    return [colour[fmt(p.params.get(axis))] for p in points]


def _cell_label(p: Point, others: list[str]) -> str:
    return ", ".join(f"{k.split('.')[-1]}={fmt(p.params.get(k))}" for k in others) or "all"


def _grouped_change(ax, points: list[Point], keys: list[str], change: dict[str, float],
                    title: str) -> None:
    """Bars of ``change`` [%] per law (without passive), grouped by the grid cell of the other
    parameters (a single cell: one bar per law)."""
    axis = law_axis(points, keys) or LAW_KEY
    others = [k for k in keys if k != axis]
    colour = law_colours(points, axis)
    laws = [law for law in dict.fromkeys(fmt(p.params.get(axis)) for p in points
                                         if not _is_passive(p, axis))
            if any(q.id in change for q in points if fmt(q.params.get(axis)) == law)]
    cells = list(dict.fromkeys(_cell_label(p, others) for p in points))
    value = {(_cell_label(p, others), fmt(p.params.get(axis))): change.get(p.id)
             for p in points}
    nl = max(1, len(laws))
    width = min(0.8 / nl, 0.35)
    for j, law in enumerate(laws):
        ys = [value.get((c, law)) for c in cells]
        xs = np.arange(len(cells)) * (1 if len(cells) > 1 else 0) + \
            (j - (nl - 1) / 2) * (width if len(cells) > 1 else 0.5)
        bars = ax.bar(xs, [np.nan if y is None else y for y in ys], width=width,
                      label=str(law), color=colour[str(law)])
        ax.bar_label(bars, labels=[f"{y:+.1f} %" if y is not None else "" for y in ys],
                     fontsize=7)
    if len(cells) > 1:
        ax.set_xticks(np.arange(len(cells)), cells, fontsize=8)
        ax.set_xlim(-0.7, len(cells) - 0.3)
        ax.legend(fontsize=8)
    else:
        xs = [(j - (nl - 1) / 2) * 0.5 for j in range(nl)]
        ax.set_xticks(xs, [str(x) for x in laws], fontsize=8)
        ax.set_xlim(min(xs, default=0) - 0.5, max(xs, default=0) + 0.5)
    ax.axhline(0, color="k", lw=0.8)
    ax.margins(y=0.15)
    ax.set_title(title, fontsize=10, loc="left")
    ax.set_ylabel("% vs passive")
    ax.grid(alpha=0.3, axis="y")


def sweep_compare_section(points: list[Point], keys: list[str]) -> str:
    lives = [p.life_km for p in points]
    accs = [_rms_of(p, BODY_ACC) for p in points]
    labels = [p.short for p in points]
    life_change = vs_passive(points, keys, lambda p: p.life_km)
    acc_change = vs_passive(points, keys, lambda p: _rms_of(p, BODY_ACC))
    colours = _point_colours(points, keys)
    body = ""
    if any(v is not None for v in lives):
        if life_change:
            fig, axes = _figure(1, 2, row_h=3.8)
            _bars(axes[0], labels, lives, "Minimum life of the lower arm", "km", log=True,
                  colors=colours)
            _grouped_change(axes[1], points, keys, life_change, "Life change vs passive")
        else:
            fig, axes = _figure(1, 1, row_h=3.8)
            _bars(axes[0], labels, lives, "Minimum life of the lower arm", "km", log=True,
                  colors=colours)
        body += "<h3>Fatigue</h3>" + img(fig_uri(fig), "minimum life per point")
        if life_change:
            body += '<p class="meta">life change vs passive = (life / life of the passive ' \
                    "point with the same other grid parameters − 1) × 100 %.</p>"
    else:
        body += note("no fatigue results in any point: run <code>suscosim fatigue "
                     "SWEEP/runs/&lt;id&gt;</code> for each point (or give the sweep a "
                     "realistic corner, whose runs carry arm loads).")
    if any(v is not None for v in accs):
        if acc_change:
            fig, axes = _figure(1, 2, row_h=3.4)
            _bars(axes[0], labels, accs, "Body acceleration RMS", "m/s²", colors=colours)
            _grouped_change(axes[1], points, keys, acc_change, "Body acceleration RMS change")
        else:
            fig, axes = _figure(1, 1, row_h=3.4)
            _bars(axes[0], labels, accs, "Body acceleration RMS", "m/s²", colors=colours)
        body += "<h3>Ride</h3>" + img(fig_uri(fig), "body acceleration RMS per point")
    return section("compare", "Comparison", body)


def overlay_groups(points: list[Point], keys: list[str]
                   ) -> list[tuple[str, list[tuple[Point, str, str]]]]:
    """Points to overlay: ``[(group title, [(point, legend label, colour)])]``. With a law
    axis, one group per cell of the other axes (e.g. per road), coloured by law as in the
    charts; without one, every point in one group."""
    axis = law_axis(points, keys)
    if axis is None:
        return [("", [(p, p.short, f"C{j % 10}") for j, p in enumerate(points)])]
    colour = law_colours(points, axis)
    others = [k for k in keys if k != axis]
    groups: dict[str, list[tuple[Point, str, str]]] = {}
    for p in points:
        v = fmt(p.params.get(axis))
        groups.setdefault(_cell_label(p, others) if others else "", []).append(
            (p, v, colour[v]))
    return list(groups.items())


def _overlay_figures(members: list[tuple[Point, str, str]], ci: int) -> str:
    """PSD and time-history overlays of one group of points (corner index ``ci``)."""
    out = ""
    fig, axes = _figure(1, 1, row_h=3.4)
    ax = axes[0]
    corner, n_psd = "", 0
    for p, lab, colour in members:
        tab = p.run.table
        fs = sample_rate(tab["t"])
        _b, cols = first_present(tab, BODY_ACC)
        if fs is None or len(cols) <= ci:
            continue
        corner, x = cols[ci]
        f, pp = welch_psd(x, fs)
        keep = (f > 0) & (f <= min(fs / 2, PSD_F_MAX_HZ))
        ax.semilogy(f[keep], np.maximum(pp[keep], 1e-30), lw=1.0, color=colour, label=lab)
        n_psd += 1
    if n_psd:
        ax.set_title("Body acceleration PSD" + (f" ({corner})" if corner else ""),
                     fontsize=10, loc="left")
        ax.set_xlabel("f [Hz]")
        ax.set_ylabel("(m/s²)²/Hz")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
        out += img(fig_uri(fig), "overlaid body acceleration PSDs")
    rows = [("Body acceleration", "m/s²", BODY_ACC), ("Tyre force", "N", TYRE_FORCE)]
    if any(p.run.has_arm() for p, _l, _c in members):
        rows.append(("Lower arm: ball joint z", "N", ("plant/arm/ball_joint_z",)))
    fig, axes = _figure(len(rows), row_h=2.4, sharex=True)
    for ax, (title, unit, bases) in zip(axes, rows, strict=True):
        for p, lab, colour in members:
            tab = p.run.table
            _b, cols = first_present(tab, bases)
            if len(cols) > ci:
                ax.plot(*decimate(tab["t"], cols[ci][1]), lw=0.8, color=colour, label=lab,
                        alpha=0.85)
        ax.set_title(title + (f" ({corner})" if corner else ""), fontsize=10, loc="left")
        ax.set_ylabel(unit)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right", ncol=min(4, len(members)))
    axes[-1].set_xlabel("t [s]")
    return out + img(fig_uri(fig), "overlaid time histories")


def sweep_overlay_section(points: list[Point], keys: list[str]) -> str:
    have = [p for p in points if p.run is not None and p.run.table is not None]
    if not have:
        return section("overlay", "PSDs and time histories of the points",
                       note("no point has a table yet."))
    # the corner with the largest body-acceleration RMS in the first point (full vehicle)
    ci = 0
    _b, cols = first_present(have[0].run.table, BODY_ACC)
    if len(cols) > 1:
        ci = int(np.argmax([np.sqrt(np.mean(x * x)) for _c, x in cols]))
    body = ""
    for title, members in overlay_groups(have, keys):
        if title:
            body += f"<h3>{esc(title)}</h3>"
        body += _overlay_figures(members, ci)
    return section("overlay", "PSDs and time histories of the points", body)


def sweep_maps_section(points: list[Point]) -> str:
    figs = []
    missing = []
    for p in points:
        uri = file_uri(p.run.damage_map) if p.run and p.run.damage_map else None
        if uri:
            life = f" · min life {fmt(p.life_km)} km" if p.life_km is not None else ""
            figs.append(f'<figure>{img(uri, f"damage map {p.id}")}<figcaption>'
                        f'<a href="#{anchor_id(p.id)}">{esc(p.id)}</a> · {esc(p.label)}'
                        f"{esc(life)}</figcaption></figure>")
        else:
            missing.append(p.id)
    body = f'<div class="maps">{"".join(figs)}</div>' if figs else ""
    if missing:
        body += note("no damage map for: " + esc(", ".join(missing)))
    return section("maps", "Damage maps of the lower arm", body)


def point_section(p: Point, d: Path) -> str:
    parts = [f'<section id="{anchor_id(p.id)}"><h3>Point {esc(p.id)} {badge(p.status)}</h3>']
    parts.append(kv_table(list(p.params.items()) or [("params", "none")]))
    try:
        rel = p.run_dir.relative_to(d)
    except ValueError:
        rel = p.run_dir
    parts.append(f'<p class="meta">run folder {cmd(str(rel))}')
    if (p.run_dir / "report.html").is_file():
        parts.append(f' · <a href="{esc((rel / "report.html").as_posix())}">its own report</a>')
    else:
        parts.append(f" · its own report: {cmd(f'suscosim report {p.run_dir}')}")
    parts.append("</p>")
    if p.run is None:
        parts.append(note("not run yet (no run folder)."))
    else:
        s = p.run.summary or {}
        if s.get("error"):
            parts.append(f'<div class="error">{esc(s["error"])}</div>')
        pairs = [(k, s.get(k)) for k in ("wall_s", "steps_per_s", "n_steps", "rows") if k in s]
        pairs += [("a_b rms [m/s²]", _rms_of(p, BODY_ACC)),
                  ("F_t rms [N]", _rms_of(p, TYRE_FORCE))]
        if p.run.fatigue:
            pairs += fatigue_numbers(p.run.fatigue)[:5]
        else:
            pairs.append(("fatigue", "no results"))
        parts.append(kv_table(pairs))
    parts.append('<p class="meta"><a href="#results">back to the results</a></p></section>')
    return "".join(parts)


def render_sweep(d: Path) -> str:
    """The HTML page of a sweep folder."""
    spec, points = load_sweep(d)
    keys = grid_keys(spec, points)
    name = str(spec.get("name") or d.name)
    counts: dict[str, int] = {}
    for p in points:
        counts[p.status] = counts.get(p.status, 0) + 1
    head = [f"<h1>Sweep {esc(name)}</h1>",
            f'<p class="meta">folder {cmd(str(d.resolve()))} · report written '
            f"{esc(_dt.datetime.now().strftime('%Y-%m-%d %H:%M:%S'))}</p>"]
    pairs = [("base scenario", spec.get("base")), ("points", len(points)),
             ("status", ", ".join(f"{v} {k}" for k, v in counts.items()) or "none")]
    grid = spec.get("grid")
    if isinstance(grid, dict):
        pairs += [(f"grid: {k}", v) for k, v in grid.items()]
    st = spec.get("set")
    if isinstance(st, dict):
        pairs += [(f"set: {k}", v) for k, v in st.items()]
    elif st:
        pairs.append(("set", st))
    head.append(kv_table(pairs))
    if not points:
        head.append(note("sweep.json lists no points."))
    navs = [("results", "Results"), ("compare", "Comparison"), ("overlay", "PSDs / histories"),
            ("maps", "Damage maps"), ("points", "Points")]
    body = "".join(head) + nav(navs)
    body += sweep_results_section(spec, points, keys, d)
    body += sweep_compare_section(points, keys)
    body += sweep_overlay_section(points, keys)
    body += sweep_maps_section(points)
    body += section("points", "Points", "".join(point_section(p, d) for p in points))
    return page(f"suscosim sweep {name}", body)


# --------------------------------------------------------------------------------- CLI


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="suscosim report",
                                 description="a self-contained HTML report of a run or sweep")
    ap.add_argument("dir", metavar="RUN_OR_SWEEP_DIR", help="a run folder or a sweep folder")
    ap.add_argument("--out", metavar="FILE.html", help="output file (default DIR/report.html)")
    ap.add_argument("--open", action="store_true", help="open the page in a web browser")
    return ap


def _fail(message: str) -> int:
    print(f"suscosim report: {message}", file=sys.stderr)
    return 2


def render(d: Path) -> tuple[str, str]:
    """(kind, HTML) of a run or sweep folder; raises BadInput if it is neither."""
    if not d.is_dir():
        raise BadInput(f"{d}: no such folder")
    if is_sweep_dir(d):
        return "sweep", render_sweep(d)
    if is_run_dir(d):
        return "run", render_run(d)
    raise BadInput(f"{d}: neither a run folder (scenario.json, summary.json, table.*, "
                   "journal.msgpack) nor a sweep folder (sweep.json)")


def main(argv: list[str] | None = None) -> int:
    """Write the report; 0 on success, 2 for bad input (one line on stderr)."""
    try:
        args = build_parser().parse_args(list(sys.argv[1:] if argv is None else argv))
    except SystemExit as exc:
        return 0 if exc.code == 0 else 2
    d = Path(args.dir)
    try:
        kind, text = render(d)
    except BadInput as exc:
        return _fail(str(exc))
    out = Path(args.out) if args.out else d / "report.html"
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(text, encoding="utf-8")
    except OSError as exc:
        return _fail(f"{out}: cannot write ({exc.strerror or exc})")
    print(f"suscosim report: {kind} {d} -> {out} ({len(text) / 1e6:.2f} MB)")
    if args.open:
        import webbrowser

        if not webbrowser.open(out.resolve().as_uri()):
            print(f"suscosim report: no browser found; open {out.resolve().as_uri()}",
                  file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
