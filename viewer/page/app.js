// Downwash Lab's live page: speaks the viewer's JSON frames (subprotocol dw.json.v1) over the
// same port as Foxglove's protocol. No library, no build step, nothing fetched from elsewhere.
"use strict";

const WINDOW_S = 20;             // strip charts show the last this many seconds
const ARENA_HALF_M = 2.0;        // the top view shows N and E within ± this
const TRAIL_S = 4;               // each vehicle's trail
const STALE_S = 3;               // a process unheard for this long is shown stale
const AXES = [
  { name: "f_n", unit: "N", get: (m) => m.force_n.x },
  { name: "f_e", unit: "N", get: (m) => m.force_n.y },
  { name: "f_d", unit: "N", get: (m) => m.force_n.z },
  { name: "m_roll", unit: "N·m", get: (m) => m.torque_nm.x },
  { name: "m_pitch", unit: "N·m", get: (m) => m.torque_nm.y },
  { name: "m_yaw", unit: "N·m", get: (m) => m.torque_nm.z },
];
const WANTED = ["stand/wrench", "predictor/wrench", "vehicles/state", "experiment/plan", "experiment/state",
                "processes/status", "stand/status"];

// Everything the page knows, also read by the browser test (tests/js/check_viewer_page.mjs).
const view = window.dwView = {
  connected: false, counts: {}, enums: { phase: [], process_state: [], stand_state: [] },
  measured: [], predicted: [], vehicles: new Map(), plan: null, state: null, stand: null, processes: new Map(),
  model: "",
};

const $ = (id) => document.getElementById(id);
const now_s = () => performance.now() / 1000;

function connect() {
  const ws = new WebSocket(`ws://${location.host}/`, "dw.json.v1");
  ws.onopen = () => { view.connected = true; setBadge(true); };
  ws.onclose = () => { view.connected = false; setBadge(false); setTimeout(connect, 1000); };
  ws.onmessage = (e) => {
    const m = JSON.parse(e.data);
    if (m.op === "hello") return hello(ws, m);
    if (m.op === "status") return showStatus(m);
    if (m.topic) take(m.topic, m.msg);
  };
}

function hello(ws, m) {
  view.enums = m.enums;
  const topics = m.topics.filter((t) => WANTED.some((w) => t.endsWith("/" + w)));
  ws.send(JSON.stringify({ op: "subscribe", topics }));
  $("footer").textContent = `${m.name} — read-only; Foxglove and Lichtblick: open connection ws://${location.host}/`;
}

function showStatus(m) { $("message").textContent = `viewer: ${m.message}`; }

function take(topic, msg) {
  view.counts[topic] = (view.counts[topic] || 0) + 1;
  const t = now_s();
  switch (topic) {
    case "stand/wrench": return push(view.measured, { t, v: AXES.map((a) => a.get(msg)) });
    case "predictor/wrench":
      view.model = msg.model_name;
      return push(view.predicted, { t, v: AXES.map((a) => a.get(msg)), band: msg.f_d_interval_n });
    case "vehicles/state": return takeVehicle(t, msg);
    case "experiment/plan": view.plan = msg; return;
    case "experiment/state": view.state = msg; return;
    case "stand/status": view.stand = msg; return;
    case "processes/status": view.processes.set(msg.process, { t, msg }); return;
  }
}

function push(series, point) {
  series.push(point);
  while (series.length && series[0].t < point.t - WINDOW_S) series.shift();
}

function takeVehicle(t, msg) {
  const v = view.vehicles.get(msg.vehicle_id) || { trail: [] };
  v.msg = msg;
  v.t = t;
  v.trail.push({ t, n: msg.position_m.x, e: msg.position_m.y });
  while (v.trail.length && v.trail[0].t < t - TRAIL_S) v.trail.shift();
  view.vehicles.set(msg.vehicle_id, v);
}

function setBadge(on) {
  const b = $("connection");
  b.textContent = on ? "live" : "disconnected — retrying";
  b.className = "badge " + (on ? "on" : "off");
}

// ---- drawing ---------------------------------------------------------------------------------

function makeCharts() {
  const box = $("charts");
  for (const a of AXES) {
    const div = document.createElement("div");
    div.className = "chart";
    div.innerHTML = `<div class="title"><span>${a.name} [${a.unit}]</span><span class="value" id="value-${a.name}">–</span></div>` +
                    `<canvas id="chart-${a.name}" width="600" height="90"></canvas>`;
    box.appendChild(div);
  }
}

function drawChart(i) {
  const a = AXES[i], c = $(`chart-${a.name}`), g = c.getContext("2d");
  const W = c.width, H = c.height, t1 = now_s(), t0 = t1 - WINDOW_S;
  g.clearRect(0, 0, W, H);
  const all = view.measured.concat(view.predicted);
  let lo = Infinity, hi = -Infinity;
  for (const p of all) { lo = Math.min(lo, p.v[i] - (i === 2 && p.band ? p.band : 0)); hi = Math.max(hi, p.v[i] + (i === 2 && p.band ? p.band : 0)); }
  if (!isFinite(lo)) { lo = -1; hi = 1; }
  const pad = Math.max(1e-3, (hi - lo) * 0.1); lo -= pad; hi += pad;
  const X = (t) => (t - t0) / WINDOW_S * W, Y = (v) => H - (v - lo) / (hi - lo) * H;
  g.strokeStyle = "#273140"; g.lineWidth = 1;
  if (lo < 0 && hi > 0) { g.beginPath(); g.moveTo(0, Y(0)); g.lineTo(W, Y(0)); g.stroke(); }
  if (i === 2) band(g, X, Y);
  line(g, view.predicted, i, X, Y, getComputedStyle(document.body).getPropertyValue("--predicted"));
  line(g, view.measured, i, X, Y, getComputedStyle(document.body).getPropertyValue("--measured"));
  const last = view.measured[view.measured.length - 1];
  $(`value-${a.name}`).textContent = last ? last.v[i].toFixed(4) : "–";
}

function band(g, X, Y) {
  const p = view.predicted.filter((q) => q.band > 0);
  if (p.length < 2) return;
  g.fillStyle = "rgba(255,169,74,0.15)";
  g.beginPath();
  p.forEach((q, k) => (k ? g.lineTo : g.moveTo).call(g, X(q.t), Y(q.v[2] + q.band)));
  for (let k = p.length - 1; k >= 0; --k) g.lineTo(X(p[k].t), Y(p[k].v[2] - p[k].band));
  g.closePath(); g.fill();
}

function line(g, series, i, X, Y, colour) {
  if (series.length < 2) return;
  g.strokeStyle = colour; g.lineWidth = 1.5; g.beginPath();
  series.forEach((p, k) => (k ? g.lineTo : g.moveTo).call(g, X(p.t), Y(p.v[i])));
  g.stroke();
}

function drawArena() {
  const c = $("arena"), g = c.getContext("2d"), S = c.width;
  const P = (n, e) => [S / 2 + e / ARENA_HALF_M * S / 2, S / 2 - n / ARENA_HALF_M * S / 2];
  g.clearRect(0, 0, S, S);
  g.strokeStyle = "#1f2833"; g.lineWidth = 1;
  for (let m = -ARENA_HALF_M; m <= ARENA_HALF_M; m += 0.5) {
    const [x] = P(0, m), [, y] = P(m, 0);
    g.beginPath(); g.moveTo(x, 0); g.lineTo(x, S); g.moveTo(0, y); g.lineTo(S, y); g.stroke();
  }
  drawLegs(g, P);
  const [sx, sy] = P(0, 0);
  g.fillStyle = "#5b6b80"; g.fillRect(sx - 9, sy - 9, 18, 18);
  g.fillStyle = "#dfe6ee"; g.font = "11px system-ui"; g.fillText("stand", sx + 12, sy + 4);
  let k = 0;
  for (const [id, v] of view.vehicles) drawVehicle(g, P, id, v, k++);
}

function drawLegs(g, P) {
  if (!view.plan) return;
  const current = view.state ? view.state.leg_index : -1;
  view.plan.legs.forEach((leg) => {
    const on = leg.index === current;
    g.strokeStyle = on ? "#ffa94a" : "#33415a"; g.lineWidth = on ? 3 : 1.5;
    const off = view.plan.offsets_m.length ? view.plan.offsets_m : [{ x: 0, y: 0 }];
    for (const o of off) {
      const [x0, y0] = P(leg.start_m.x + o.x, leg.start_m.y + o.y), [x1, y1] = P(leg.end_m.x + o.x, leg.end_m.y + o.y);
      g.beginPath(); g.moveTo(x0, y0); g.lineTo(x1, y1); g.stroke();
    }
  });
}

const COLOURS = ["#4aa3ff", "#3fbf6f", "#c678dd", "#e5c07b"];
function drawVehicle(g, P, id, v, k) {
  const colour = COLOURS[k % COLOURS.length];
  g.strokeStyle = colour; g.globalAlpha = 0.5; g.lineWidth = 1.5; g.beginPath();
  v.trail.forEach((p, j) => (j ? g.lineTo : g.moveTo).call(g, ...P(p.n, p.e)));
  g.stroke(); g.globalAlpha = 1;
  const [x, y] = P(v.msg.position_m.x, v.msg.position_m.y);
  g.fillStyle = v.msg.tracking_valid ? colour : "#e5484d";
  g.beginPath(); g.arc(x, y, 7, 0, 2 * Math.PI); g.fill();
  g.fillStyle = "#dfe6ee"; g.font = "11px system-ui";
  g.fillText(`${id} ${(-v.msg.position_m.z).toFixed(2)} m`, x + 10, y - 8);
}

function drawPanels() {
  const s = view.state, names = view.enums;
  if (view.plan) $("plan").textContent = `${view.plan.name} (${view.plan.formation})`;
  if (s) {
    const phase = names.phase[s.phase] || String(s.phase);
    $("phase").textContent = phase; $("phase").className = "phase state-" + phase;
    $("leg").textContent = s.leg_index < 0 ? `– of ${s.leg_count}` : `${s.leg_index + 1} of ${s.leg_count}`;
    $("progress").textContent = `${(100 * s.progress).toFixed(1)} %`;
    $("progress-bar").style.width = `${(100 * s.progress).toFixed(1)}%`;
    $("eta").textContent = s.eta_s >= 0 ? `${s.eta_s.toFixed(0)} s` : "–";
    if (s.message) $("message").textContent = s.message;
  }
  if (view.stand) {
    const st = names.stand_state[view.stand.state] || String(view.stand.state);
    $("stand-state").textContent = st; $("stand-state").className = "state-" + st;
    $("stand-rate").textContent = `${view.stand.sample_rate_hz.toFixed(1)} Hz`;
  }
  $("model").textContent = view.model ? `(${view.model})` : "";
  drawProcesses();
  $("vehicles").innerHTML = [...view.vehicles].map(([id, v]) =>
    `<div id="vehicle-${id}">${id}: N ${v.msg.position_m.x.toFixed(3)} E ${v.msg.position_m.y.toFixed(3)} D ${v.msg.position_m.z.toFixed(3)} m</div>`).join("");
}

function drawProcesses() {
  const t = now_s(), rows = [];
  for (const [name, p] of [...view.processes].sort()) {
    const st = view.enums.process_state[p.msg.state] || String(p.msg.state), age = t - p.t;
    rows.push(`<tr><td>${name}</td><td>${p.msg.host}</td><td class="state-${st}">${st}</td>` +
              `<td class="${age > STALE_S ? "stale" : ""}">${age.toFixed(1)} s ago</td></tr>`);
  }
  $("processes").tBodies[0].innerHTML = rows.join("");
}

function frame() {
  AXES.forEach((_, i) => drawChart(i));
  drawArena();
  drawPanels();
  requestAnimationFrame(frame);
}

makeCharts();
connect();
requestAnimationFrame(frame);
