// suscosim scope: polls /data?since=K, keeps the samples per line, draws them with uPlot
// (rolling window, autoscale, pause), the node states, the progress, the damage map and the
// coupling residual (recorder/coupling: the running relative residual per bond, the
// warning threshold drawn).
"use strict";
const COLOURS = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b",
                 "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"];
const POLL_MS = 250;
const LAG_MAX = 5000;  // steps
const MAX_POINTS = 200000;  // per line, in the page
const S = {lines: {}, groups: {}, plots: {}, paused: false, windowS: 5, geometry: null,
           map: null, fatigue: null, last: null, fetchingMeta: false,
           coupling: {k: [], t: [], rel: {}, last: null, plot: null, bonds: []}};

const $ = (id) => document.getElementById(id);
// names come from the run (node, channel, unit, a node's message): text, never markup (#43)
const ESC = {"&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&#39;"};
const esc = (s) => String(s).replace(/[&<>"']/g, (c) => ESC[c]);
const fmt = (x, n = 4) => (x === null || x === undefined) ? "-" :
  (typeof x === "number" ? (Math.abs(x) >= 1e5 || (x !== 0 && Math.abs(x) < 1e-3) ?
   x.toExponential(n - 1) : +x.toPrecision(n)).toString() : String(x));

function since() {
  // the smallest last step over the lines (a line may lag the others by a message), but
  // not more than LAG_MAX steps behind the newest (a channel that stopped must not make
  // every answer resend everything after it)
  let lo = null, hi = null;
  for (const key in S.lines) {
    const l = S.lines[key];
    if (!l.k.length) continue;
    const k = l.k[l.k.length - 1];
    lo = (lo === null) ? k : Math.min(lo, k);
    hi = (hi === null) ? k : Math.max(hi, k);
  }
  return lo === null ? -1 : Math.max(lo, hi - LAG_MAX);
}

function ingest(d) {
  for (const key in d.lines) {
    const src = d.lines[key];
    let l = S.lines[key];
    if (!l) {
      l = S.lines[key] = {key, group: src.group, label: src.label, unit: src.unit,
                          rank: src.rank, k: [], t: [], y: []};
      (S.groups[src.group] = S.groups[src.group] || []).push(key);
    }
    const last = l.k.length ? l.k[l.k.length - 1] : -1;
    for (let i = 0; i < src.k.length; i++) {
      if (src.k[i] <= last) continue;  // already have it
      l.k.push(src.k[i]); l.t.push(src.t[i]); l.y.push(src.y[i]);
    }
    if (l.k.length > MAX_POINTS) {
      const cut = l.k.length - MAX_POINTS;
      l.k.splice(0, cut); l.t.splice(0, cut); l.y.splice(0, cut);
    }
  }
  if (d.fatigue) S.fatigue = d.fatigue;
  if (d.coupling) ingestCoupling(d.coupling);
  if (d.map_geometry) S.geometry = d.map_geometry;
  if (d.damage_map) {
    if (d.damage_map.log10_damage) S.map = d.damage_map;
    else if (S.map) Object.assign(S.map, d.damage_map);
    else S.map = d.damage_map;
    if (!S.geometry && !S.fetchingMeta) fetchMeta();
  }
  S.last = d;
}

function ingestCoupling(c) {
  // one point per recorder/coupling message: k, t [s], rel[bond] [-] (running)
  const C = S.coupling, last = C.k.length ? C.k[C.k.length - 1] : -1;
  for (const b in c.rel) if (!(b in C.rel)) C.rel[b] = C.k.map(() => null);
  for (let i = 0; i < c.k.length; i++) {
    if (c.k[i] <= last) continue;
    C.k.push(c.k[i]); C.t.push(c.t[i]);
    for (const b in C.rel) C.rel[b].push(c.rel[b] ? c.rel[b][i] : null);
  }
  if (C.k.length > MAX_POINTS) {
    const cut = C.k.length - MAX_POINTS;
    C.k.splice(0, cut); C.t.splice(0, cut);
    for (const b in C.rel) C.rel[b].splice(0, cut);
  }
  C.last = c.last; C.threshold = c.threshold; C.steps = c.steps; C.fromK = c.from_k;
}

function couplingSince() {
  const C = S.coupling;
  return C.k.length ? C.k[C.k.length - 1] : -1;
}

function drawCoupling() {
  const C = S.coupling;
  if (!C.last) return;
  $("coupling-none").hidden = true; $("coupling-live").hidden = false;
  const thr = C.threshold, tot = C.last.rel_total;
  $("coupling-total").textContent = fmt(100 * tot);
  $("coupling-warn").textContent = (thr !== null && tot > thr) ?
    `above the ${fmt(100 * thr)} % warning threshold` : "";
  const bonds = Object.keys(C.rel).sort((a, b) => (a === "total") - (b === "total") ||
                                                  a.localeCompare(b));
  $("coupling-facts").textContent = `steps ${C.fromK}..${C.last.k} (${C.steps} steps): ` +
    bonds.filter((b) => b !== "total").map((b) => `${b} ${fmt(100 * C.last["rel_" + b])} %`)
      .join(", ") + " (running: sum |dE| over the energy each bond carried)";
  if (!C.plot || C.bonds.join() !== bonds.join()) {
    if (C.plot) C.plot.destroy();
    const div = $("coupling-plot");
    div.innerHTML = "";
    const series = [{label: "t [s]", value: (u, v) => fmt(v, 5)}].concat(bonds.map((b, i) => ({
      label: b, stroke: COLOURS[i % COLOURS.length], width: b === "total" ? 2 : 1.2,
      value: (u, v) => fmt(v)})));
    series.push({label: "threshold", stroke: "#c53030", width: 1, dash: [6, 4],
                 value: (u, v) => fmt(v)});
    C.plot = new uPlot({width: Math.max(320, div.clientWidth || 540), height: 200,
                        legend: {show: true}, scales: {x: {time: false}}, series,
                        axes: [{label: "t [s]"}, {label: "residual [%]", size: 60}]},
                       [[]].concat(series.slice(1).map(() => [])), div);
    C.bonds = bonds;
  }
  const pct = (ys) => ys.map((y) => (y === null ? null : 100 * y));
  const data = [C.t.slice()].concat(bonds.map((b) => pct(C.rel[b])));
  data.push(C.t.map(() => (thr === null || thr === undefined ? null : 100 * thr)));
  C.plot.setData(data);
  const div = $("coupling-plot");
  div.dataset.points = C.t.length; div.dataset.k = C.last.k;
}

async function fetchMeta() {
  S.fetchingMeta = true;
  try {
    const m = await (await fetch("/meta")).json();
    if (m.map_geometry) S.geometry = m.map_geometry;
  } finally { S.fetchingMeta = false; }
}

function windowed(key, x0) {
  const l = S.lines[key];
  let i = 0;
  if (x0 !== null) { let lo = 0, hi = l.t.length; while (lo < hi) { const m = (lo + hi) >> 1;
    if (l.t[m] < x0) lo = m + 1; else hi = m; } i = lo; }
  return i;
}

function minMaxColumns(data, columns) {
  // #32: a long window is drawn as each pixel column's min and max (peaks kept), not as
  // every sample: two points a column, the first at the column's first time with every
  // line's min, the second at its last time with every line's max.
  const t = data[0], n = t.length;
  if (n <= 2 * columns) return data;
  const per = n / columns, out = data.map(() => []);
  for (let c = 0; c < columns; c++) {
    const a = Math.floor(c * per), b = Math.min(n, Math.floor((c + 1) * per));
    if (b <= a) continue;
    out[0].push(t[a], t[b - 1]);
    for (let s = 1; s < data.length; s++) {
      let lo = null, hi = null;
      for (let i = a; i < b; i++) {
        const v = data[s][i];
        if (v === null || v === undefined) continue;
        if (lo === null || v < lo) lo = v;
        if (hi === null || v > hi) hi = v;
      }
      out[s].push(lo, hi);
    }
  }
  return out;
}

function plotFor(group) {
  if (S.plots[group]) return S.plots[group];
  const keys = S.groups[group];
  const first = S.lines[keys[0]];
  const div = document.createElement("div");
  div.className = "card plot";
  div.dataset.group = group;
  div.dataset.rank = first.rank;
  div.innerHTML = `<h2>${esc(group)} <span class="meta">[${esc(first.unit || "-")}]</span></h2>`;
  // in the order of the --channels patterns (then of arrival)
  const after = [...$("plots").children].find((c) => +c.dataset.rank > first.rank);
  $("plots").insertBefore(div, after || null);
  const width = Math.max(320, div.clientWidth - 24);
  const opts = {
    width, height: 210, legend: {show: true},
    scales: {x: {time: false}},
    series: [{label: "t [s]", value: (u, v) => fmt(v, 5)}].concat(keys.map((k, i) => ({
      label: S.lines[k].label, stroke: COLOURS[i % COLOURS.length], width: 1.2,
      value: (u, v) => fmt(v)}))),
    axes: [{label: "t [s]"}, {label: `${group.split("/").pop()} [${first.unit || "-"}]`,
            size: 70}],
  };
  const data = [[]].concat(keys.map(() => []));
  const u = new uPlot(opts, data, div);
  S.plots[group] = {u, div, keys};
  return S.plots[group];
}

function drawPlots() {
  for (const group in S.groups) {
    const p = plotFor(group);
    if (p.keys.length !== S.groups[group].length) {  // a late corner: rebuild the plot
      p.u.destroy(); p.div.remove(); delete S.plots[group]; plotFor(group); continue;
    }
    const l0 = S.lines[p.keys[0]];
    if (!l0.t.length) continue;
    const tEnd = l0.t[l0.t.length - 1];
    const x0 = S.windowS > 0 ? tEnd - S.windowS : null;
    const i0 = windowed(p.keys[0], x0);
    let data = [l0.t.slice(i0)];
    for (const key of p.keys) {
      const l = S.lines[key];
      const j = windowed(key, x0);
      data.push(l.y.slice(j, j + data[0].length));
    }
    data = minMaxColumns(data, Math.max(100, p.u.bbox.width / (window.devicePixelRatio || 1)));
    p.u.setData(data);
    p.div.dataset.lastK = l0.k[l0.k.length - 1];
    p.div.dataset.points = data[0].length;
  }
}

function drawStatus(d) {
  $("run-id").textContent = d.run;
  $("source").textContent = d.source;
  const rs = $("run-state");
  rs.textContent = d.run_state; rs.className = `badge state-${d.run_state}`;
  const lk = $("last-k");
  lk.textContent = d.k; lk.dataset.k = d.k;
  document.body.dataset.lastK = d.k;
  $("n-steps").textContent = d.n_steps ?? "?";
  $("last-t").textContent = d.k >= 0 ? d.t.toFixed(3) : "-";
  $("steps-per-s").textContent = d.steps_per_s ? Math.round(d.steps_per_s) : "0";
  $("messages").textContent = d.messages;
  $("undecodable").textContent = d.undecodable ? `, ${d.undecodable} undecodable` : "";
  $("reason").textContent = d.reason || "";
  $("progress-bar").style.width = `${Math.min(100, 100 * (d.progress || 0))}%`;
  const tb = $("nodes").querySelector("tbody");
  tb.innerHTML = "";
  for (const [name, n] of Object.entries(d.nodes)) {
    const tr = document.createElement("tr");
    tr.dataset.node = name; tr.dataset.state = n.state;
    tr.innerHTML = `<td class="mono">${esc(name)}</td><td><span class="badge ` +
      `state-${esc(n.state)}">${esc(n.state)}</span>${n.info ? " " + esc(n.info) : ""}</td>` +
      `<td>${n.k >= 0 ? esc(n.k) : "-"}</td>`;
    tb.appendChild(tr);
  }
}

// ---- damage map: log colour scale (inferno, reversed: dark = most damaged) ----------------
const INFERNO = [[252, 255, 164], [249, 201, 50], [246, 136, 40], [221, 81, 58],
                 [174, 43, 85], [120, 28, 109], [64, 10, 103], [0, 0, 4]];
function colour(f) {
  f = Math.max(0, Math.min(1, f)) * (INFERNO.length - 1);
  const i = Math.min(INFERNO.length - 2, Math.floor(f)), r = f - i;
  const a = INFERNO[i], b = INFERNO[i + 1];
  return `rgb(${a.map((v, j) => Math.round(v + r * (b[j] - v))).join(",")})`;
}

function drawMap() {
  const m = S.map, g = S.geometry, fat = S.fatigue;
  if (!m && !fat) return;
  $("fatigue-none").hidden = true; $("fatigue-live").hidden = false;
  const life = fat ? fat.life_km : (m ? m.life_km : null);
  $("min-life").textContent = fmt(life);
  $("fatigue-facts").textContent = fat ?
    `from the fatigue node at step ${fat.k}: max damage ${fmt(fat.max_damage)}, critical ` +
    `node ${fat.critical_node_id}, ${fmt(fat.distance_m)} m of road so far` :
    "computed by the scope from the arm loads (no fatigue node message)";
  if (!m) return;
  if (m.problem) { $("map-facts").textContent = `no map: ${m.problem}`; return; }
  $("map-facts").textContent = `map at step ${m.k}${m.from_k ? ` (from step ${m.from_k})` : ""}` +
    `${m.missing_steps ? `, ${m.missing_steps} steps missed` : ""}: max damage ` +
    `${fmt(m.max_damage)} per pass, critical node ${m.critical_node_id}, life ` +
    `${fmt(m.life_km)} km${m.final ? " (final)" : ""}`;
  const cv = $("damage-map");
  if (!g || !g.xyz_mm || !m.log10_damage) return;
  const ctx = cv.getContext("2d");
  const W = cv.width, H = cv.height, bar = 64, pad = 26;
  ctx.clearRect(0, 0, W, H);
  const P = g.xyz_mm, hp = Object.entries(g.hardpoints);
  const all = P.concat(hp.map(([, p]) => p));
  const ext = (j) => [Math.min(...all.map((p) => p[j])), Math.max(...all.map((p) => p[j]))];
  const [x0, x1] = ext(0), [y0, y1] = ext(1), [z0, z1] = ext(2);
  const sc = Math.min((W - bar - 2 * pad) / (x1 - x0), (H - 3 * pad - 30) / (y1 - y0 + z1 - z0));
  const logs = m.log10_damage.filter((v) => v !== null);
  const hi = logs.length ? Math.max(...logs) : 0, lo = hi - 8;
  // least damaged first: the most damaged nodes are drawn on top
  const order = P.map((_, i) => i).sort((a, b) =>
    (m.log10_damage[a] ?? -1e9) - (m.log10_damage[b] ?? -1e9));
  const ci = g.node_id.indexOf(m.critical_node_id);
  const views = [["plan view (x forward, y outboard)", 1, pad + 14, y1],
                 ["side view (x forward, z up)", 2, pad + 14 + (y1 - y0) * sc + pad + 14, z1]];
  let drawn = 0;
  for (const [title, j, oy, top] of views) {
    const X = (p) => pad + (p[0] - x0) * sc, Y = (p) => oy + (top - p[j]) * sc;
    ctx.fillStyle = "#1d2330"; ctx.font = "12px sans-serif"; ctx.fillText(title, pad, oy - 6);
    for (const i of order) {
      const v = m.log10_damage[i];
      ctx.fillStyle = v === null ? "#e2e8f0" : colour((v - lo) / (hi - lo));
      ctx.fillRect(X(P[i]) - 1.5, Y(P[i]) - 1.5, 3, 3);
      drawn++;
    }
    if (ci >= 0) {
      ctx.strokeStyle = "#00b5d8"; ctx.lineWidth = 2; ctx.beginPath();
      ctx.arc(X(P[ci]), Y(P[ci]), 8, 0, 2 * Math.PI); ctx.stroke();
    }
    ctx.fillStyle = "#000"; ctx.font = "10px sans-serif";
    for (const [name, p] of hp) ctx.fillText(j === 1 ? "+ " + name : "+", X(p) - 3, Y(p) + 3);
  }
  for (let j = 0; j < 100; j++) {  // colour bar
    ctx.fillStyle = colour(1 - j / 99);
    ctx.fillRect(W - bar + 8, pad + j * (H - 2 * pad) / 100, 14, (H - 2 * pad) / 100 + 1);
  }
  ctx.fillStyle = "#1d2330"; ctx.font = "10px sans-serif";
  ctx.fillText(`1e${hi.toFixed(1)}`, W - bar + 24, pad + 8);
  ctx.fillText(`1e${lo.toFixed(1)}`, W - bar + 24, H - pad);
  ctx.save(); ctx.translate(W - 6, H / 2); ctx.rotate(-Math.PI / 2);
  ctx.fillText("Miner damage per pass (log)", -70, 0); ctx.restore();
  cv.dataset.drawn = drawn / 2; cv.dataset.k = m.k;
}

async function poll() {
  try {
    const r = await fetch(`/data?since=${since()}&coupling_since=${couplingSince()}`);
    const d = await r.json();
    ingest(d);
    $("conn").textContent = "";
    drawStatus(d);
    if (!S.paused) { drawPlots(); drawMap(); drawCoupling(); }
  } catch (e) {
    $("conn").textContent = `scope server not reachable (${e})`;
  }
  setTimeout(poll, POLL_MS);
}

$("pause").addEventListener("click", () => {
  S.paused = !S.paused;
  $("pause").textContent = S.paused ? "Resume" : "Pause";
  if (!S.paused) { drawPlots(); drawMap(); drawCoupling(); }
});
$("window").addEventListener("change", (e) => { S.windowS = +e.target.value; drawPlots(); });
window.addEventListener("resize", () => {
  for (const g in S.plots) S.plots[g].u.setSize({width: Math.max(320,
    S.plots[g].div.clientWidth - 24), height: 210});
});
poll();
