// worldtrack serve: the floor plan and the people on it. Plain JavaScript modules, no build step, no CDN.
// window.worldtrack is the page's small public handle (tests and users' scripts): ready, mode, transform,
// frameIndex, state, updates, lags (live: s from the map state's writing to its drawing), seek(k),
// play(), pause(), select(id), setView({x, y, w, h}) (SVG pixels; double-click: the whole plan).
import { $, S, WT, drawPlan, getJSON, select } from "./page.js";
import { initZoom, setView } from "./zoom.js";
import { initRun } from "./timeline.js";
import { initLive } from "./live.js";

WT.select = select;
WT.setView = setView;

// ---------------------------------------------------------------- start
async function start() {
  S.plan = await getJSON("api/plan");
  S.T = S.plan.transform;
  WT.mode = S.plan.mode;
  WT.transform = S.T;
  document.title = `worldtrack — ${S.plan.name}`;
  $("title").textContent = S.plan.title;
  $("mode").textContent = S.plan.mode === "live" ? "live map" : "finished run";
  drawPlan();
  initZoom();
  setView(S.view);
  $("plan").addEventListener("click", () => { if (!S.dragged) select(null); S.dragged = false; });
  $("p-close").addEventListener("click", () => select(null));
  if (S.plan.mode === "run") await initRun(); else initLive();
  WT.ready = true;
}
start().catch((e) => { $("conn").textContent = String(e.message || e); $("conn").className = "conn bad"; WT.error = String(e); });
