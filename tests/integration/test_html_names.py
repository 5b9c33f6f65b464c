"""Names from files are text in HTML (issue #43 item 5): a run folder whose run id, node,
channel, part, folder, event and law names hold ``<script>`` or ``"><img onerror=...>`` shows
them as text in the run report, the duty report and the live scope, loaded in headless
Chromium (the browser the scope and report tests use): no element of the payload is made,
no script of it runs."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import time
from pathlib import Path

import pytest

from cosim.wire import Message
from orchestrator.scope.server import ScopeServer
from orchestrator.scope.state import ScopeState, Selection

from ..conftest import CH3_STEP, suscosim

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
SCRIPT = "<script>document.documentElement.setAttribute('data-pwned','script')</script>"
IMG = "\"><img src=x onerror=\"document.documentElement.setAttribute('data-pwned','img')\">"
EVIL = f"x{SCRIPT}{IMG}"

pytestmark = pytest.mark.long  # every test loads its page in headless Chromium


def _dom(url: str, tmp: Path, budget_ms: int = 3000) -> str:
    assert CHROMIUM, "headless Chromium not installed (Debian: apt-get install -y chromium)"
    cmd = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
           "--no-first-run", "--disable-background-networking", "--disable-component-update",
           "--disable-sync", f"--user-data-dir={tmp / f'chromium-{time.monotonic_ns()}'}",
           f"--virtual-time-budget={budget_ms}", "--dump-dom", url]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=120,
                         env=dict(os.environ, HOME=str(tmp)))
    assert "<html" in res.stdout, res.stderr[-2000:]
    return res.stdout


def _as_text(dom: str) -> None:
    """The payload made nothing: no attribute set by it, no <script>/<img> element of it, and
    its text is there, escaped."""
    assert 'data-pwned="' not in dom
    assert "<script>document" not in dom and "<img src=\"x\"" not in dom
    assert "&lt;script&gt;document" in dom


def _poison(x):
    """Every string of a JSON document (keys and values) with the payload appended."""
    if isinstance(x, dict):
        return {_poison(k): _poison(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_poison(v) for v in x]
    return x + EVIL if isinstance(x, str) else x


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("names") / "run"
    r = suscosim("run", str(CH3_STEP), "--out", str(out), "--quiet", "--set", "run.t_end=0.2",
                 timeout=180)
    assert r.returncode == 0, r.stdout + r.stderr
    return out


def test_the_run_report_shows_hostile_names_as_text(run_dir, tmp_path):
    d = tmp_path / "run"
    shutil.copytree(run_dir, d)
    for f in (d / "table.parquet", d / "report.html"):
        f.unlink(missing_ok=True)
    sc = json.loads((d / "scenario.json").read_text())
    sc["run"]["id"] = sc["run"]["name"] = EVIL
    (d / "scenario.json").write_text(json.dumps(sc))
    sm = json.loads((d / "summary.json").read_text())
    sm["channels"] = _poison(sm.get("channels", {}))
    sm["nodes"] = _poison(sm.get("nodes", {}))
    sm["error"] = EVIL
    (d / "summary.json").write_text(json.dumps(sm))
    lines = (d / "table.csv").read_text().splitlines()
    head = lines[0].split(",")
    lines[0] = ",".join([head[0], *(f'"{h}{EVIL.replace(chr(34), chr(39))}"'
                                    for h in head[1:])])
    (d / "table.csv").write_text("\n".join(lines) + "\n")
    (d / "fatigue").mkdir(exist_ok=True)
    part = {"name": EVIL, "folder": EVIL, "load_channel": EVIL, "min_life_km": 1.0}
    (d / "fatigue" / "summary.json").write_text(json.dumps({
        "source": EVIL, "parts": [part, dict(part)], "not_computed": {EVIL: EVIL}}))
    r = suscosim("report", str(d))
    assert r.returncode == 0, r.stdout + r.stderr
    page = (d / "report.html").read_text()
    assert "<script" not in page and "<img src=x" not in page
    _as_text(_dom((d / "report.html").resolve().as_uri(), tmp_path))


def test_the_duty_report_shows_hostile_event_and_law_names_as_text(tmp_path):
    d = tmp_path / "duty"
    d.mkdir()
    event = {"name": EVIL, "repeats": 2, "pass_length_m": 100.0, "distance_km": 0.2,
             "max_damage_per_pass": 1e-9, "own_critical_node_id": 3,
             "damage_per_schedule_at_critical": 2e-9, "share_at_critical": 1.0, "run_dir": EVIL}
    law = {"name": EVIL, "life_schedules": 10.0, "life_km": 2.0, "critical_node_id": 3,
           "dominant_event": EVIL, "dominant_share": 1.0,
           "damage_per_schedule_at_node": [2e-9], "ratio_to_reference": [1.0],
           "damage_per_schedule_at_node_total": 2e-9}
    (d / "duty.json").write_text(json.dumps({
        "name": EVIL, "events": [event], "critical_node_id": 3, "dominant_event": EVIL,
        "dominant_share": 1.0, "laws": {"laws": [law, dict(law)], "reference": EVIL,
                                        "node_id": EVIL, "events": [EVIL]}}))
    r = suscosim("report", str(d))
    assert r.returncode == 0, r.stdout + r.stderr
    page = (d / "report.html").read_text()
    assert "<script" not in page and "<img src=x" not in page
    _as_text(_dom((d / "report.html").resolve().as_uri(), tmp_path))


def test_the_scope_shows_hostile_node_and_channel_names_as_text(tmp_path):
    node, channel = f"n{EVIL}", f"c{EVIL}"
    state = ScopeState(EVIL, Selection(["*/*"]), source="replay", n_steps=10, h=0.01,
                       nodes=[node])
    state.node_event(node, "error", 3, 0.03, info=EVIL)
    for k in range(5):
        state.add_data(node, channel, Message("data", k, 0.01 * k, {"v": float(k)}))
    state.run_event("failed", reason=EVIL)
    server = ScopeServer(state)
    server.start()
    try:
        dom = _dom(server.url, tmp_path)
    finally:
        server.close()
    _as_text(dom)
    assert '<tr data-node="nx&lt;script&gt;' in dom  # the node's row was drawn
    assert 'class="card plot" data-group="nx&lt;script&gt;' in dom  # and its channel's plot
