// worldtrack serve, a finished run: the timeline (scrub, play, step), trails and history from tracks.csv.
import { $, S, WT, fmt, getJSON, render, toSvg } from "./page.js";
import { extent, fitTo } from "./zoom.js";

let run = null;

// ---------------------------------------------------------------- a finished run
function lastAtOrBefore(arr, value, key) {      // binary search: last index with key(arr[i]) <= value
  let lo = 0, hi = arr.length - 1, best = -1;
  while (lo <= hi) { const mid = (lo + hi) >> 1; if (key(arr[mid]) <= value) { best = mid; lo = mid + 1; } else hi = mid - 1; }
  return best;
}

export async function initRun() {
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
  S.clockText = (t) => `${fmt(t, 2)} s`;
  S.trailOf = (id) => {
    const rows = byId.get(id) || [], t = run.times[WT.frameIndex];
    const end = lastAtOrBefore(rows, t, time), out = [];
    for (let j = end; j >= 0 && time(rows[j]) >= t - S.plan.trail_s; j--) out.push([R.x[rows[j]], R.y[rows[j]]]);
    return out.reverse();
  };
  S.historyOf = async (id) => (byId.get(id) || []).map((i) => [time(i), R.x[i], R.y[i]]);
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
    if (S.plan.frames.length && (!playing || now - lastFrameAt > 250)) {
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
  if (S.plan.frames.length) {
    $("frame-panel").hidden = false;
    for (const c of S.plan.frames) { const o = document.createElement("option"); o.value = o.textContent = c; $("frame-cam").append(o); }
    $("frame-cam").addEventListener("change", () => seek(WT.frameIndex));
  }
  Object.assign(WT, { seek, play, pause, frames: run.frames, times: run.times });
  const everyone = R.x.map((x, i) => toSvg(x, R.y[i]));
  S.peoplePoints = () => everyone;
  if (everyone.length) {
    const [u0, u1, v0, v1] = extent(everyone);
    if ((u1 - u0) * (v1 - v0) < 0.3 * S.T.width * S.T.height)
      fitTo(everyone);                            // people use a small part of the plan: start there
  }
  $("map-line").textContent = `${run.frames.length} frames, ${byId.size} people, ${fmt(tEnd, 1)} s`;
  seek(0);
}
