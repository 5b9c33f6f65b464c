"""``suscosim scope``: a real run over real Zenoh, the scope's web server, headless Chromium.

* A Chapter 3 run watched live: two ``/data`` reads while it runs have increasing step
  indices and the samples of the run's table; the page, loaded in headless Chromium (while
  the run goes, unless it has already ended), shows the data (the last step index and the
  plots' points in the DOM after its script ran); the run's table is bit-identical to the
  same run without the scope.
* The same run replayed from its journal: every step, in order, then every node done.
* The realistic corner with the live fatigue node (``ch6_realistic_qvm.toml``, 0.6 s): the
  page draws the damage map, and at the last step the scope's map has the run's own
  ``fatigue/summary.json`` numbers.
* Bad input: exit 2 with a message, no traceback.

The browser parts skip with a reason when Chromium is not installed (the rest still runs).
"""

from __future__ import annotations

import json
import os
import re
import select
import shutil
import signal
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest

from cosim.bus import free_loopback_endpoint
from cosim.table import read_table

from ..conftest import CH3_STEP, COARSE_ARM, ROOT, node_pids, popen_suscosim, suscosim

pytestmark = pytest.mark.integration

T_END = "3.0"  # s: 3000 steps of the ch3 quarter car, a few seconds of wall time
REALISTIC = ROOT / "scenarios" / "thesis" / "ch6_realistic_qvm.toml"
REALISTIC_SET = ("--set", "run.t_end=0.6",
                 "--set", f"fatigue.influence={COARSE_ARM}", "--set",
                 "run.stall_timeout_s=60")
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
NO_CHROMIUM = "headless Chromium not installed (Debian: apt-get install -y chromium): the " \
              "page is not loaded in a browser"


# ---- helpers ---------------------------------------------------------------------------
def _wait_json(path: Path, proc: subprocess.Popen, timeout: float = 90.0) -> dict:
    """The JSON file once it is written (it may be seen empty for a moment)."""
    deadline = time.monotonic() + timeout
    while True:
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, f"{path} not written"
        try:
            return json.loads(path.read_text())
        except (OSError, ValueError):
            time.sleep(0.05)


def _start_scope(*args: str, env: dict | None = None) -> tuple[subprocess.Popen, str]:
    """Start ``suscosim scope ARGS --port 0``; return it and the URL it printed."""
    if env is None:
        proc = popen_suscosim("scope", *args, "--port", "0")
    else:
        proc = subprocess.Popen([sys.executable, "-m", "orchestrator", "scope", *args, "--port",
                                 "0"], cwd=ROOT, env={**env, "PYTHONPATH": str(ROOT)},
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    line = ""
    while "http://" not in line:
        assert time.monotonic() < deadline, "the scope printed no URL"
        ready, _, _ = select.select([proc.stdout], [], [], 1.0)
        if ready:
            line = proc.stdout.readline()
            assert line, f"the scope ended: {proc.communicate()}"
    proc.first_line = line
    return proc, re.search(r"(http://\S+/)", line).group(1)


def _stop(proc: subprocess.Popen) -> str:
    """SIGTERM the scope; it ends with exit 0 and no traceback; returns its stderr."""
    proc.send_signal(signal.SIGTERM)
    _out, err = proc.communicate(timeout=30)
    assert proc.returncode == 0, err
    assert "Traceback" not in err, err
    return err


def _data(url: str, since: int = -1) -> dict:
    with urllib.request.urlopen(f"{url}data?since={since}", timeout=10) as r:
        assert r.headers["Content-Type"] == "application/json"
        return json.loads(r.read())


def _until(url: str, ok, timeout: float = 120.0, since: int = -1) -> dict:
    deadline = time.monotonic() + timeout
    while True:
        d = _data(url, since)
        if ok(d):
            return d
        assert time.monotonic() < deadline, {k: d[k] for k in ("k", "run_state", "nodes")}
        time.sleep(0.1)


def _chromium(url: str, tmp: Path, *, dom: bool = True, png: Path | None = None,
              budget_ms: int = 4000) -> str:
    """Load the page in headless Chromium, let its script run ``budget_ms`` of virtual
    time; return the DOM (or write a screenshot)."""
    cmd = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
           "--no-first-run", "--disable-background-networking", "--disable-component-update",
           "--disable-sync", f"--user-data-dir={tmp / f'chromium-{time.monotonic_ns()}'}",
           f"--virtual-time-budget={budget_ms}", "--window-size=1500,1150"]
    cmd += ["--dump-dom"] if dom else [f"--screenshot={png}"]
    res = subprocess.run([*cmd, url], capture_output=True, text=True, timeout=120,
                         env=dict(os.environ, HOME=str(tmp)))
    if png is not None:
        assert png.is_file(), f"no screenshot (exit {res.returncode}): {res.stderr[-2000:]}"
    return res.stdout


def _dom_step(dom: str) -> int:
    m = re.search(r'id="last-k" data-k="(-?\d+)"', dom)
    assert m, dom[:3000]
    return int(m.group(1))


# ---- a live run, and the same run without the scope ---------------------------------------
@pytest.fixture(scope="module")
def unwatched(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("unwatched") / "run"
    res = suscosim("run", str(CH3_STEP), "--out", str(out), "--quiet", "--set",
                   f"run.t_end={T_END}", "--set", 'run.id="scopebase"', timeout=180)
    assert res.returncode == 0, res.stdout + res.stderr
    return out


@pytest.fixture(scope="module")
def watched(tmp_path_factory, request) -> dict:
    """The run with a scope on it: two /data reads and the page's DOM while it runs (when
    the Chromium test, marker ``long``, is selected), the last /data after it ended."""
    tmp = tmp_path_factory.mktemp("watched")
    dom_wanted = CHROMIUM and any(i.name == "test_the_page_loads_the_data_in_chromium"
                                  for i in request.session.items)
    out = tmp / "run"
    run = popen_suscosim("run", str(CH3_STEP), "--out", str(out), "--quiet", "--listen",
                         free_loopback_endpoint(), "--set", f"run.t_end={T_END}",
                         "--set", 'run.id="scopetest"')
    scope = None
    seen: dict = {"out": out}
    try:
        _wait_json(out / "run.json", run)
        scope, url = _start_scope(str(out), "--channels", "plant/state", "tyre_road/force/F_t")
        first = _until(url, lambda d: d["k"] >= 0)
        seen["first_running"] = run.poll() is None
        second = _until(url, lambda d: d["k"] > first["k"] + 50, since=first["k"])
        seen["second_running"] = run.poll() is None
        if dom_wanted:  # (while the run goes, if it still does)
            seen["dom"] = _chromium(url, tmp)
        seen["first"], seen["second"] = first, second
        stdout, stderr = run.communicate(timeout=180)
        assert run.returncode == 0, stdout + stderr
        seen["last"] = _until(url, lambda d: d["run_state"] == "done" and all(
            n["state"] == "done" for n in d["nodes"].values()), timeout=60)
        seen["stderr"] = _stop(scope)
    finally:
        for p in (run, scope):
            if p is not None and p.poll() is None:
                p.kill()
    return seen


def test_scope_data_advance_while_the_run_goes(watched) -> None:
    first, second, last = watched["first"], watched["second"], watched["last"]
    assert watched["first_running"] and watched["second_running"]
    assert first["run"] == "scopetest" and first["source"] == "live"
    assert first["n_steps"] == 3000 and second["k"] > first["k"] >= 0
    table = read_table(watched["out"] / "table.parquet")
    # the second read holds only steps after the first read's, each the recorded value
    z_b = second["lines"]["plant/state/z_b"]
    assert z_b["k"] and z_b["k"][0] > first["k"] and z_b["unit"] == "m"
    assert z_b["k"] == list(range(z_b["k"][0], z_b["k"][-1] + 1))
    assert np.array_equal(z_b["y"], table["plant/state/z_b"][z_b["k"]])
    assert np.allclose(z_b["t"], table["t"][z_b["k"]], rtol=0, atol=1e-12)
    assert second["lines"]["tyre_road/force/F_t"]["unit"] == "N"
    assert "controller/force/F_d" not in second["lines"]  # not chosen with --channels
    assert set(second["lines"]) == {f"plant/state/{f}" for f in ("z_b", "v_b", "z_w", "v_w")} \
        | {"tyre_road/force/F_t"}
    assert second["steps_per_s"] > 0
    # after the run: every step seen, every node done, the progress full
    assert last["k"] == 3000 and last["progress"] == 1.0 and last["undecodable"] == 0
    assert {n: v["state"] for n, v in last["nodes"].items()} == {
        n: "done" for n in ("plant", "tyre_road", "controller", "recorder")}
    assert "run scopetest done at step 3000" in watched["stderr"]


def test_the_watched_run_is_the_unwatched_run(watched, unwatched) -> None:
    summary = json.loads((watched["out"] / "summary.json").read_text())
    assert summary["status"] == "ok" and not any(summary["rejected_messages"].values())
    base, mine = read_table(unwatched / "table.csv"), read_table(watched["out"] / "table.csv")
    assert set(base) == set(mine)
    for col in base:
        assert np.array_equal(base[col], mine[col]), col


@pytest.mark.long  # headless Chromium
@pytest.mark.skipif(CHROMIUM is None, reason=NO_CHROMIUM)
def test_the_page_loads_the_data_in_chromium(watched) -> None:
    dom = watched["dom"]
    k = _dom_step(dom)
    assert 0 <= k <= 3000, k
    assert 'id="run-id" class="mono">scopetest<' in dom
    plots = re.findall(r'class="card plot" data-group="([^"]+)" data-rank="\d+" '
                       r'data-last-k="(\d+)" data-points="(\d+)"', dom)
    assert {g for g, _k, _n in plots} == {"plant/state/z_b", "plant/state/v_b",
                                          "plant/state/z_w", "plant/state/v_w",
                                          "tyre_road/force/F_t"}, plots
    assert plots[-1][0] == "tyre_road/force/F_t"  # in the order of --channels
    assert all(int(n) > 10 and int(lk) <= k for _g, lk, n in plots), plots
    assert dom.count("<canvas") >= len(plots)  # uPlot drew each plot on a canvas
    assert 'data-node="plant"' in dom


# ---- a finished run, replayed -------------------------------------------------------------
def test_scope_replays_a_finished_run(unwatched) -> None:
    scope, url = _start_scope(str(unwatched), "--speed", "3")
    try:
        first = _until(url, lambda d: d["k"] >= 0)
        assert first["source"] == "replay" and first["run"] == "scopebase"
        second = _until(url, lambda d: d["k"] > first["k"], since=first["k"])
        assert second["run_state"] == "stepping" and second["k"] < 3000
        last = _until(url, lambda d: d["run_state"] == "done")
        every = _data(url)
        _stop(scope)
    finally:
        if scope.poll() is None:
            scope.kill()
    assert last["k"] == 3000 and all(n["state"] == "done" for n in last["nodes"].values())
    table = read_table(unwatched / "table.parquet")
    for name in ("plant/state/z_b", "plant/response/a_b", "tyre_road/force/F_t",
                 "controller/force/F_d"):
        line = every["lines"][name]
        assert line["k"] == list(range(3001)), name  # every step, in order
        assert np.array_equal(line["y"], table[name]), name


def test_a_killed_node_is_gone_on_the_page(tmp_path) -> None:
    """SIGKILL the controller mid-run: its liveliness token drops, the scope shows it gone
    and the run failed with the orchestrator's reason; the others are not 'done'."""
    out = tmp_path / "run"
    run = popen_suscosim("run", str(CH3_STEP), "--out", str(out), "--quiet", "--listen",
                         free_loopback_endpoint(), "--set", "run.t_end=20.0", "--set",
                         'run.id="scopekill"')
    scope = None
    try:
        _wait_json(out / "run.json", run)
        scope, url = _start_scope(str(out))
        _until(url, lambda d: d["k"] > 300)
        pids = node_pids("scopekill", "controller")
        assert pids, "controller process not found"
        for pid in pids:
            os.kill(pid, signal.SIGKILL)
        last = _until(url, lambda d: d["run_state"] == "failed"
                      and d["nodes"]["controller"]["state"] == "gone", timeout=60)
        run.communicate(timeout=120)
        _stop(scope)
    finally:
        for p in (run, scope):
            if p is not None and p.poll() is None:
                p.kill()
    assert run.returncode == 1
    assert "controller" in last["reason"], last["reason"]
    assert 300 < last["k"] < 20000
    assert last["nodes"]["plant"]["state"] != "done"


# ---- through a router, as from another machine -------------------------------------------
def test_scope_through_a_router_by_run_id(tmp_path) -> None:
    """A run whose nodes meet at a router; the scope knows only the run id and the router
    (what a scope on another machine has) and is a client of the router."""
    ep = free_loopback_endpoint()
    router = popen_suscosim("router", "--listen", ep)
    run = scope = None
    try:
        line = router.stdout.readline()
        assert "listening on" in line, line + router.stderr.read()
        out = tmp_path / "run"
        run = popen_suscosim("run", str(CH3_STEP), "--out", str(out), "--quiet", "--connect",
                             ep, "--set", "run.t_end=2.0", "--set", 'run.id="scoperouter"')
        _wait_json(out / "run.json", run)
        scope, url = _start_scope("scoperouter", "--connect", ep, "--mode", "client")
        first = _until(url, lambda d: d["k"] >= 0)
        second = _until(url, lambda d: d["k"] > first["k"], since=first["k"])
        stdout, stderr = run.communicate(timeout=180)
        assert run.returncode == 0, stdout + stderr
        last = _until(url, lambda d: d["run_state"] == "done" and all(
            n["state"] == "done" for n in d["nodes"].values()), timeout=60)
        err = _stop(scope)
    finally:
        for p in (run, scope, router):
            if p is not None and p.poll() is None:
                p.terminate()
                p.communicate(timeout=30)
    assert f"run scoperouter, live via {ep} (client session)" in scope.first_line
    assert second["k"] > first["k"] >= 0 and second["source"] == "live"
    # n_steps and the node list came from the run's orchestrator (its scenario queryable)
    assert last["n_steps"] == 2000 and last["k"] == 2000
    assert set(last["nodes"]) == {"plant", "tyre_road", "controller", "recorder"}
    table = read_table(out / "table.parquet")
    z_b = last["lines"]["plant/state/z_b"]
    assert np.array_equal(z_b["y"], table["plant/state/z_b"][z_b["k"]])
    assert "run scoperouter done at step 2000" in err


def test_scope_started_by_run_id_before_its_run(tmp_path) -> None:
    """Started first (nothing listens at the endpoint yet), the scope finds the run when it
    comes and learns its scenario from the run's orchestrator then."""
    ep = free_loopback_endpoint()
    scope, url = _start_scope("scopefirst", "--connect", ep)
    run = None
    try:
        empty = _data(url)
        assert empty["k"] == -1 and empty["n_steps"] is None and empty["nodes"] == {}
        run = popen_suscosim("run", str(CH3_STEP), "--out", str(tmp_path / "run"), "--quiet",
                             "--listen", ep, "--set", "run.t_end=2.0", "--set",
                             'run.id="scopefirst"')
        stdout, stderr = run.communicate(timeout=180)
        assert run.returncode == 0, stdout + stderr
        last = _until(url, lambda d: d["run_state"] == "done" and d["k"] == 2000, timeout=60)
        _stop(scope)
    finally:
        for p in (run, scope):
            if p is not None and p.poll() is None:
                p.kill()
    assert last["n_steps"] == 2000 and last["progress"] == 1.0
    assert {n: v["state"] for n, v in last["nodes"].items()} == {
        n: "done" for n in ("plant", "tyre_road", "controller", "recorder")}


# ---- the damage map of a realistic run with live fatigue --------------------------------------
@pytest.mark.long  # headless Chromium: the map's DOM and a screenshot of it
def test_damage_map_of_a_realistic_run_with_live_fatigue(tmp_path) -> None:
    out = tmp_path / "ch6"
    run = popen_suscosim("run", str(REALISTIC), "--out", str(out), "--quiet", "--listen",
                         free_loopback_endpoint(), *REALISTIC_SET)
    scope = None
    try:
        _wait_json(out / "run.json", run)
        scope, url = _start_scope(str(out), "--channels", "plant/arm/ball_joint_*")
        stdout, stderr = run.communicate(timeout=300)
        assert run.returncode == 0, stdout + stderr
        last = _until(url, lambda d: (d["damage_map"] or {}).get("final")
                      and (d["fatigue"] or {}).get("k") == d["n_steps"], timeout=60)
        shot = None
        if CHROMIUM:
            shot = tmp_path / "scope.png"
            dom = _chromium(url, tmp_path)
            _chromium(url, tmp_path, dom=False, png=shot)
        _stop(scope)
    finally:
        for p in (run, scope):
            if p is not None and p.poll() is None:
                p.kill()
    fs = json.loads((out / "fatigue" / "summary.json").read_text())
    assert fs["source"] == "live"
    dm, fat = last["damage_map"], last["fatigue"]
    n = int(round(0.6 / 0.0005))
    assert last["n_steps"] == n and dm["k"] == n and dm["from_k"] == 0
    assert dm["missing_steps"] == 0
    # the scope's map (its own LiveFatigue on the plant/arm messages) is the node's result
    assert dm["max_damage"] == pytest.approx(fs["max_damage_per_pass"], rel=1e-9)
    assert dm["critical_node_id"] == fs["critical_node_id"]
    assert dm["life_km"] == pytest.approx(fs["min_life_km"], rel=1e-9)
    # and the fatigue node's own live message says the same minimum life
    assert fat["life_km"] == pytest.approx(fs["min_life_km"], rel=1e-9)
    logd = [v for v in dm["log10_damage"] if v is not None]
    assert len(dm["log10_damage"]) == fs["n_nodes"] and logd
    assert max(logd) == pytest.approx(np.log10(fs["max_damage_per_pass"]), abs=1e-3)
    assert last["lines"]["plant/arm/ball_joint_z"]["unit"] == "N"
    if not CHROMIUM:
        pytest.skip(NO_CHROMIUM + " (the map's numbers were checked)")
    m = re.search(r'id="damage-map"[^>]*data-drawn="(\d+)" data-k="(\d+)"', dom)
    assert m and int(m.group(1)) == fs["n_nodes"] and int(m.group(2)) == n, dom[:3000]
    life = re.search(r'id="min-life">([^<]+)<', dom).group(1)
    assert float(life) == pytest.approx(fs["min_life_km"], rel=1e-3)
    import matplotlib.image as mpimg

    img = np.round(mpimg.imread(shot)[..., :3] * 255).astype(int)
    # the map's dark purple (inferno's most damaged end: the colour bar and the worst nodes)
    purple = [np.all(np.abs(img - c) <= 20, axis=-1).sum() for c in ((64, 10, 103),
                                                                   (120, 28, 109))]
    assert min(purple) > 20, f"no damage colours in the screenshot: {purple}"


# ---- bad input -----------------------------------------------------------------------------
@pytest.mark.parametrize(("args", "message"), [
    (["nosuch/folder"], "no such run folder"),
    (["r1", "--channels", "a/b/c/d"], "expected NODE/CHANNEL[/FIELD]"),
    (["r1", "--channels", "plant/ctl"], "control channel"),
    (["r1", "--speed", "0"], "--speed 0"),
    (["r1", "--port", "70000"], "--port 70000"),
])
def test_bad_input_exits_2(args, message, capsys) -> None:
    from orchestrator.scope import main

    assert main(args) == 2  # (checked before any session or server is opened)
    assert message in capsys.readouterr().err


def test_a_finished_run_without_journal_and_a_busy_port(tmp_path, unwatched) -> None:
    (tmp_path / "summary.json").write_text("{}")
    res = suscosim("scope", str(tmp_path), timeout=60)
    assert res.returncode == 2 and "no such journal file" in res.stderr, res.stderr
    scope, url = _start_scope(str(unwatched), "--fast")
    try:
        port = url.rsplit(":", 1)[1].strip("/")
        res = suscosim("scope", str(unwatched), "--port", port, timeout=60)
        assert res.returncode == 2 and f"cannot serve on 127.0.0.1:{port}" in res.stderr
        with pytest.raises(urllib.error.HTTPError) as e:
            urllib.request.urlopen(f"{url}data?since=x", timeout=10)
        assert e.value.code == 400
    finally:
        _stop(scope)


# ---- the state behind /data (no processes) -------------------------------------------------
def test_state_gives_the_samples_after_since_and_the_node_states() -> None:
    from cosim.wire import Message
    from orchestrator.scope.state import ScopeState, Selection

    st = ScopeState("r1", Selection(["plant/state/z_*", "tyre_road/force"]), n_steps=9,
                    nodes=["plant", "tyre_road"], max_samples=5)
    st.node_event("plant", "up")
    st.node_event("plant", "ready")
    for k in range(10):
        st.add_data("plant", "state", Message("data", k, k * 0.1, {
            "z_b": [0.1 * k, 0.2, 0.3, float("nan")], "v_b": [1.0] * 4, "z_w": 2.0 * k}),
            now=float(k))
    d = st.snapshot(6, now=9.5)
    assert d["k"] == 9 and d["progress"] == 1.0 and d["steps_per_s"] == pytest.approx(1.0)
    assert set(d["lines"]) == {f"plant/state/z_b[{i}]" for i in range(4)} | {"plant/state/z_w"}
    fl, rr = d["lines"]["plant/state/z_b[0]"], d["lines"]["plant/state/z_b[3]"]
    assert (fl["label"], fl["unit"], fl["group"]) == ("z_b FL", "m", "plant/state/z_b")
    assert fl["k"] == [7, 8, 9] and fl["y"] == pytest.approx([0.7, 0.8, 0.9])
    assert rr["y"] == [None, None, None]  # NaN: JSON has none
    assert st.snapshot(-1)["lines"]["plant/state/z_w"]["k"] == [5, 6, 7, 8, 9]  # the last 5
    assert d["nodes"]["plant"]["state"] == "stepping" and d["nodes"]["tyre_road"]["state"] \
        == "waiting"
    st.node_event("plant", "done", 9, 0.9)
    st.node_event("plant", "gone")  # its token drops after done: still done
    st.node_event("tyre_road", "stepping", 3)
    st.node_event("tyre_road", "gone")  # dropped while stepping
    st.node_event("tyre_road", "ready")  # a late message does not bring it back
    nodes = st.snapshot()["nodes"]
    assert (nodes["plant"]["state"], nodes["tyre_road"]["state"]) == ("done", "gone")
    st.set_map(None, {"k": 5, "log10_damage": [-3.0]})
    assert st.snapshot(4)["damage_map"]["log10_damage"] == [-3.0]
    assert "log10_damage" not in st.snapshot(5)["damage_map"]  # unchanged since step 5
    assert json.dumps(st.snapshot(-1), allow_nan=False)


def test_channel_patterns() -> None:
    from orchestrator.scope.state import ScopeInputError, Selection, parse_pattern

    sel = Selection(["*/force/F_*", "plant/arm"])
    assert sel.keyexprs("r1") == ["suscosim/r1/*/force", "suscosim/r1/plant/arm"]
    assert sel.wants("controller", "force") and not sel.wants("controller", "ctl")
    assert [ln.unit for ln in sel.lines("tyre_road", "force", "F_t", 0)] == ["N"]
    assert sel.lines("tyre_road", "force", "k_t", 0) == []
    arm = sel.lines("plant", "arm", "torsion_bar_mx", 0)
    assert arm[0].unit == "N·m" and arm[0].rank == 1
    assert parse_pattern("plant/state").field is None
    for bad in ("plant", "a/b/c/d", "pl ant/state", "plant/records"):
        with pytest.raises(ScopeInputError):
            parse_pattern(bad)


def test_open_hands_the_url_to_the_browser(tmp_path, unwatched) -> None:
    """--open gives the page's URL to the browser (``$BROWSER``, here a recorder)."""
    seen = tmp_path / "opened.txt"
    rec = f"{sys.executable} -c \"import sys; open('{seen}', 'w').write(sys.argv[1])\" %s"
    scope, url = _start_scope(str(unwatched), "--fast", "--open",
                              env=dict(os.environ, BROWSER=rec))
    try:
        deadline = time.monotonic() + 30
        while not seen.exists() or not seen.read_text():
            assert time.monotonic() < deadline, "the browser was not called"
            time.sleep(0.1)
        assert seen.read_text() == url
    finally:
        _stop(scope)


# ---- the Host header (DNS rebinding, #30 item 16; a real server, no run) --------------------
def _get_with_host(port: int, host: str | None) -> int:
    """The status of ``GET /meta`` sent to 127.0.0.1:port with ``Host: host`` (None: none)."""
    import http.client

    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    try:
        conn.putrequest("GET", "/meta", skip_host=True)
        if host is not None:
            conn.putheader("Host", host)
        conn.endheaders()
        return conn.getresponse().status
    finally:
        conn.close()


def test_the_scope_answers_only_to_loopback_host_names() -> None:
    from orchestrator.scope.server import ScopeServer, allowed_hosts, host_header_ok
    from orchestrator.scope.state import ScopeState, Selection

    server = ScopeServer(ScopeState("r1", Selection(["plant/state"])), "127.0.0.1", 0)
    server.start()
    try:
        port = server.httpd.server_address[1]
        for ok in (f"localhost:{port}", f"127.0.0.1:{port}", f"[::1]:{port}",
                   f"LOCALHOST:{port}"):
            assert _get_with_host(port, ok) == 200, ok
        for bad in (f"evil.example:{port}", "evil.example", f"localhost:{port + 1}",
                    "localhost", f"127.0.0.1.evil.example:{port}", f"10.0.0.1:{port}", None):
            assert _get_with_host(port, bad) == 403, bad
    finally:
        server.close()
    # served on every address: loopback names, this machine's names and IP literals
    names, any_ip = allowed_hosts("0.0.0.0")
    assert any_ip and "localhost" in names
    assert host_header_ok("192.168.1.5:8470", names, any_ip, 8470)
    assert host_header_ok("[fe80::1]:8470", names, any_ip, 8470)
    assert not host_header_ok("evil.example:8470", names, any_ip, 8470)
    names, any_ip = allowed_hosts("192.168.1.5")
    assert not any_ip and host_header_ok("192.168.1.5:80", names, any_ip, 80)
    assert host_header_ok("192.168.1.5", names, any_ip, 80)
    assert not host_header_ok("192.168.1.6:80", names, any_ip, 80)
