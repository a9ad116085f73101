// worldtrack serve, zoom (wheel), pan (drag), fit; the scale bar. Symbols keep their size on screen.
import { $, S, el, render, text } from "./page.js";

function drawScaleBar() {                       // in the view's corner farthest from every camera
  const g = $("layer-scale"), k = 1 / S.zoom;
  g.replaceChildren();
  const target = 120 / S.T.scale * k;             // about 120 screen px
  const nice = [0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100].find((m) => m >= target * 0.6) || 100;
  const len = nice * S.T.scale, pad = 16 * k;
  const corners = [[S.view.x + pad, S.view.y + S.view.h - pad], [S.view.x + S.view.w - pad - len, S.view.y + S.view.h - pad],
                   [S.view.x + pad, S.view.y + pad + 12 * k], [S.view.x + S.view.w - pad - len, S.view.y + pad + 12 * k]];
  const far = (c) => Math.min(...S.plan.cameras.map((q) => Math.hypot(q.at[0] - c[0] - len / 2, q.at[1] - c[1])), 1e9);
  const [x, y] = corners.reduce((a, b) => (far(b) > far(a) ? b : a));
  el("line", { x1: x, y1: y, x2: x + len, y2: y, class: "scale-bar" }, g);
  el("line", { x1: x, y1: y - 4 * k, x2: x, y2: y + 4 * k, class: "scale-bar" }, g);
  el("line", { x1: x + len, y1: y - 4 * k, x2: x + len, y2: y + 4 * k, class: "scale-bar" }, g);
  const t = text(g, x + len / 2, y - 6 * k, "scale-text", `${nice} m`);
  t.setAttribute("text-anchor", "middle");
  t.style.fontSize = `${11 * k}px`;
}

// ---------------------------------------------------------------- zoom (wheel), pan (drag), fit
export function setView(v) {
  const w = Math.min(S.T.width, Math.max(S.T.width / 60, v.w)), h = w * S.T.height / S.T.width;
  const cx = Math.min(S.T.width, Math.max(0, v.x + v.w / 2)), cy = Math.min(S.T.height, Math.max(0, v.y + v.h / 2));
  S.view = { x: cx - w / 2, y: cy - h / 2, w, h };
  S.zoom = S.T.width / w;
  $("plan").setAttribute("viewBox", `${S.view.x.toFixed(2)} ${S.view.y.toFixed(2)} ${w.toFixed(2)} ${h.toFixed(2)}`);
  const k = 1 / S.zoom;                             // symbols keep their size on screen
  for (const g of document.querySelectorAll("#layer-cameras .camera"))
    g.setAttribute("transform", g.dataset.at + ` scale(${k})`);
  for (const t of document.querySelectorAll("#layer-entries text, #layer-obstacles text"))
    t.style.fontSize = `${11 * k}px`;
  drawScaleBar();
  render(S.current);
}
export function fitTo(points) {                         // [[u, v], …] in SVG pixels
  if (!points.length) return setView({ x: 0, y: 0, w: S.T.width, h: S.T.height });
  const [u0, u1, v0, v1] = extent(points);
  const w = Math.max(u1 - u0, (v1 - v0) * S.T.width / S.T.height) * 1.15 + 4 * S.T.scale;
  setView({ x: (u0 + u1) / 2 - w / 2, y: (v0 + v1) / 2 - w * S.T.height / S.T.width / 2, w, h: w * S.T.height / S.T.width });
}
export function extent(points) {                      // [u0, u1, v0, v1] (no spread: runs have 100k rows)
  let u0 = Infinity, u1 = -Infinity, v0 = Infinity, v1 = -Infinity;
  for (const [u, v] of points) { u0 = Math.min(u0, u); u1 = Math.max(u1, u); v0 = Math.min(v0, v); v1 = Math.max(v1, v); }
  return [u0, u1, v0, v1];
}
export function initZoom() {
  const svg = $("plan");
  S.view = { x: 0, y: 0, w: S.T.width, h: S.T.height };
  svg.addEventListener("wheel", (ev) => {
    ev.preventDefault();
    const p = new DOMPoint(ev.clientX, ev.clientY).matrixTransform(svg.getScreenCTM().inverse());
    const r = Math.exp(Math.max(-1, Math.min(1, ev.deltaY * 0.0015)));
    setView({ x: p.x - (p.x - S.view.x) * r, y: p.y - (p.y - S.view.y) * r, w: S.view.w * r, h: S.view.h * r });
  }, { passive: false });
  let drag = null;
  svg.addEventListener("pointerdown", (ev) => {
    drag = { x: ev.clientX, y: ev.clientY, view: { ...S.view }, s: svg.getScreenCTM().a, moved: false };
  });
  window.addEventListener("pointermove", (ev) => {
    if (!drag || !(ev.buttons & 1)) return;
    if (Math.hypot(ev.clientX - drag.x, ev.clientY - drag.y) > 4) drag.moved = true;
    if (drag.moved) setView({ ...drag.view, x: drag.view.x - (ev.clientX - drag.x) / drag.s,
                              y: drag.view.y - (ev.clientY - drag.y) / drag.s });
  });
  window.addEventListener("pointerup", () => { S.dragged = !!(drag && drag.moved); drag = null; });
  svg.addEventListener("dblclick", () => setView({ x: 0, y: 0, w: S.T.width, h: S.T.height }));
  $("fit-all").addEventListener("click", () => setView({ x: 0, y: 0, w: S.T.width, h: S.T.height }));
  $("fit-people").addEventListener("click", () => fitTo(S.peoplePoints()));
}
