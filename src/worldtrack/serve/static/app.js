// worldtrack serve: the floor plan and the people on it. Plain JavaScript, no build step, no CDN.
// Floor metres -> SVG pixels: u = (x - x_min) * scale, v = (y_max - y) * scale (see serve/plan.py).
// window.worldtrack is the page's small public handle (tests and users' scripts): ready, mode,
// frameIndex, state, updates, lags (live: s from the map state's writing to its drawing), seek(k),
// play(), pause(), select(id), setView({x, y, w, h}) (SVG pixels; double-click: the whole plan).
"use strict";
(() => {
  const SVGNS = "http://www.w3.org/2000/svg";
  const COLOURS = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
                   "#bcbd22", "#17becf"];
  const $ = (id) => document.getElementById(id);
  const WT = (window.worldtrack = { ready: false, frameIndex: 0, state: null, updates: 0, lags: [] });
  let plan, T, run = null, selected = null, current = [];
  const nodes = new Map();            // id -> {g, sigma, heading, label, speed}
  const cameraRows = new Map();       // camera id -> {state, lag, sees, ring}

  const colour = (id) => COLOURS[(Math.abs(id) - 1 + COLOURS.length * 1000) % COLOURS.length];
  const toSvg = (x, y) => [(x - T.x_min) * T.scale, (T.y_max - y) * T.scale];
  const pts = (ring) => ring.map((p) => p[0].toFixed(1) + "," + p[1].toFixed(1)).join(" ");
  const fmt = (v, d = 2) => (v === null || v === undefined || !isFinite(v) ? "—" : v.toFixed(d));

  function el(tag, attrs, parent) {
    const e = document.createElementNS(SVGNS, tag);
    for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
    if (parent) parent.appendChild(e);
    return e;
  }
  function text(parent, x, y, cls, s) { const t = el("text", { x, y, class: cls }, parent); t.textContent = s; return t; }
  function centroid(ring) { let u = 0, v = 0; for (const p of ring) { u += p[0]; v += p[1]; } return [u / ring.length, v / ring.length]; }

  async function getJSON(path) {
    const r = await fetch(path, { credentials: "same-origin" });
    if (!r.ok) throw new Error(path + ": HTTP " + r.status);
    return r.json();
  }

  // ---------------------------------------------------------------- the floor plan
  function drawPlan() {
    const svg = $("plan");
    svg.setAttribute("viewBox", `0 0 ${T.width} ${T.height}`);
    svg.style.maxWidth = T.width + "px";
    for (const w of plan.walkable) {
      el("polygon", { points: pts(w.outer), class: "floor" }, $("layer-floor"));
      el("polygon", { points: pts(w.outer) }, $("floor-clip"));
      for (const h of w.holes) el("polygon", { points: pts(h), class: "hole" }, $("layer-floor"));
    }
    plan.cameras.forEach((c, k) => {
      const col = COLOURS[k % COLOURS.length];
      for (const ring of c.coverage)
        el("polygon", { points: pts(ring), class: "coverage", fill: col, stroke: col, "data-camera": c.id }, $("layer-coverage"));
    });
    for (const e of plan.entries) {
      el("polygon", { points: pts(e.ring), class: "entry" }, $("layer-entries"));
      const [u, v] = centroid(e.ring);
      text($("layer-entries"), u, v, "entry-label", e.name).setAttribute("text-anchor", "middle");
    }
    for (const o of plan.obstacles) {
      el("polygon", { points: pts(o.ring), class: "obstacle " + o.kind }, $("layer-obstacles"));
      const [u, v] = centroid(o.ring);
      const t = text($("layer-obstacles"), u, v + 4, "plan-label", o.name);
      t.setAttribute("text-anchor", "middle");
      if (o.kind === "box") t.setAttribute("fill", "#fff");
    }
    plan.cameras.forEach((c, k) => {
      const g = el("g", { class: "camera", "data-camera": c.id,
                          transform: `translate(${c.at[0]},${c.at[1]})` }, $("layer-cameras"));
      g.dataset.at = `translate(${c.at[0]},${c.at[1]})`;
      const ring = el("circle", { r: 13, class: "camera-ring " + (plan.mode === "live" ? "down" : "recorded") }, g);
      el("polygon", { points: "13,0 -7,-8 -7,8", class: "camera-icon", fill: COLOURS[k % COLOURS.length],
                      transform: `rotate(${(c.heading * 180 / Math.PI).toFixed(1)})` }, g);
      const lu = -Math.cos(c.heading) * 26, lv = -Math.sin(c.heading) * 26 + 4;   // behind the camera
      const anchor = c.at[0] < 0.15 * T.width ? "start" : c.at[0] > 0.85 * T.width ? "end" : "middle";
      text(g, anchor === "start" ? Math.max(lu, -12) : anchor === "end" ? Math.min(lu, 12) : lu, lv, "plan-label",
           `${c.id} (${c.height_m} m)`).setAttribute("text-anchor", anchor);
      addCameraRow(c.id, ring);
    });
  }

  function drawScaleBar() {                       // in the view's corner farthest from every camera
    const g = $("layer-scale"), k = 1 / zoom;
    g.replaceChildren();
    const target = 120 / T.scale * k;             // about 120 screen px
    const nice = [0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100].find((m) => m >= target * 0.6) || 100;
    const len = nice * T.scale, pad = 16 * k;
    const corners = [[view.x + pad, view.y + view.h - pad], [view.x + view.w - pad - len, view.y + view.h - pad],
                     [view.x + pad, view.y + pad + 12 * k], [view.x + view.w - pad - len, view.y + pad + 12 * k]];
    const far = (c) => Math.min(...plan.cameras.map((q) => Math.hypot(q.at[0] - c[0] - len / 2, q.at[1] - c[1])), 1e9);
    const [x, y] = corners.reduce((a, b) => (far(b) > far(a) ? b : a));
    el("line", { x1: x, y1: y, x2: x + len, y2: y, class: "scale-bar" }, g);
    el("line", { x1: x, y1: y - 4 * k, x2: x, y2: y + 4 * k, class: "scale-bar" }, g);
    el("line", { x1: x + len, y1: y - 4 * k, x2: x + len, y2: y + 4 * k, class: "scale-bar" }, g);
    const t = text(g, x + len / 2, y - 6 * k, "scale-text", `${nice} m`);
    t.setAttribute("text-anchor", "middle");
    t.style.fontSize = `${11 * k}px`;
  }

  // ---------------------------------------------------------------- zoom (wheel), pan (drag), fit
  let view = null, zoom = 1, dragged = false;
  function setView(v) {
    const w = Math.min(T.width, Math.max(T.width / 60, v.w)), h = w * T.height / T.width;
    const cx = Math.min(T.width, Math.max(0, v.x + v.w / 2)), cy = Math.min(T.height, Math.max(0, v.y + v.h / 2));
    view = { x: cx - w / 2, y: cy - h / 2, w, h };
    zoom = T.width / w;
    $("plan").setAttribute("viewBox", `${view.x.toFixed(2)} ${view.y.toFixed(2)} ${w.toFixed(2)} ${h.toFixed(2)}`);
    const k = 1 / zoom;                             // symbols keep their size on screen
    for (const g of document.querySelectorAll("#layer-cameras .camera"))
      g.setAttribute("transform", g.dataset.at + ` scale(${k})`);
    for (const t of document.querySelectorAll("#layer-entries text, #layer-obstacles text"))
      t.style.fontSize = `${11 * k}px`;
    drawScaleBar();
    render(current);
  }
  function fitTo(points) {                         // [[u, v], …] in SVG pixels
    if (!points.length) return setView({ x: 0, y: 0, w: T.width, h: T.height });
    const [u0, u1, v0, v1] = extent(points);
    const w = Math.max(u1 - u0, (v1 - v0) * T.width / T.height) * 1.15 + 4 * T.scale;
    setView({ x: (u0 + u1) / 2 - w / 2, y: (v0 + v1) / 2 - w * T.height / T.width / 2, w, h: w * T.height / T.width });
  }
  function extent(points) {                      // [u0, u1, v0, v1] (no spread: runs have 100k rows)
    let u0 = Infinity, u1 = -Infinity, v0 = Infinity, v1 = -Infinity;
    for (const [u, v] of points) { u0 = Math.min(u0, u); u1 = Math.max(u1, u); v0 = Math.min(v0, v); v1 = Math.max(v1, v); }
    return [u0, u1, v0, v1];
  }
  let peoplePoints = () => current.map((p) => toSvg(p.x, p.y));
  function initZoom() {
    const svg = $("plan");
    view = { x: 0, y: 0, w: T.width, h: T.height };
    svg.addEventListener("wheel", (ev) => {
      ev.preventDefault();
      const p = new DOMPoint(ev.clientX, ev.clientY).matrixTransform(svg.getScreenCTM().inverse());
      const r = Math.exp(Math.max(-1, Math.min(1, ev.deltaY * 0.0015)));
      setView({ x: p.x - (p.x - view.x) * r, y: p.y - (p.y - view.y) * r, w: view.w * r, h: view.h * r });
    }, { passive: false });
    let drag = null;
    svg.addEventListener("pointerdown", (ev) => {
      drag = { x: ev.clientX, y: ev.clientY, view: { ...view }, s: svg.getScreenCTM().a, moved: false };
    });
    window.addEventListener("pointermove", (ev) => {
      if (!drag || !(ev.buttons & 1)) return;
      if (Math.hypot(ev.clientX - drag.x, ev.clientY - drag.y) > 4) drag.moved = true;
      if (drag.moved) setView({ ...drag.view, x: drag.view.x - (ev.clientX - drag.x) / drag.s,
                                y: drag.view.y - (ev.clientY - drag.y) / drag.s });
    });
    window.addEventListener("pointerup", () => { dragged = !!(drag && drag.moved); drag = null; });
    svg.addEventListener("dblclick", () => setView({ x: 0, y: 0, w: T.width, h: T.height }));
    $("fit-all").addEventListener("click", () => setView({ x: 0, y: 0, w: T.width, h: T.height }));
    $("fit-people").addEventListener("click", () => fitTo(peoplePoints()));
  }

  function addCameraRow(id, ring) {
    const tr = document.createElement("tr");
    tr.innerHTML = `<td></td><td><span class="state"></span></td><td></td><td></td>`;
    tr.cells[0].textContent = id;
    $("camera-table").tBodies[0].appendChild(tr);
    cameraRows.set(id, { tr, state: tr.cells[1].firstChild, lag: tr.cells[2], sees: tr.cells[3], ring });
    setCameraState(id, plan.mode === "live" ? "down" : "recorded", null);
  }

  function setCameraState(id, state, lagMs) {
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

  function render(people) {
    current = people;
    const present = new Set();
    for (const p of people) {
      present.add(p.id);
      const n = personNode(p.id), [u, v] = toSvg(p.x, p.y);
      const m = T.scale * zoom;                      // metres -> the symbol's own units (scaled by 1/zoom)
      n.g.setAttribute("transform", `translate(${u.toFixed(2)},${v.toFixed(2)}) scale(${(1 / zoom).toFixed(4)})`);
      n.sigma.setAttribute("r", p.sigma > 0 ? (p.sigma * m).toFixed(1) : 0);
      const vx = p.vx || 0, vy = p.vy || 0, speed = Math.hypot(vx, vy);
      n.heading.setAttribute("x2", speed > 0.05 ? (vx * m).toFixed(1) : 0);
      n.heading.setAttribute("y2", speed > 0.05 ? (-vy * m).toFixed(1) : 0);
      n.speed.textContent = `${speed.toFixed(1)} m/s`;
      n.g.classList.toggle("unmeasurable", !!p.unmeasurable);
      n.g.classList.toggle("selected", p.id === selected);
    }
    for (const [id, n] of nodes) if (!present.has(id)) { n.g.remove(); nodes.delete(id); }
    const lost = people.filter((p) => p.unmeasurable).length;
    $("count").textContent = `${people.length} people` + (lost ? ` (${lost} ${plan.mode === "live" ? "lost" : "unmeasurable"})` : "");
    const sees = new Map(plan.cameras.map((c) => [c.id, 0]));
    for (const p of people) for (const c of p.cams) sees.set(c, (sees.get(c) || 0) + 1);
    for (const [id, row] of cameraRows) row.sees.textContent = sees.get(id);
    drawTrails();
    showSelected();
  }

  function drawTrails() {
    const layer = $("layer-trails");
    layer.replaceChildren();
    for (const p of current) {
      const trail = trailOf(p.id);
      if (trail.length < 2) continue;
      el("polyline", { class: "trail", stroke: colour(p.id), "data-id": p.id,
                       points: trail.map(([x, y]) => toSvg(x, y).map((a) => a.toFixed(1)).join(",")).join(" ") }, layer);
    }
  }

  // ---------------------------------------------------------------- the selected person
  function select(id) {
    selected = id;
    $("person-panel").hidden = id === null;
    for (const [pid, n] of nodes) n.g.classList.toggle("selected", pid === id);
    $("layer-history").replaceChildren();
    if (id !== null) historyOf(id).then((path) => {
      if (selected !== id || path.length < 2) return;
      $("layer-history").replaceChildren();
      el("polyline", { class: "history", stroke: colour(id),
                       points: path.map(([, x, y]) => toSvg(x, y).map((a) => a.toFixed(1)).join(",")).join(" ") },
         $("layer-history"));
      selectedHistory = path;
      showSelected();
    });
    selectedHistory = [];
    showSelected();
  }
  let selectedHistory = [];
  WT.select = select;

  function showSelected() {
    const lines = $("layer-sightlines");
    lines.replaceChildren();
    if (selected === null) return;
    const p = current.find((q) => q.id === selected);
    $("p-id").textContent = selected;
    const rows = [];
    if (p) {
      const [u, v] = toSvg(p.x, p.y), speed = Math.hypot(p.vx || 0, p.vy || 0);
      const heading = speed > 0.05 ? `${Math.round(Math.atan2(p.vy, p.vx) * 180 / Math.PI)}° from +X` : "—";
      rows.push(["position", `${fmt(p.x)}, ${fmt(p.y)} m`], ["speed", `${fmt(speed)} m/s`], ["heading", heading],
                ["σ", `${fmt(p.sigma)} m`], ["state", p.unmeasurable ? (p.mode || "unmeasurable") + " (unmeasurable)" : p.mode || "—"],
                ["seen by", p.cams.length ? p.cams.join(", ") : "no camera"]);
      if (p.workers !== undefined) rows.push(["workers", `${p.workers}${p.lead ? " (lead " + p.lead + ")" : ""}`]);
      for (const cid of p.cams) {
        const c = plan.cameras.find((q) => q.id === cid);
        if (c) el("line", { x1: c.at[0], y1: c.at[1], x2: u, y2: v, class: "sightline" }, lines);
      }
    } else rows.push(["state", "not on the plan now"]);
    const h = selectedHistory;
    if (h.length) {
      let dist = 0;
      for (let i = 1; i < h.length; i++) dist += Math.hypot(h[i][1] - h[i - 1][1], h[i][2] - h[i - 1][2]);
      rows.push(["first seen", clockText(h[0][0])], ["last seen", clockText(h[h.length - 1][0])],
                ["walked", `${fmt(dist, 1)} m in ${fmt(h[h.length - 1][0] - h[0][0], 1)} s`]);
    }
    const dl = $("p-info");
    dl.replaceChildren();
    for (const [k, v] of rows) {
      const dt = document.createElement("dt"), dd = document.createElement("dd");
      dt.textContent = k; dd.textContent = v; dl.append(dt, dd);
    }
  }

  // ---------------------------------------------------------------- a finished run
  let trailOf = () => [], historyOf = async () => [], clockText = (t) => fmt(t);
  function lastAtOrBefore(arr, value, key) {      // binary search: last index with key(arr[i]) <= value
    let lo = 0, hi = arr.length - 1, best = -1;
    while (lo <= hi) { const mid = (lo + hi) >> 1; if (key(arr[mid]) <= value) { best = mid; lo = mid + 1; } else hi = mid - 1; }
    return best;
  }

  async function initRun() {
    run = await getJSON("api/run");
    const R = run.rows, n = R.id.length, byFrame = run.frames.map(() => []), byId = new Map();
    for (let i = 0; i < n; i++) {
      byFrame[R.frame[i]].push(i);
      if (!byId.has(R.id[i])) byId.set(R.id[i], []);
      byId.get(R.id[i]).push(i);
    }
    const row = (i) => ({ id: R.id[i], x: R.x[i], y: R.y[i], vx: R.vx[i], vy: R.vy[i], sigma: R.sigma[i],
                          height: R.height[i], unmeasurable: R.unmeasurable[i], mode: R.mode[i],
                          cams: R.cams[i].map((k) => run.cameras[k]) });
    const time = (i) => run.times[R.frame[i]];
    clockText = (t) => `${fmt(t, 2)} s`;
    trailOf = (id) => {
      const rows = byId.get(id) || [], t = run.times[WT.frameIndex];
      const end = lastAtOrBefore(rows, t, time), out = [];
      for (let j = end; j >= 0 && time(rows[j]) >= t - plan.trail_s; j--) out.push([R.x[rows[j]], R.y[rows[j]]]);
      return out.reverse();
    };
    historyOf = async (id) => (byId.get(id) || []).map((i) => [time(i), R.x[i], R.y[i]]);
    const last = run.frames.length - 1, tEnd = run.times[last] ?? 0;
    const scrub = $("scrub");
    scrub.max = Math.max(0, last);
    $("timeline").hidden = false;
    let playing = false, playT = 0, wall = 0, lastFrameAt = 0;
    function seek(k) {
      k = Math.max(0, Math.min(last, Math.round(k)));
      WT.frameIndex = k;
      scrub.value = k;
      const people = byFrame[k] ? byFrame[k].map(row) : [], t = run.times[k] ?? 0;
      render(people);
      WT.state = { frame: run.frames[k], t, people };
      $("clock").textContent = `t ${fmt(t, 2)} s · frame ${run.frames[k] ?? 0}`;
      $("t-label").textContent = `${fmt(t, 1)} / ${fmt(tEnd, 1)} s`;
      WT.updates++;
      const now = performance.now();
      if (plan.frames.length && (!playing || now - lastFrameAt > 250)) {
        lastFrameAt = now;
        $("frame-img").src = `api/frame/${encodeURIComponent($("frame-cam").value)}/${run.frames[k]}`;
      }
    }
    function tick(now) {
      if (!playing) return;
      playT += ((now - wall) / 1000) * parseFloat($("speed").value);
      wall = now;
      const k = lastAtOrBefore(run.times, playT, (x) => x);
      if (k !== WT.frameIndex) seek(k);
      if (k >= last) return pause();
      requestAnimationFrame(tick);
    }
    function play() {
      if (WT.frameIndex >= last) seek(0);
      playing = true; playT = run.times[WT.frameIndex] ?? 0; wall = performance.now();
      $("play").textContent = "❚❚";
      requestAnimationFrame(tick);
    }
    function pause() { playing = false; $("play").textContent = "▶"; }
    scrub.addEventListener("input", () => { pause(); seek(parseInt(scrub.value, 10)); });
    $("play").addEventListener("click", () => (playing ? pause() : play()));
    document.addEventListener("keydown", (ev) => {
      if (["BUTTON", "SELECT"].includes(ev.target.tagName)) return;     // their own keys
      if (ev.key === " ") { ev.preventDefault(); playing ? pause() : play(); }
      else if (ev.target === scrub) return;                                // the slider steps by itself
      else if (ev.key === "ArrowRight") { pause(); seek(WT.frameIndex + 1); }
      else if (ev.key === "ArrowLeft") { pause(); seek(WT.frameIndex - 1); }
    });
    if (plan.frames.length) {
      $("frame-panel").hidden = false;
      for (const c of plan.frames) { const o = document.createElement("option"); o.value = o.textContent = c; $("frame-cam").append(o); }
      $("frame-cam").addEventListener("change", () => seek(WT.frameIndex));
    }
    Object.assign(WT, { seek, play, pause, frames: run.frames, times: run.times });
    const everyone = R.x.map((x, i) => toSvg(x, R.y[i]));
    peoplePoints = () => everyone;
    if (everyone.length) {
      const [u0, u1, v0, v1] = extent(everyone);
      if ((u1 - u0) * (v1 - v0) < 0.3 * T.width * T.height)
        fitTo(everyone);                            // people use a small part of the plan: start there
    }
    $("map-line").textContent = `${run.frames.length} frames, ${byId.size} people, ${fmt(tEnd, 1)} s`;
    seek(0);
  }

  // ---------------------------------------------------------------- the live map
  function initLive() {
    const trails = new Map(), memory = new Map();
    let lastT = null, backoff = 500;
    clockText = (t) => new Date(t * 1000).toLocaleTimeString([], { hour12: false }) + "." + Math.floor((t % 1) * 10);
    trailOf = (id) => (trails.get(id) || []).map(([, x, y]) => [x, y]);
    historyOf = async (id) => {
      try { const h = await getJSON(`api/history/${id}?s=300`); if (h.length) return h; } catch (e) { /* offline */ }
      return memory.get(id) || [];
    };
    $("mode").classList.add("live");
    function onState(msg) {
      if (lastT !== null && msg.t <= lastT) return;      // a state the backlog already gave
      lastT = msg.t;
      for (const [young, old] of Object.entries(msg.aliases || {})) {
        const y = parseInt(young, 10);
        if (trails.has(y)) { trails.set(old, (trails.get(old) || []).concat(trails.get(y))); trails.delete(y); }
      }
      for (const p of msg.people) {
        if (p.mode !== "tracking") continue;
        for (const m of [trails, memory]) { if (!m.has(p.id)) m.set(p.id, []); m.get(p.id).push([msg.t, p.x, p.y]); }
        const mem = memory.get(p.id);
        if (mem.length > 20000) mem.splice(0, mem.length - 20000);
      }
      for (const [id, tr] of trails) {
        let cut = 0;
        while (cut < tr.length && tr[cut][0] < msg.t - plan.trail_s) cut++;
        if (cut === tr.length) trails.delete(id); else if (cut) tr.splice(0, cut);
      }
      render(msg.people);
      $("clock").textContent = `${clockText(msg.t)} · lag ${Math.round(msg.lag_ms)} ms`;
      WT.state = msg;
      WT.updates++;
      if (msg.written) {                                  // map written -> drawn here (same machine's clock)
        WT.lags.push(Date.now() / 1000 - msg.written);
        if (WT.lags.length > 5000) WT.lags.shift();
      }
    }
    function onCameras(msg) {
      for (const c of msg.cameras) setCameraState(c.id, c.state, c.lag_ms);
      const f = msg.fusion || {};
      $("map-line").textContent = msg.error ? msg.error
        : `${msg.workers} workers · fusion ${f.holder || "none"}${f.lag_ms !== null && f.lag_ms !== undefined ? ", lag " + f.lag_ms + " ms" : ""}`;
      $("conn").className = "conn" + (msg.error ? " bad" : "");
      if (msg.error) $("conn").textContent = msg.error;
    }
    function connect() {
      const url = new URL("ws", location.href);
      url.protocol = location.protocol === "https:" ? "wss:" : "ws:";
      url.search = "";
      const ws = new WebSocket(url);
      ws.onopen = () => { backoff = 500; $("conn").textContent = "connected"; $("conn").className = "conn"; };
      ws.onmessage = (ev) => {
        const msg = JSON.parse(ev.data);
        if (msg.type === "state") onState(msg); else if (msg.type === "cameras") onCameras(msg);
      };
      ws.onclose = () => {
        $("conn").textContent = "reconnecting…"; $("conn").className = "conn bad";
        setTimeout(connect, backoff); backoff = Math.min(8000, backoff * 2);
      };
    }
    connect();
  }

  // ---------------------------------------------------------------- start
  async function start() {
    plan = await getJSON("api/plan");
    T = plan.transform;
    WT.mode = plan.mode;
    WT.transform = T;
    document.title = `worldtrack — ${plan.name}`;
    $("title").textContent = plan.title;
    $("mode").textContent = plan.mode === "live" ? "live map" : "finished run";
    drawPlan();
    initZoom();
    setView(view);
    $("plan").addEventListener("click", () => { if (!dragged) select(null); dragged = false; });
    $("p-close").addEventListener("click", () => select(null));
    if (plan.mode === "run") await initRun(); else initLive();
    WT.ready = true;
  }
  start().catch((e) => { $("conn").textContent = String(e.message || e); $("conn").className = "conn bad"; WT.error = String(e); });
})();
