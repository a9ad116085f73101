// worldtrack serve, the live map: a websocket of map states and camera status, trails, history.
import { $, S, WT, getJSON, render, setCameraState } from "./page.js";

// ---------------------------------------------------------------- the live map
export function initLive() {
  const trails = new Map(), memory = new Map();
  let lastT = null, backoff = 500;
  S.clockText = (t) => new Date(t * 1000).toLocaleTimeString([], { hour12: false }) + "." + Math.floor((t % 1) * 10);
  S.trailOf = (id) => (trails.get(id) || []).map(([, x, y]) => [x, y]);
  S.historyOf = async (id) => {
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
      while (cut < tr.length && tr[cut][0] < msg.t - S.plan.trail_s) cut++;
      if (cut === tr.length) trails.delete(id); else if (cut) tr.splice(0, cut);
    }
    render(msg.people);
    $("clock").textContent = `${S.clockText(msg.t)} · lag ${Math.round(msg.lag_ms)} ms`;
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
