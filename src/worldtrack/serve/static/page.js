// worldtrack serve, the page's core: shared state, the floor plan, the people, the selected person.
// Floor metres -> SVG pixels: u = (x - x_min) * scale, v = (y_max - y) * scale (see serve/plan.py).
// Plain JavaScript modules, no build step, no CDN.

/** What the modules share: the plan and its transform, the zoom, who is drawn, who is selected, and
 * the mode's own answers (trail, history, clock text, the points "fit to people" uses). */
export const S = { plan: null, T: null, zoom: 1, view: null, current: [], selected: null, selectedHistory: [],
                   dragged: false, trailOf: () => [], historyOf: async () => [], clockText: (t) => fmt(t),
                   peoplePoints: () => S.current.map((p) => toSvg(p.x, p.y)) };
/** The page's public handle (tests, users' scripts): see app.js. */
export const WT = (window.worldtrack = { ready: false, frameIndex: 0, state: null, updates: 0, lags: [] });

const SVGNS = "http://www.w3.org/2000/svg";
export const COLOURS = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
                 "#bcbd22", "#17becf"];
export const $ = (id) => document.getElementById(id);
const nodes = new Map();            // id -> {g, sigma, heading, label, speed}
const cameraRows = new Map();       // camera id -> {state, lag, sees, ring}

export const colour = (id) => COLOURS[(Math.abs(id) - 1 + COLOURS.length * 1000) % COLOURS.length];
export const toSvg = (x, y) => [(x - S.T.x_min) * S.T.scale, (S.T.y_max - y) * S.T.scale];
const pts = (ring) => ring.map((p) => p[0].toFixed(1) + "," + p[1].toFixed(1)).join(" ");
export const fmt = (v, d = 2) => (v === null || v === undefined || !isFinite(v) ? "—" : v.toFixed(d));

export function el(tag, attrs, parent) {
  const e = document.createElementNS(SVGNS, tag);
  for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
  if (parent) parent.appendChild(e);
  return e;
}
export function text(parent, x, y, cls, s) { const t = el("text", { x, y, class: cls }, parent); t.textContent = s; return t; }
function centroid(ring) { let u = 0, v = 0; for (const p of ring) { u += p[0]; v += p[1]; } return [u / ring.length, v / ring.length]; }

export async function getJSON(path) {
  const r = await fetch(path, { credentials: "same-origin" });
  if (!r.ok) throw new Error(path + ": HTTP " + r.status);
  return r.json();
}


// ---------------------------------------------------------------- the floor plan
export function drawPlan() {
  const svg = $("plan");
  svg.setAttribute("viewBox", `0 0 ${S.T.width} ${S.T.height}`);
  svg.style.maxWidth = S.T.width + "px";
  for (const w of S.plan.walkable) {
    el("polygon", { points: pts(w.outer), class: "floor" }, $("layer-floor"));
    el("polygon", { points: pts(w.outer) }, $("floor-clip"));
    for (const h of w.holes) el("polygon", { points: pts(h), class: "hole" }, $("layer-floor"));
  }
  S.plan.cameras.forEach((c, k) => {
    const col = COLOURS[k % COLOURS.length];
    for (const ring of c.coverage)
      el("polygon", { points: pts(ring), class: "coverage", fill: col, stroke: col, "data-camera": c.id }, $("layer-coverage"));
  });
  for (const e of S.plan.entries) {
    el("polygon", { points: pts(e.ring), class: "entry" }, $("layer-entries"));
    const [u, v] = centroid(e.ring);
    text($("layer-entries"), u, v, "entry-label", e.name).setAttribute("text-anchor", "middle");
  }
  for (const o of S.plan.obstacles) {
    el("polygon", { points: pts(o.ring), class: "obstacle " + o.kind }, $("layer-obstacles"));
    const [u, v] = centroid(o.ring);
    const t = text($("layer-obstacles"), u, v + 4, "plan-label", o.name);
    t.setAttribute("text-anchor", "middle");
    if (o.kind === "box") t.setAttribute("fill", "#fff");
  }
  S.plan.cameras.forEach((c, k) => {
    const g = el("g", { class: "camera", "data-camera": c.id,
                        transform: `translate(${c.at[0]},${c.at[1]})` }, $("layer-cameras"));
    g.dataset.at = `translate(${c.at[0]},${c.at[1]})`;
    const ring = el("circle", { r: 13, class: "camera-ring " + (S.plan.mode === "live" ? "down" : "recorded") }, g);
    el("polygon", { points: "13,0 -7,-8 -7,8", class: "camera-icon", fill: COLOURS[k % COLOURS.length],
                    transform: `rotate(${(c.heading * 180 / Math.PI).toFixed(1)})` }, g);
    const lu = -Math.cos(c.heading) * 26, lv = -Math.sin(c.heading) * 26 + 4;   // behind the camera
    const anchor = c.at[0] < 0.15 * S.T.width ? "start" : c.at[0] > 0.85 * S.T.width ? "end" : "middle";
    text(g, anchor === "start" ? Math.max(lu, -12) : anchor === "end" ? Math.min(lu, 12) : lu, lv, "plan-label",
         `${c.id} (${c.height_m} m)`).setAttribute("text-anchor", anchor);
    addCameraRow(c.id, ring);
  });
}

function addCameraRow(id, ring) {
  const tr = document.createElement("tr");
  tr.innerHTML = `<td></td><td><span class="state"></span></td><td></td><td></td>`;
  tr.cells[0].textContent = id;
  $("camera-table").tBodies[0].appendChild(tr);
  cameraRows.set(id, { tr, state: tr.cells[1].firstChild, lag: tr.cells[2], sees: tr.cells[3], ring });
  setCameraState(id, S.plan.mode === "live" ? "down" : "recorded", null);
}

export function setCameraState(id, state, lagMs) {
  const row = cameraRows.get(id);
  if (!row) return;
  row.state.textContent = state;
  row.state.className = "state " + state;
  row.ring.setAttribute("class", "camera-ring " + state);
  row.lag.textContent = lagMs === null || lagMs === undefined ? "—" : `${Math.round(lagMs)} ms`;
}

// ---------------------------------------------------------------- people
function personNode(id) {
  let n = nodes.get(id);
  if (n) return n;
  const g = el("g", { class: "person", "data-id": id }, $("people"));
  n = { g, sigma: el("circle", { class: "sigma", r: 0 }, g),
        heading: el("line", { class: "heading", x1: 0, y1: 0, x2: 0, y2: 0, stroke: colour(id) }, g) };
  el("circle", { class: "dot", r: 6, fill: colour(id) }, g);
  n.label = text(g, 8, -8, "label", String(id));
  n.speed = text(g, 8, 16, "speed", "");
  g.addEventListener("click", (ev) => { ev.stopPropagation(); select(id); });
  nodes.set(id, n);
  return n;
}

export function render(people) {
  S.current = people;
  const present = new Set();
  for (const p of people) {
    present.add(p.id);
    const n = personNode(p.id), [u, v] = toSvg(p.x, p.y);
    const m = S.T.scale * S.zoom;                      // metres -> the symbol's own units (scaled by 1/zoom)
    n.g.setAttribute("transform", `translate(${u.toFixed(2)},${v.toFixed(2)}) scale(${(1 / S.zoom).toFixed(4)})`);
    n.sigma.setAttribute("r", p.sigma > 0 ? (p.sigma * m).toFixed(1) : 0);
    const vx = p.vx || 0, vy = p.vy || 0, speed = Math.hypot(vx, vy);
    n.heading.setAttribute("x2", speed > 0.05 ? (vx * m).toFixed(1) : 0);
    n.heading.setAttribute("y2", speed > 0.05 ? (-vy * m).toFixed(1) : 0);
    n.speed.textContent = `${speed.toFixed(1)} m/s`;
    n.g.classList.toggle("unmeasurable", !!p.unmeasurable);
    n.g.classList.toggle("selected", p.id === S.selected);
  }
  for (const [id, n] of nodes) if (!present.has(id)) { n.g.remove(); nodes.delete(id); }
  const lost = people.filter((p) => p.unmeasurable).length;
  $("count").textContent = `${people.length} people` + (lost ? ` (${lost} ${S.plan.mode === "live" ? "lost" : "unmeasurable"})` : "");
  const sees = new Map(S.plan.cameras.map((c) => [c.id, 0]));
  for (const p of people) for (const c of p.cams) sees.set(c, (sees.get(c) || 0) + 1);
  for (const [id, row] of cameraRows) row.sees.textContent = sees.get(id);
  drawTrails();
  showSelected();
}

function drawTrails() {
  const layer = $("layer-trails");
  layer.replaceChildren();
  for (const p of S.current) {
    const trail = S.trailOf(p.id);
    if (trail.length < 2) continue;
    el("polyline", { class: "trail", stroke: colour(p.id), "data-id": p.id,
                     points: trail.map(([x, y]) => toSvg(x, y).map((a) => a.toFixed(1)).join(",")).join(" ") }, layer);
  }
}

// ---------------------------------------------------------------- the selected person
export function select(id) {
  S.selected = id;
  $("person-panel").hidden = id === null;
  for (const [pid, n] of nodes) n.g.classList.toggle("selected", pid === id);
  $("layer-history").replaceChildren();
  if (id !== null) S.historyOf(id).then((path) => {
    if (S.selected !== id || path.length < 2) return;
    $("layer-history").replaceChildren();
    el("polyline", { class: "history", stroke: colour(id),
                     points: path.map(([, x, y]) => toSvg(x, y).map((a) => a.toFixed(1)).join(",")).join(" ") },
       $("layer-history"));
    S.selectedHistory = path;
    showSelected();
  });
  S.selectedHistory = [];
  showSelected();
}
WT.select = select;

function showSelected() {
  const lines = $("layer-sightlines");
  lines.replaceChildren();
  if (S.selected === null) return;
  const p = S.current.find((q) => q.id === S.selected);
  $("p-id").textContent = S.selected;
  const rows = [];
  if (p) {
    const [u, v] = toSvg(p.x, p.y), speed = Math.hypot(p.vx || 0, p.vy || 0);
    const heading = speed > 0.05 ? `${Math.round(Math.atan2(p.vy, p.vx) * 180 / Math.PI)}° from +X` : "—";
    rows.push(["position", `${fmt(p.x)}, ${fmt(p.y)} m`], ["speed", `${fmt(speed)} m/s`], ["heading", heading],
              ["σ", `${fmt(p.sigma)} m`], ["state", p.unmeasurable ? (p.mode || "unmeasurable") + " (unmeasurable)" : p.mode || "—"],
              ["seen by", p.cams.length ? p.cams.join(", ") : "no camera"]);
    if (p.workers !== undefined) rows.push(["workers", `${p.workers}${p.lead ? " (lead " + p.lead + ")" : ""}`]);
    for (const cid of p.cams) {
      const c = S.plan.cameras.find((q) => q.id === cid);
      if (c) el("line", { x1: c.at[0], y1: c.at[1], x2: u, y2: v, class: "sightline" }, lines);
    }
  } else rows.push(["state", "not on the plan now"]);
  const h = S.selectedHistory;
  if (h.length) {
    let dist = 0;
    for (let i = 1; i < h.length; i++) dist += Math.hypot(h[i][1] - h[i - 1][1], h[i][2] - h[i - 1][2]);
    rows.push(["first seen", S.clockText(h[0][0])], ["last seen", S.clockText(h[h.length - 1][0])],
              ["walked", `${fmt(dist, 1)} m in ${fmt(h[h.length - 1][0] - h[0][0], 1)} s`]);
  }
  const dl = $("p-info");
  dl.replaceChildren();
  for (const [k, v] of rows) {
    const dt = document.createElement("dt"), dd = document.createElement("dd");
    dt.textContent = k; dd.textContent = v; dl.append(dt, dd);
  }
}
