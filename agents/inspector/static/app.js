// faultmas inspect: the page. One server-sent event stream (/events) brings the whole view on each change;
// this file only draws it. No framework, no build step, nothing fetched from elsewhere.
"use strict";

const $ = (id) => document.getElementById(id);
const COLOURS = ["#1e88e5", "#e53935", "#43a047", "#fb8c00", "#8e24aa", "#00acc1", "#6d4c41", "#3949ab", "#c0ca33", "#d81b60", "#546e7a", "#00897b"];
const state = { agent: null, source: null, marks: [], marksFrom: 0, view: null, zoom: 8, fit: true, plansShown: -1, colours: {} };

function colour(name) {
  if (!(name in state.colours)) state.colours[name] = COLOURS[Object.keys(state.colours).length % COLOURS.length];
  return state.colours[name];
}

function el(tag, attrs, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) {
    if (k === "class") e.className = v; else if (k === "text") e.textContent = v; else e.setAttribute(k, v);
  }
  for (const c of children) e.append(c);
  return e;
}

function connect() {
  if (state.source) state.source.close();
  state.marks = [];
  state.marksFrom = 0;
  const url = "/events" + (state.agent ? "?agent=" + encodeURIComponent(state.agent) : "");
  const source = new EventSource(url);
  state.source = source;
  source.onopen = () => { $("link").textContent = "live"; $("link").className = "up"; };
  source.onerror = () => { $("link").textContent = "disconnected (retrying)"; $("link").className = "down"; };
  source.onmessage = (event) => {
    let view;
    try { view = JSON.parse(event.data); } catch (e) { console.warn("bad view", e); return; }
    addMarks(view);
    state.view = view;
    render(view);
  };
}

// The hub numbers the timeline's marks from the first it saw and keeps the newest timeline_limit of them; a view
// brings those from number timeline_first on. The page keeps as many (state.marks: numbers state.marksFrom...), so a
// team held up for days does not grow it either; a reconnected stream sends the kept marks again: they replace ours.
function addMarks(view) {
  const first = view.timeline_first ?? state.marksFrom + state.marks.length;
  if (first < state.marksFrom || first > state.marksFrom + state.marks.length) {
    state.marks = [];            // a gap (dropped before we saw them) or a stream begun again
    state.marksFrom = first;
  }
  state.marks.splice(first - state.marksFrom);
  state.marks.push(...view.timeline);
  const over = state.marks.length - (view.timeline_limit ?? Infinity);
  if (over > 0) {
    state.marks.splice(0, over);
    state.marksFrom += over;
  }
}

function select(agent) {
  if (agent === state.agent) return;
  state.agent = agent;
  state.plansShown = -1;
  location.hash = "agent=" + encodeURIComponent(agent);
  $("mind-name").textContent = agent;
  connect();
}

function render(view) {
  $("mas").textContent = "MAS " + view.mas;
  renderTeam(view.team);
  renderMind(view.mind);
  renderWorld(view.robots);
  renderTimeline(view.clock);
}

function renderTeam(team) {
  const body = $("team").tBodies[0];
  body.replaceChildren();
  for (const a of team) {
    const row = el("tr", { "data-agent": a.agent },
      el("td", { text: a.agent }), el("td", { text: a.robot || "-" }),
      el("td", { class: "cycles", text: a.cycles ?? "-" }), el("td", { class: "top", title: a.top || "", text: a.top || "" }));
    row.className = (a.alive ? "alive" : "dead") + (a.agent === state.agent ? " selected" : "") + (a.paused ? " paused" : "");
    row.onclick = () => select(a.agent);
    body.append(row);
  }
}

function list(id, items, make) {
  const ul = $(id);
  ul.replaceChildren(...items.map(make));
}

function renderMind(mind) {
  if (!mind) return;
  $("cycles").textContent = mind.cycles;
  for (const b of ["pause", "step", "resume"]) $(b).disabled = !mind.control;
  $("step").disabled = !mind.control || !mind.paused;
  $("pause").disabled = !mind.control || mind.paused;
  $("resume").disabled = !mind.control || !mind.paused;
  $("run-state").textContent = mind.paused ? "paused" : "running";
  if (!mind.control) $("control-status").textContent = "read-only (the MAS does not allow pausing)";
  const filter = $("belief-filter").value.trim().toLowerCase();
  const beliefs = mind.beliefs.filter((b) => !filter || b.toLowerCase().includes(filter));
  list("beliefs", beliefs, (b) => el("li", { text: b }));
  if (mind.beliefs_cut) $("beliefs").append(el("li", { class: "hint", text: `… ${mind.beliefs_cut} more not sent` }));
  list("events", mind.pending_events, (e) => el("li", { text: e.trigger + (e.intention ? `  (intention ${e.intention})` : "") }));
  const box = $("intentions");
  box.replaceChildren(...mind.intention_stacks.map((i) => el("div", { class: "intention", "data-intention": i.id },
    el("div", { class: "state", text: `intention ${i.id}: ${i.state}` }),
    ...i.stack.map((im) => el("div", { class: "im" },
      el("span", { text: im.event }), " ", el("span", { class: "where", text: "@ " + im.source }),
      im.step ? el("div", { class: "step", text: "  ▸ " + im.step }) : "")))));
  if (!mind.intention_stacks.length) box.append(el("p", { class: "hint", text: "no intention" }));
  list("messages", mind.messages.slice().reverse(), (m) => el("li", { class: "msg-" + m.dir,
    text: `${new Date(m.t * 1000).toLocaleTimeString()} ${m.dir === "in" ? "←" : "→"} ${m.peer} ${m.performative} ${m.content}` }));
  if (mind.plans && mind.plans.length !== state.plansShown) {
    state.plansShown = mind.plans.length;
    $("plan-count").textContent = mind.plans.length;
    list("plans", mind.plans, (p) => el("li", { title: p.path + "\n" + p.text, text: `${p.source}  ${p.label ? "@" + p.label + " " : ""}${p.trigger}` }));
  }
  const diag = $("diagnoses");
  diag.replaceChildren(...mind.diagnoses.slice().reverse().map((d) => el("div", { class: "diag" },
    el("div", { text: `${new Date(d.t * 1000).toLocaleTimeString()} ${mind.agent} ${d.action}(${d.model}) ${d.state}` }),
    el("div", { text: "observations: " + Object.entries(d.observations).map(([k, v]) => (v ? "" : "~") + k).join(", ") }),
    el("div", { text: "result: " + JSON.stringify(d.result) }))));
  if (!mind.diagnoses.length) diag.append(el("p", { class: "hint", text: `${mind.agent} has made no .diagnose call yet` }));
  for (const o of mind.observers || []) {   // the agent's .observe sessions (detection/)
    diag.append(el("div", { class: "observers" },
      el("div", { text: `observers of ${o.config}: Obs ${o.obs.join(", ") || "-"}` }),
      el("div", { text: "diagnoses: " + JSON.stringify(o.diagnoses) + "  PosAb: " + JSON.stringify(o.possibly_faulty) }),
      el("div", { text: "rules fired: " + (o.fired.map((f) => f.rule + (f.error ? ` (${f.error})` : "")).join(", ") || "-") }),
      el("ul", { class: "terms" }, ...o.verdicts.map((v) => el("li", { class: v.holds === false ? "bad" : "",
        text: `${v.holds === null ? "?" : v.holds ? "" : "~"}${v.observation}  ${v.measured === null ? "" : "measured " + Number(v.measured).toPrecision(3)}` })))));
  }
}

// Odometry starts at zero where each robot stood; with the simulator's ground truth (origin) it is drawn
// from there, in the world's frame; without, each robot in its own odometry frame.
function toWorld(origin, p) {
  if (!origin || !p) return p;
  const a = origin[2] * Math.PI / 180, [x, y] = p;
  const out = [origin[0] + x * Math.cos(a) - y * Math.sin(a), origin[1] + x * Math.sin(a) + y * Math.cos(a)];
  if (p.length > 2) out.push(p[2] + origin[2]);
  return out;
}

function renderWorld(robots) {
  const canvas = $("map"), ctx = canvas.getContext("2d");
  const names = Object.keys(robots);
  const pts = [];
  for (const r of Object.values(robots)) {
    r.trail = r.trail.map((p) => toWorld(r.origin, p));
    r.pose = toWorld(r.origin, r.odom);
    pts.push(...r.trail, ...r.truth_trail);
    if (r.pose) pts.push([r.pose[0], r.pose[1]]);
    if (r.truth) pts.push([r.truth[0], r.truth[1]]);
  }
  let [x0, x1, y0, y1] = [-2, 2, -2, 2];
  for (const [x, y] of pts) { x0 = Math.min(x0, x - 0.7); x1 = Math.max(x1, x + 0.7); y0 = Math.min(y0, y - 0.7); y1 = Math.max(y1, y + 0.7); }
  const scale = Math.min(canvas.width / (x1 - x0), canvas.height / (y1 - y0));
  const X = (x) => (x - x0) * scale, Y = (y) => canvas.height - (y - y0) * scale;
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  ctx.strokeStyle = "#eceff1"; ctx.lineWidth = 1;
  for (let g = Math.ceil(x0); g <= x1; g++) { ctx.beginPath(); ctx.moveTo(X(g), 0); ctx.lineTo(X(g), canvas.height); ctx.stroke(); }
  for (let g = Math.ceil(y0); g <= y1; g++) { ctx.beginPath(); ctx.moveTo(0, Y(g)); ctx.lineTo(canvas.width, Y(g)); ctx.stroke(); }
  const path = (points, dashed, c) => {
    if (points.length < 2) return;
    ctx.setLineDash(dashed ? [4, 4] : []); ctx.strokeStyle = c; ctx.lineWidth = dashed ? 1 : 2;
    ctx.beginPath(); ctx.moveTo(X(points[0][0]), Y(points[0][1]));
    for (const [x, y] of points.slice(1)) ctx.lineTo(X(x), Y(y));
    ctx.stroke(); ctx.setLineDash([]);
  };
  const body = $("robots").tBodies[0];
  body.replaceChildren();
  for (const name of names) {
    const r = robots[name], c = colour(name);
    path(r.truth_trail, true, "#90a4ae");
    path(r.trail, false, c);
    if (r.truth && r.pose) {   // where it is, faint, when it believes otherwise
      ctx.strokeStyle = c; ctx.lineWidth = 1; ctx.beginPath(); ctx.arc(X(r.truth[0]), Y(r.truth[1]), 7, 0, 2 * Math.PI); ctx.stroke();
    }
    const pose = r.pose || r.truth;
    if (pose) {
      const [x, y, yaw] = pose, a = yaw * Math.PI / 180;
      ctx.fillStyle = c; ctx.beginPath(); ctx.arc(X(x), Y(y), 7, 0, 2 * Math.PI); ctx.fill();
      ctx.strokeStyle = "#000"; ctx.lineWidth = 2; ctx.beginPath(); ctx.moveTo(X(x), Y(y));
      ctx.lineTo(X(x + 0.3 * Math.cos(a)), Y(y + 0.3 * Math.sin(a))); ctx.stroke();
      ctx.fillStyle = "#000"; ctx.fillText(name, X(x) + 9, Y(y) - 9);
      for (const s of r.seen) {   // the camera ray: angles are positive to the right
        const b = a - s.angle_deg * Math.PI / 180;
        ctx.strokeStyle = c; ctx.setLineDash([2, 3]); ctx.lineWidth = 1; ctx.beginPath(); ctx.moveTo(X(x), Y(y));
        ctx.lineTo(X(x + s.depth_m * Math.cos(b)), Y(y + s.depth_m * Math.sin(b))); ctx.stroke(); ctx.setLineDash([]);
      }
    }
    const fmt = (p) => p ? `${p[0].toFixed(2)}, ${p[1].toFixed(2)}, ${p[2].toFixed(0)}°` : "-";
    body.append(el("tr", { "data-robot": name }, el("td", { text: name }), el("td", { class: "pose", text: fmt(r.odom) }),
      el("td", { class: "truth", text: fmt(r.truth) }),
      el("td", { text: r.seen.map((s) => `${s.robot} at ${s.depth_m.toFixed(2)} m`).join("; ") || "-" })));
  }
}

function renderTimeline(clock) {
  const marks = state.marks, svg = $("timeline");
  $("clock").textContent = `(${clock} seconds)`;
  const agents = [...new Set(marks.map((m) => m.agent))].sort();
  const lane = 60, left = 80, end = Math.max(10, ...marks.map((m) => m.t));
  if (state.fit) state.zoom = Math.max(2, ($("timeline-scroll").clientWidth - left - 160) / end);
  const width = left + end * state.zoom + 160;
  svg.setAttribute("width", width); svg.setAttribute("height", Math.max(60, 20 + agents.length * lane));
  const ns = "http://www.w3.org/2000/svg";
  const node = (tag, attrs, text) => { const e = document.createElementNS(ns, tag); for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v); if (text !== undefined) e.textContent = text; return e; };
  svg.replaceChildren();
  const tick = [1, 2, 5, 10, 20, 50, 100, 200, 500].find((d) => d * state.zoom >= 40) || 1000;
  for (let t = 0; t <= end; t += tick) {
    svg.append(node("line", { x1: left + t * state.zoom, x2: left + t * state.zoom, y1: 0, y2: 12 + agents.length * lane, stroke: "#eceff1" }));
    svg.append(node("text", { x: left + t * state.zoom + 2, y: 10, fill: "#90a4ae" }, `${t}s`));
  }
  agents.forEach((a, i) => svg.append(node("text", { x: 4, y: 28 + i * lane, fill: colour(a) }, a)));
  const ends = {};   // per agent: where the label of each of its rows ends, so labels do not overlap
  for (const m of marks) {
    const i = agents.indexOf(m.agent), x = left + m.t * state.zoom, y = 24 + i * lane;
    const rows = (ends[m.agent] = ends[m.agent] || [0, 0, 0, 0]);
    let k = rows.findIndex((end) => end < x);
    if (k < 0) k = rows.indexOf(Math.min(...rows));
    rows[k] = x + 6 * m.step.length + 8;
    const g = node("g", { class: "mark", "data-step": m.step, "data-agent": m.agent });
    g.append(node("circle", { cx: x, cy: y, r: 4, fill: colour(m.agent) }));
    g.append(node("text", { x: x + 3, y: y + 12 + k * 10, fill: "#37474f" }, m.step));
    g.append(node("title", {}, `${m.t.toFixed(2)} s ${m.agent}: ${m.step} ${m.detail}`));
    svg.append(g);
  }
  const limit = state.view ? state.view.timeline_limit : marks.length;
  $("timeline-dropped").textContent = state.marksFrom
    ? `${state.marksFrom} earlier mark${state.marksFrom === 1 ? "" : "s"} dropped (the newest ${limit} are kept)` : "";
  const last = marks[marks.length - 1];
  $("timeline-last").textContent = last ? `${last.agent}: ${last.step} ${last.detail}` : "-";
}

async function command(name) {
  if (!state.agent) return;
  const status = $("control-status");
  status.textContent = name + "…";
  try {
    const response = await fetch(`/api/agents/${encodeURIComponent(state.agent)}/control`,
      { method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify({ command: name }) });
    const answer = await response.json();
    status.textContent = answer.ok ? `${name}: cycle ${answer.cycles}` : `refused: ${answer.error}`;
    if (answer.ok) $("cycles").textContent = answer.cycles;
  } catch (e) {
    status.textContent = `${name} failed: ${e}`;
  }
}

for (const name of ["pause", "step", "resume"]) $(name).onclick = () => command(name);
$("belief-filter").oninput = () => state.view && renderMind(state.view.mind);
$("zoom-in").onclick = () => { state.fit = false; state.zoom *= 1.5; renderTimeline(state.view ? state.view.clock : ""); };
$("zoom-out").onclick = () => { state.fit = false; state.zoom = Math.max(0.5, state.zoom / 1.5); renderTimeline(state.view ? state.view.clock : ""); };
const wanted = new URLSearchParams(location.hash.slice(1)).get("agent");
if (wanted) select(wanted); else connect();
