"""``suscosim report``: real runs over real Zenoh, then the HTML page of a run and of a sweep.

The runs are short (ch3 step 0.5 s; realistic corner 1.2 s with a coarse fatigue mesh). The
sweep fixture is written here (sweep.json / results.json over two real run folders and one
point not run yet), so these tests do not depend on ``suscosim sweep``. The screenshot test
renders the pages in headless Chromium (Debian package ``chromium``) and checks that the
page and its embedded images were drawn.
"""

from __future__ import annotations

import base64
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import CH3_STEP, COARSE_ARM, ROOT, suscosim

REALISTIC = ROOT / "scenarios" / "ch4_qvm_realistic_bump_pothole.toml"
PNG_URI = re.compile(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"')


def _ok(res: subprocess.CompletedProcess) -> subprocess.CompletedProcess:
    assert res.returncode == 0, f"exit {res.returncode}\n{res.stdout}\n{res.stderr}"
    return res


def _realistic_run(out: Path, law: str, tmp: Path) -> Path:
    scenario = REALISTIC
    if law != "passive":  # the TSS laws take a preset instead of the passive damper's c
        text = REALISTIC.read_text()
        text = text.replace('law = "passive"', f'law = "{law}"\npreset = "realistic"')
        text = re.sub(r"(?m)^c = 3800\.0.*\n", "", text)
        scenario = tmp / f"{law}.toml"
        scenario.write_text(text)
    # no live fatigue node: the batch below writes the run's fatigue results
    _ok(suscosim("run", str(scenario), "--out", str(out), "--quiet", "--set", "run.t_end=1.2",
                 "--set", f"fatigue.influence={COARSE_ARM}", "--set", "fatigue.live=false",
                 timeout=180))
    _ok(suscosim("fatigue", str(out), "--set", f"influence={COARSE_ARM}", timeout=180))
    return out


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> dict[str, Path]:
    """A ch3 run, and a sweep folder with a passive and a TSS1 realistic-corner run (+ fatigue)
    and a third point that has not run."""
    base = tmp_path_factory.mktemp("report")
    ch3 = base / "ch3"
    _ok(suscosim("run", str(CH3_STEP), "--out", str(ch3), "--quiet", "--set", "run.t_end=0.5"))
    sweep = base / "sweep"
    points = [{"id": law, "params": {"controller.law": law}, "run_dir": f"runs/{law}"}
              for law in ("passive", "tss1", "tss2")]
    for law in ("passive", "tss1"):
        _realistic_run(sweep / "runs" / law, law, base)
    (sweep / "sweep.json").write_text(json.dumps({
        "name": "mini", "base": str(REALISTIC), "set": {"run.t_end": 1.2},
        "grid": {"controller.law": ["passive", "tss1", "tss2"]}, "points": points}))
    rows = []
    for p in points:
        d = sweep / p["run_dir"]
        if (d / "summary.json").is_file():
            s = json.loads((d / "summary.json").read_text())
            f = json.loads((d / "fatigue" / "summary.json").read_text())
            rows.append({"id": p["id"], "controller.law": p["id"], "status": s["status"],
                         "error": s["error"], "wall_s": s["wall_s"],
                         "steps_per_s": s["steps_per_s"], "min_life_km": f["min_life_km"]})
        else:
            rows.append({"id": p["id"], "controller.law": p["id"], "status": "pending"})
    (sweep / "results.json").write_text(json.dumps(rows))
    return {"ch3": ch3, "sweep": sweep, "passive": sweep / "runs" / "passive",
            "tss1": sweep / "runs" / "tss1"}


def _g(x: float) -> str:
    """Numbers are shown with 4 significant digits on the page."""
    return f"{x:.4g}"


def assert_self_contained(page: str) -> list[bytes]:
    """No scripts, no remote resources, every image an embedded PNG; returns the PNGs."""
    assert "<script" not in page.lower()
    assert not re.search(r'(?i)(src|href)\s*=\s*["\']?\s*(https?:)?//', page)
    assert not re.search(r"(?i)url\(\s*['\"]?(https?:)?//", page)
    assert "@import" not in page
    srcs = re.findall(r'(?i)<img[^>]*\ssrc="([^"]*)"', page)
    assert srcs, "no images in the page"
    assert all(s.startswith("data:image/png;base64,") for s in srcs), srcs[:3]
    pngs = [base64.b64decode(m) for m in PNG_URI.findall(page)]
    assert len(pngs) == len(srcs)
    assert all(p.startswith(b"\x89PNG\r\n\x1a\n") and len(p) > 2000 for p in pngs)
    return pngs


def test_run_report_lumped_ch3(runs):
    d = runs["ch3"]
    res = _ok(suscosim("report", str(d)))
    out = d / "report.html"
    assert out.is_file() and str(out) in res.stdout
    page = out.read_text()
    pngs = assert_self_contained(page)
    assert len(pngs) >= 3  # time histories, PSDs, tyre load
    for heading in ("Scenario", "Time histories", "Power spectral densities",
                    "RMS and peak of every channel", "Ride metrics",
                    "Tyre and lower-arm load histories", "Fatigue of the lower arm"):
        assert f">{heading}</h2>" in page, heading
    summary = json.loads((d / "summary.json").read_text())
    assert summary["status"] == "ok"
    assert _g(summary["steps_per_s"]) in page and _g(summary["wall_s"]) in page
    assert summary["run_id"] in page
    for name, st in summary["channels"].items():  # the RMS/peak table holds every channel
        row = re.search(rf"<tr><td>{re.escape(name)}</td>(.*?)</tr>", page)
        assert row, name
        assert _g(st["rms"]) in row.group(1) and _g(st["peak"]) in row.group(1), name
    assert "quarter_car_lumped" in page and "has no arm" in page
    assert "no fatigue results" in page


def test_run_report_realistic_with_fatigue(runs, tmp_path):
    d = runs["passive"]
    out = tmp_path / "sub" / "passive.html"
    _ok(suscosim("report", str(d), "--out", str(out)))
    page = out.read_text()
    pngs = assert_self_contained(page)
    for heading in ("Tyre and lower-arm load histories", "Fatigue of the lower arm"):
        assert f">{heading}</h2>" in page
    assert ">Damage map</h3>" in page
    fat = json.loads((d / "fatigue" / "summary.json").read_text())
    for key in ("min_life_km", "min_life_repeats", "max_damage_per_pass"):
        assert _g(fat[key]) in page, key
    assert f"<td>critical node</td><td class=\"num\">{fat['critical_node_id']}</td>" in page
    assert fat["config"]["method"] in page and fat["config"]["mean_stress"] in page
    # the damage map is the fatigue worker's own image, embedded byte for byte
    assert (d / "fatigue" / "damage_map.png").read_bytes() in pngs
    # #26 item 4: the life under both S-N methods and probabilities, the range shown;
    # #30 item 5: the S-N plot with the critical node's cycles
    assert "Life by S-N method" in page
    lo, hi = fat["sn_methods"]["life_range_km"]
    assert lo <= fat["min_life_km"] <= hi and lo < hi
    assert f"{_g(lo)}" in page and f"{_g(hi)}" in page
    assert (d / "fatigue" / "sn_plot.png").read_bytes() in pngs
    # #30 item 1: the map's data (all nodes projected) has the critical node at its damage
    import csv

    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from nodes.fatigue.map_render import draw

    rows = list(csv.DictReader(open(d / "fatigue" / "damage_per_node.csv")))
    xyz = np.array([[float(r[k]) for k in ("x_m", "y_m", "z_m")] for r in rows])
    dmg = np.array([float(r["damage_per_pass"]) for r in rows])
    drawn = draw(Figure(), xyz, dmg, node_ids=[int(r["node_id"]) for r in rows])
    assert drawn["critical_id"] == fat["critical_node_id"]
    assert drawn["projections"]["plan"].value_at(drawn["critical"]) == \
        pytest.approx(fat["max_damage_per_pass"], rel=1e-5)
    import pyarrow.parquet as pq

    arm = [c for c in pq.read_schema(d / "table.parquet").names if c.startswith("plant/arm/")]
    assert arm and all(f"<td>{c}</td>" in page for c in arm)  # each in the RMS/peak table
    assert 'alt="load histories"' in page


def test_sweep_report(runs):
    d = runs["sweep"]
    _ok(suscosim("report", str(d)))
    page = (d / "report.html").read_text()
    pngs = assert_self_contained(page)
    for heading in ("Results", "Comparison", "PSDs and time histories of the points",
                    "Damage maps of the lower arm", "Points"):
        assert f">{heading}</h2>" in page, heading
    life = {law: json.loads((d / "runs" / law / "fatigue" / "summary.json").read_text())
            ["min_life_km"] for law in ("passive", "tss1")}
    change = (life["tss1"] / life["passive"] - 1.0) * 100.0
    row = re.search(r'<tr><td><a href="#point-tss1">tss1</a></td>(.*?)</tr>', page)
    assert row, "no results row for tss1"
    assert _g(life["tss1"]) in row.group(1) and _g(change) in row.group(1)
    assert "life change vs passive" in page
    for law in ("passive", "tss1", "tss2"):  # a section (anchor) per point, linked
        assert f'id="point-{law}"' in page and f'href="#point-{law}"' in page
    assert "not run" in page and "no damage map for: tss2" in page
    for law in ("passive", "tss1"):
        assert (d / "runs" / law / "fatigue" / "damage_map.png").read_bytes() in pngs
    assert "results.json: every column" in page


def test_failed_run_renders_with_journal_data(runs, tmp_path):
    """A failed run that left only its journal: status and error shown, data rebuilt."""
    d = tmp_path / "failed"
    shutil.copytree(runs["ch3"], d)
    for name in ("table.csv", "table.parquet", "report.html"):
        (d / name).unlink(missing_ok=True)
    s = json.loads((d / "summary.json").read_text())
    s.update(status="failed", error="node 'controller' exited with code -9 (see logs)",
             channels={})
    (d / "summary.json").write_text(json.dumps(s))
    _ok(suscosim("report", str(d)))
    page = (d / "report.html").read_text()
    assert_self_contained(page)
    assert 'class="badge failed"' in page
    assert "node &#x27;controller&#x27; exited with code -9" in page
    assert "rebuilt from journal.msgpack" in page
    assert ">Time histories</h2>" in page and 'alt="time histories"' in page
    # the statistics are computed from the rebuilt table and match the recorder's
    ref = json.loads((runs["ch3"] / "summary.json").read_text())["channels"]
    rms = ref["plant/response/a_b"]["rms"]
    assert re.search(rf"<td>plant/response/a_b</td><td>[^<]*</td><td class=\"num\">"
                     rf"{re.escape(_g(rms))}</td>", page)


def test_run_without_summary_or_table_still_renders(tmp_path, runs):
    d = tmp_path / "bare"
    d.mkdir()
    shutil.copy(runs["ch3"] / "scenario.json", d / "scenario.json")
    _ok(suscosim("report", str(d)))
    page = (d / "report.html").read_text()
    assert "no summary.json" in page and "the run recorded nothing" in page
    assert "no fatigue results: run <code>suscosim fatigue" in page
    assert "<script" not in page and not re.search(r"https?://", page)


def test_bad_input_exit_2(tmp_path):
    empty = tmp_path / "empty"
    empty.mkdir()
    res = suscosim("report", str(empty))
    assert res.returncode == 2
    assert "neither a run folder" in res.stderr and "Traceback" not in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
    assert not (empty / "report.html").exists()
    res = suscosim("report", str(tmp_path / "nope"))
    assert res.returncode == 2 and "no such folder" in res.stderr
    bad = tmp_path / "badsweep"
    bad.mkdir()
    (bad / "sweep.json").write_text("{not json")
    res = suscosim("report", str(bad))
    assert res.returncode == 2 and "sweep.json: unreadable" in res.stderr
    assert "Traceback" not in res.stderr


def test_open_calls_the_browser(runs, tmp_path):
    """--open hands the page's file:// URI to the browser (``$BROWSER``, here a recorder)."""
    seen = tmp_path / "opened.txt"
    rec = f"python3 -c \"import sys; open('{seen}', 'w').write(sys.argv[1])\" %s"
    out = tmp_path / "r.html"
    env = dict(os.environ, BROWSER=rec, PYTHONPATH=str(ROOT))
    _ok(subprocess.run([sys.executable, "-m", "orchestrator", "report", str(runs["ch3"]),
                        "--out", str(out), "--open"], cwd=ROOT, env=env, capture_output=True,
                       text=True, timeout=120))
    assert seen.read_text() == out.resolve().as_uri()


def _chromium() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser")


def _screenshot(page: Path, png: Path, tmp: Path) -> np.ndarray:
    exe = _chromium()
    cmd = [exe, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
           "--no-first-run", "--disable-background-networking", "--disable-component-update",
           "--disable-sync", f"--user-data-dir={tmp / 'chromium-profile'}",
           f"--screenshot={png}", "--window-size=1280,2000", page.resolve().as_uri()]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=120,
                         env=dict(os.environ, HOME=str(tmp)))
    assert png.is_file(), f"no screenshot (exit {res.returncode}): {res.stderr[-2000:]}"
    import matplotlib.image as mpimg

    a = mpimg.imread(png)  # float RGB(A) in 0..1
    return np.round(a[..., :3] * 255).astype(int)


def _near(img: np.ndarray, rgb: tuple[int, int, int], tol: int = 12) -> int:
    return int(np.all(np.abs(img - np.asarray(rgb)) <= tol, axis=-1).sum())


@pytest.mark.long  # headless Chromium
@pytest.mark.skipif(_chromium() is None,
                    reason="headless Chromium not installed (Debian: apt-get install -y "
                           "chromium); the HTML report is not screenshot-tested")
def test_screenshot_in_headless_chromium(runs, tmp_path):
    run_page, sweep_page = runs["passive"] / "report.html", runs["sweep"] / "report.html"
    for page, d in ((run_page, runs["passive"]), (sweep_page, runs["sweep"])):
        if not page.exists():  # (written by the tests above when they ran)
            _ok(suscosim("report", str(d)))
    shots = {}
    for page, name in ((run_page, "run"), (sweep_page, "sweep")):
        img = shots[name] = _screenshot(page, tmp_path / f"{name}.png", tmp_path)
        assert img.shape[0] >= 1000 and img.shape[1] >= 1000, img.shape
        colours = np.unique(img.reshape(-1, 3) // 8, axis=0)
        assert len(colours) > 50, f"{name}: only {len(colours)} colours: a blank page?"
        assert img.std() > 20, f"{name}: nearly uniform image"
        # matplotlib's first line/bar colour (C0 #1f77b4): the embedded plots were drawn
        assert _near(img, (31, 119, 180)) > 200, f"{name}: no plot pixels in the screenshot"
    # the run page's green "ok" badge (#2f855a), at the top of the page
    assert _near(shots["run"][:300], (47, 133, 90)) > 100


def test_life_change_vs_passive_on_a_variant_axis(tmp_path):
    """A sweep whose law comes from a named-variant axis (``strategy``, as in
    scenarios/thesis/ch6_fatigue.toml): the passive point of each road is the baseline."""
    from orchestrator.report import Point, law_axis, vs_passive

    life = {("pave", "passive"): 100.0, ("pave", "tss1"): 52.0, ("pave", "tss3"): 4.0,
            ("bump", "passive"): 10.0, ("bump", "tss1"): 15.0, ("bump", "tss3"): None}
    pts = [Point(f"{r}-{s}", {"road": r, "strategy": s}, tmp_path, None,
                 {"road": {"type": r}, "controller": {"law": s}}) for r, s in life]
    keys = ["road", "strategy"]
    assert law_axis(pts, keys) == "strategy"
    change = vs_passive(pts, keys, lambda p: life[(p.params["road"], p.params["strategy"])])
    assert change == pytest.approx({"pave-passive": 0.0, "pave-tss1": -48.0,
                                    "pave-tss3": -96.0, "bump-passive": 0.0,
                                    "bump-tss1": 50.0})
    no_passive = [p for p in pts if p.params["strategy"] != "passive"]
    assert law_axis(no_passive, keys) is None and vs_passive(no_passive, keys, len) == {}
