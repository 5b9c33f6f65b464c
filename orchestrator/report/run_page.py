"""The sections of a run's page (scenario, time histories, PSDs, RMS/peak, ride metrics,
loads, fatigue, logs) and the page itself."""

from __future__ import annotations

import datetime as _dt
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from cosim.coupling_energy import WARNING_THRESHOLD
from cosim.safe_open import read_user_file

from . import markup as mk
from . import signals, stream
from .fatigue_section import fatigue_section
from .plots import MAX_PLOT_POINTS, fig_uri, img, new_figure, plot_panels
from .stream import RunData, load_run

RUN_KEYS = ("name", "id", "mode", "exchange", "coupling", "h", "substeps", "t_end",
            "t_end_source", "n_steps", "nodes")


def run_header(r: RunData, title_prefix: str = "Run") -> str:
    s = r.summary or {}
    out = [f"<h1>{mk.esc(title_prefix)} {mk.esc(r.run_id)} {mk.badge(r.status)}</h1>",
           f'<p class="meta">folder {mk.cmd(str(r.path.resolve()))} · report written '
           f"{mk.esc(_dt.datetime.now().strftime('%Y-%m-%d %H:%M:%S'))}</p>"]
    if r.summary is None:
        out.append(mk.note("no summary.json: the run is still going, or its orchestrator was "
                        "killed before it could write one. Shown: whatever the folder holds."))
    if s.get("error"):
        out.append(f'<div class="error">run failed: {mk.esc(s["error"])}</div>')
    for p in r.problems:
        out.append(mk.note(mk.esc(p)))
    glance = mk.kv_table(at_a_glance(r), "At a glance", cls="kv glance")
    status_tab = ""
    if r.summary is not None:
        labels = {"wall_s": "wall time [s]", "step_wall_s": "stepping wall time [s]",
                  "run_wall_s": "start to all nodes done [s]", "steps_per_s": "coupled steps per s"}
        labels |= {k: k for k in ("n_steps", "rows", "mode", "exchange", "coupling", "h",
                                  "substeps", "t_end")}
        pairs: list[tuple[str, Any]] = [("status", r.status)]
        pairs += [(lab, s[k]) for k, lab in labels.items() if k in s]
        rej = {k: v for k, v in (s.get("rejected_messages") or {}).items() if v}
        pairs.append(("rejected messages", rej or "none"))
        pairs += coupling_residual_rows(s)
        status_tab = mk.kv_table(pairs, "Run")
    out.append(mk.row(glance, status_tab))
    res = s.get("coupling_energy_residual") or {}
    if res.get("total", 0.0) > WARNING_THRESHOLD:
        out.append(mk.note(f"the coupling energy residual ({100 * res['total']:.3g} %) is above "
                        f"{100 * WARNING_THRESHOLD:g} % (about 1 % peak error, "
                        "docs/coupling_residual.md): a smaller run.h or the jacobian coupling "
                        "would be more accurate"))
    return "\n".join(out)


def coupling_residual_rows(s: dict) -> list[tuple[str, Any]]:
    """``summary.json``'s coupling energy residual rows [%]: the total and each bond's."""
    res = s.get("coupling_energy_residual") or {}
    if "total" not in res:
        return []
    rows: list[tuple[str, Any]] = [("coupling energy residual [%]", 100 * res["total"])]
    rows += [(f"  {b} bond [%]", 100 * v) for b, v in res.items() if b != "total"]
    return rows


def _scn(r: RunData, sec: str, key: str) -> Any:
    return ((r.scenario or {}).get(sec) or {}).get(key)


def at_a_glance(r: RunData) -> list[tuple[str, Any]]:
    pairs: list[tuple[str, Any]] = []
    if r.scenario is not None:
        road = r.scenario.get("road") or {}
        parts = (road.get("type"), road.get("class") and f"class {road['class']}",
                 road.get("speed_kmh") and f"{mk.fmt(road['speed_kmh'])} km/h",
                 road.get("length_m") and f"{mk.fmt(road['length_m'])} m")
        pairs += [("vehicle", _scn(r, "vehicle", "model")),
                  ("road", " ".join(str(x) for x in parts if x)),
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


def _idle_run_keys(run: dict) -> set[str]:
    """``run`` keys that do nothing in this run (not shown)."""
    idle = set()
    if not run.get("adaptive"):
        idle |= {"h_min", "h_max", "h_tol"}
    if not run.get("checkpoint_every_s"):
        idle |= {"checkpoint_every_s", "checkpoint_keep"}
    return idle


def scenario_section(r: RunData) -> str:
    if r.scenario is None:
        return mk.section("scenario", "Scenario", mk.note("no scenario.json in the run folder."))
    parts = []
    order = ["run", "vehicle", "road", "tyre", "controller", "fatigue"]
    keys = order + [k for k in r.scenario if k not in order]
    for k in keys:
        v = r.scenario.get(k)
        if v is None:
            continue
        if k == "run":
            idle = _idle_run_keys(v)
            pairs = [(x, v[x]) for x in RUN_KEYS if x in v] + \
                    [(x, y) for x, y in mk.flatten(v)
                     if x not in RUN_KEYS and x != "dir" and x.split(".")[0] not in idle]
        else:
            pairs = mk.flatten(v)
        parts.append(mk.kv_table(pairs, k))
    return mk.section("scenario", "Scenario", mk.row(*parts))


def _source(r: RunData) -> stream.TableSource:
    assert r.source is not None, "a table section of a run without a table"
    return r.source


def streamed_panels(src: stream.TableSource, build: Callable[[dict], tuple[list[tuple], list[str]]]
                    ) -> tuple[list[tuple], list[str], tuple[float, float]]:
    """``build(batch)``'s panels decimated batch by batch, missing titles, first/last t [s]."""
    decs: list[list[stream.StreamDecimator]] | None = None
    shape: list[tuple] = []
    missing: list[str] = []
    t0 = t1 = float("nan")
    for b in src.batches():
        panels, missing = build(b)
        if decs is None:
            t0 = float(b["t"][0])
            shape = panels
            decs = [[stream.StreamDecimator(src.n_rows, MAX_PLOT_POINTS) for _ in lines]
                    for _t, _u, lines in panels]
        for ds, (_t, _u, lines) in zip(decs, panels, strict=True):
            for d, (_lab, y) in zip(ds, lines, strict=True):
                d.add(b["t"], y)
        t1 = float(b["t"][-1])
    out = [(title, unit, [(lab, d.result()) for d, (lab, _y) in zip(ds, lines, strict=True)])
           for ds, (title, unit, lines) in zip(decs or [], shape, strict=True)]
    return out, missing, (t0, t1)


def time_section(r: RunData) -> str:
    src = _source(r)
    panels, missing, (t0, t1) = streamed_panels(src, signals.time_history_panels)
    body = f'<p class="meta">from {mk.esc(r.table_note)}: {src.n_rows} samples, ' \
           f"t = {mk.fmt(t0)} … {mk.fmt(t1)} s</p>"
    if panels:
        body += img(plot_panels(None, panels), "time histories")
    if missing:
        body += mk.note("not in this run's table: " + mk.esc(", ".join(missing)))
    return mk.section("time", "Time histories", body)


def _stream_rate(src: stream.TableSource) -> float | None:
    """Sampling rate [Hz] (median step), None if a step is > 1 % off (ride_metrics' rule)."""
    from nodes.recorder.ride_stream import stream_rate

    try:
        return stream_rate(src.batches(["t"]))
    except ValueError:
        return None


def psd_section(r: RunData) -> str:
    src = _source(r)
    fs = _stream_rate(src)
    if fs is None:
        return mk.section("psd", "Power spectral densities",
                       mk.note("the time column is not uniformly sampled (a run with missing "
                            "steps?): no PSD."))
    n = src.n_rows
    nperseg = stream.psd_nperseg(n)
    sigs: list[tuple[str, str, tuple[str, ...], list[tuple[str, stream.StreamWelch]]]] = []
    for b in src.batches():
        if not sigs:
            wanted: tuple[tuple[str, str, tuple[str, ...]], ...] = (
                ("Body acceleration", "(m/s²)²/Hz", signals.BODY_ACC),
                ("Tyre force", "N²/Hz", signals.TYRE_FORCE))
            for title, unit, bases in wanted:
                _b, cols = signals.first_present(b, bases)
                if cols:
                    sigs.append((title, unit, bases,
                                 [(c, stream.StreamWelch(fs, nperseg)) for c, _x in cols]))
            if not sigs:
                break
        for _t, _u, bases, ws in sigs:
            _b, cols = signals.first_present(b, bases)
            for (_c, w), (_c2, x) in zip(ws, cols, strict=True):
                w.add(x)
    if not sigs:
        return mk.section("psd", "Power spectral densities",
                       mk.note("no body acceleration or tyre force in the table."))
    fmax = min(fs / 2, signals.PSD_F_MAX_HZ)
    fig, axes = new_figure(1, len(sigs), row_h=3.4)
    for ax, (title, unit, _bases, ws) in zip(axes, sigs, strict=True):
        for c, w in ws:
            f, p = w.result()
            keep = (f > 0) & (f <= fmax)
            ax.semilogy(f[keep], np.maximum(p[keep], 1e-30), lw=1.0, label=c or None)
        ax.set_title(title, fontsize=10, loc="left")
        ax.set_xlabel("f [Hz]")
        ax.set_ylabel(unit)
        ax.grid(alpha=0.3, which="both")
        if len(ws) > 1:
            ax.legend(fontsize=7)
    body = img(fig_uri(fig), "PSDs") + (
        f'<p class="meta">Welch, Hann window, {nperseg} samples per segment '
        f"(n/4, at most {stream.PSD_MAX_NPERSEG}), 50 % overlap, mean removed, segments "
        f"accumulated as the table is read; fs = {mk.fmt(fs)} Hz; shown to {mk.fmt(fmax)} Hz.</p>")
    return mk.section("psd", "Power spectral densities", body)


def stats_section(r: RunData) -> str:
    chans = (r.summary or {}).get("channels") or {}
    src = "summary.json"
    if not chans and r.source is not None:
        chans = stream.column_stats(r.source)
        src = r.table_note
    if not chans:
        return mk.section("stats", "RMS and peak of every channel",
                       mk.note("no channel statistics: the run recorded no complete step."))
    rows = [(name, signals.unit_of(name), st.get("rms"), st.get("peak"), st.get("t_peak"),
             st.get("mean"), st.get("std"), st.get("min"), st.get("max"))
            for name, st in sorted(chans.items())]
    body = f'<p class="meta">from {mk.esc(src)}; peak = the value of largest magnitude ' \
           f"(signed), at t_peak.</p>" + mk.table_html(
               ["channel", "unit", "rms", "peak", "t_peak [s]", "mean", "std", "min", "max"],
               rows)
    return mk.section("stats", "RMS and peak of every channel", body)


def streamed_ride_metrics(src: stream.TableSource) -> dict[str, float]:
    """:func:`nodes.recorder.ride_metrics.run_metrics` of the table read in batches."""
    from nodes.recorder.ride_stream import streamed_metric_values

    m = streamed_metric_values(src.names, src.n_rows, lambda cols: src.batches(cols))
    return {label: value for value, _u, label in m.values()}


def ride_section(r: RunData) -> str:
    try:
        m = streamed_ride_metrics(_source(r))
    except (ValueError, KeyError) as exc:
        return mk.section("ride", "Ride metrics", mk.note(f"no ride metrics: {mk.esc(exc)}"))
    if not m:
        return mk.section("ride", "Ride metrics", mk.note("no ride channels in the table."))
    body = mk.table_html(["metric", "value"], list(m.items()), cls="kv") + (
        '<p class="meta">nodes.recorder.ride_metrics.run_metrics: band RMS as the thesis '
        "computes it (resampled to 500 Hz, periodogram of the whole record, Eq 4.8/4.9; the "
        "table read in batches, nodes.recorder.ride_stream), full-band RMS at the "
        "run's own rate, ISO 2631-1 Wk weighting, suspension "
        "working space (SWS), dynamic tyre load (DTL).</p>")
    return mk.section("ride", "Ride metrics", body)


def _load_panels(b: dict) -> tuple[list[tuple], list[str]]:
    panels = []
    _b, ft = signals.first_present(b, signals.TYRE_FORCE)
    if ft:
        panels.append(("Tyre force (vertical, compressive +)", "N",
                       [(signals.corner_label("F_t", c), x) for c, x in ft]))
    for point, comps in signals.arm_groups(b).items():
        unit = "N·m" if all(a.startswith("m") for a, _ in comps) else "N"
        panels.append((f"Lower arm: {point.replace('_', ' ')} (arm frame)", unit, comps))
    return panels, []


def loads_section(r: RunData) -> str:
    src = _source(r)
    panels, _m, _t = streamed_panels(src, _load_panels)
    body = ""
    if panels:
        body += img(plot_panels(None, panels), "load histories")
    if not r.has_arm():
        model = ((r.scenario or {}).get("vehicle") or {}).get("model", "?")
        body += mk.note(f"no lower-arm load channels (<code>plant/arm/...</code>) in this run: the "
                     f"vehicle model {mk.cmd(model)} has no arm. The double-wishbone corner "
                     f"({mk.cmd('quarter_car_double_wishbone')}) reports them.")
    else:
        body += '<p class="meta">Forces on the lower arm at its joints, arm frame ' \
                "(see cosim/channels.py); these drive the fatigue analysis.</p>"
    return mk.section("loads", "Tyre and lower-arm load histories", body)


def logs_section(r: RunData) -> str:
    logs = sorted((r.path / "logs").glob("*.log")) if (r.path / "logs").is_dir() else []
    parts = []
    for p in logs:
        try:
            lines = read_user_file(p, "report", inside=r.path / "logs").decode(
                errors="replace").splitlines()
        except (OSError, ValueError):  # InputFileError: not a regular file, too large
            continue
        lines = [ln for ln in lines if ln.strip() and not ln.startswith("pybullet build time")]
        if lines:
            parts.append(f"<h3>{mk.esc(p.name)}</h3><pre>{mk.esc(chr(10).join(lines[-25:]))}</pre>")
    return mk.section("logs", "Node logs (last lines)", "".join(parts)) if parts else ""


def run_body(r: RunData) -> str:
    """The sections of a run page: the results, then the scenario, the logs of a failed run."""
    parts: list[str] = []
    if r.source is None:
        j = r.path / "journal.msgpack"
        if r.table_note:
            hint = mk.esc(r.table_note)
        elif j.is_file():
            hint = f"run {mk.cmd(f'suscosim export {j}')}"
        else:
            hint = "the run recorded nothing (no journal.msgpack)"
        parts.append(mk.section("time", "Time histories",
                             mk.note(f"no table (table.parquet / table.csv): {hint}.")))
        parts.append(stats_section(r))
    else:
        parts += [time_section(r), psd_section(r), stats_section(r), ride_section(r),
                  loads_section(r)]
    parts.append(fatigue_section(r))
    parts.append(scenario_section(r))
    if r.status != "ok":
        parts.append(logs_section(r))
    return "".join(parts)


RUN_NAV = (("scenario", "Scenario"), ("time", "Time histories"), ("psd", "PSDs"),
           ("stats", "RMS / peak"), ("ride", "Ride metrics"), ("loads", "Loads"),
           ("fatigue", "Fatigue"), ("damage-map", "Damage map"))


def render_run(d: Path) -> str:
    r = load_run(d)
    body = run_header(r) + mk.nav(RUN_NAV) + run_body(r)
    return mk.page(f"suscosim run {r.run_id}", body)
