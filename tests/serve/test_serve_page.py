"""The page of a finished run in a real browser: one element per person at the right frame, at the
positions of tracks.csv (within a pixel of the scene-to-SVG transform), scrubbing, playing, clicking."""

from __future__ import annotations

import numpy as np

from worldtrack.io.tracks import read_tracks
from worldtrack.scene import load_scene
from worldtrack.serve.plan import PlanTransform, cameras_seeing

from _servekit import DOTS_JS, open_page

def expected(run_dir, frame: int) -> dict[int, np.ndarray]:
    """{id: SVG position} of tracks.csv's rows at ``frame``, through the scene-to-SVG transform."""
    table = read_tracks(run_dir / "tracks.csv")
    transform = PlanTransform.fit(load_scene(run_dir.parent / "syn" / "scene.yaml"))
    rows = np.flatnonzero(table.frame == frame)
    return dict(zip(table.id[rows].tolist(), transform.to_svg(table.xy[rows])))


def check_frame(page, run_dir, frame: int) -> dict[int, tuple[float, float]]:
    dots = page.evaluate(DOTS_JS)
    want = expected(run_dir, frame)
    got = {d["id"]: (d["u"], d["v"]) for d in dots}
    assert len(dots) == len(got), "two elements for one person"
    assert set(got) == set(want), f"frame {frame}: ids on the page {sorted(got)}, in tracks.csv {sorted(want)}"
    for pid, uv in got.items():
        err = float(np.hypot(*(np.array(uv) - want[pid])))
        assert err < 1.0, f"frame {frame}, person {pid}: {err:.2f} px from tracks.csv's position"
    return got


def test_scrubbing_puts_every_person_where_tracks_csv_says(page, run_server, finished_run):
    open_page(page, run_server.url)
    frames = page.evaluate("window.worldtrack.frames")
    table = read_tracks(finished_run / "tracks.csv")
    assert frames[0] == 0 and frames[-1] == int(table.frame.max())
    assert page.locator("#people .person").count() == int((table.frame == 0).sum())
    seen = []
    for k in (int(table.frame.min()), len(frames) // 2, len(frames) - 1):
        page.locator("#scrub").fill(str(k))                   # the slider, as a user drags it
        assert page.evaluate("window.worldtrack.frameIndex") == k
        assert f"frame {frames[k]}" in page.locator("#clock").inner_text()
        seen.append(check_frame(page, finished_run, frames[k]))
    t_now = table.time[table.frame == frames[-1]][0]
    assert page.locator("#layer-trails polyline").count() >= 2
    for line in page.locator("#layer-trails polyline").all():       # trails: the last 2 s (--trail 2)
        pid = int(line.get_attribute("data-id"))
        rows = (table.id == pid) & (table.time <= t_now + 1e-6) & (table.time >= t_now - 2.0 - 1e-6)
        assert len(line.get_attribute("points").split()) == int(rows.sum())
    moved = [pid for pid in set(seen[1]) & set(seen[2]) if np.hypot(*np.subtract(seen[1][pid], seen[2][pid])) > 5]
    assert moved, "nobody moved between the middle and the last frame"
    page.keyboard.press("ArrowLeft")                          # keys step one frame (focus on the page)
    page.locator("#plan").click(position={"x": 2, "y": 2})
    page.keyboard.press("ArrowLeft")
    check_frame(page, finished_run, frames[page.evaluate("window.worldtrack.frameIndex")])


def test_play_runs_through_the_timeline(page, run_server, finished_run):
    open_page(page, run_server.url)
    page.select_option("#speed", "4")
    page.click("#play")
    page.wait_for_function("window.worldtrack.frameIndex >= window.worldtrack.frames.length - 1", timeout=10000)
    assert page.locator("#play").inner_text() == "▶"          # stopped at the end
    check_frame(page, finished_run, page.evaluate("window.worldtrack.frames.at(-1)"))


def test_click_person_shows_history_cameras_and_frame(page, run_server, finished_run):
    open_page(page, run_server.url)
    table = read_tracks(finished_run / "tracks.csv")
    frames = page.evaluate("window.worldtrack.frames")
    k = len(frames) // 2
    page.locator("#scrub").fill(str(k))
    pid = int(table.id[table.frame == frames[k]][0])
    page.click(f'#people .person[data-id="{pid}"] .dot')
    assert page.locator("#person-panel").is_visible()
    assert page.locator("#p-id").inner_text() == str(pid)
    info = page.evaluate("""() => Object.fromEntries([...document.querySelectorAll('#p-info dt')].map(
        dt => [dt.textContent, dt.nextElementSibling.textContent]))""")
    scene = load_scene(finished_run.parent / "syn" / "scene.yaml")
    row = np.flatnonzero((table.frame == frames[k]) & (table.id == pid))[0]
    cams = cameras_seeing(scene, table.xy[row], table.extra["height"][row].astype(float))[0]
    assert info["seen by"] == (", ".join(cams) or "no camera")
    assert info["position"] == f"{table.x[row]:.2f}, {table.y[row]:.2f} m"
    history = page.locator("#layer-history polyline").get_attribute("points").split()
    assert len(history) == int((table.id == pid).sum())           # the whole track, every row
    assert page.locator("#layer-sightlines line").count() == len(cams)
    img = page.locator("#frame-img")                               # --frames: the annotated frame
    assert img.get_attribute("src").endswith(f"/c1/{frames[k]}")
    page.wait_for_function("document.getElementById('frame-img').naturalWidth === 320", timeout=10000)


def test_unmeasurable_people_are_drawn_differently(page, run_server, finished_run):
    table = read_tracks(finished_run / "tracks.csv")
    flagged = np.flatnonzero(np.char.find(table.extra["flags"].astype(str), "unmeasurable") >= 0)
    assert len(flagged) == 1                                  # the fixture flags one row
    frame, marked = int(table.frame[flagged[0]]), int(table.id[flagged[0]])
    open_page(page, run_server.url)
    page.evaluate(f"window.worldtrack.seek(window.worldtrack.frames.indexOf({frame}))")
    dots = {d["id"]: d["cls"] for d in page.evaluate(DOTS_JS)}
    assert "unmeasurable" in dots[marked].split()
    assert all("unmeasurable" not in c.split() for pid, c in dots.items() if pid != marked)
    dash = page.evaluate(f"""getComputedStyle(document.querySelector(
        '#people .person[data-id="{marked}"] .dot')).strokeDasharray""")
    assert dash not in ("", "none")
    page.evaluate(f"window.worldtrack.seek(window.worldtrack.frames.indexOf({frame + 1}))")
    assert "unmeasurable" not in page.locator(f'#people .person[data-id="{marked}"]').get_attribute("class")


def test_zoom_and_a_narrow_window_keep_the_transform(page, run_server, finished_run, tmp_path):
    """The SVG scales with the window and zooms with the wheel: positions in SVG units stay those of
    the transform, the dots keep their size on screen and the σ circles their size in metres."""
    page.set_viewport_size({"width": 700, "height": 700})
    open_page(page, run_server.url)
    frames = page.evaluate("window.worldtrack.frames")
    k = len(frames) // 2
    page.evaluate(f"window.worldtrack.seek({k})")
    check_frame(page, finished_run, frames[k])
    width = "document.querySelector('#people .person .dot').getBoundingClientRect().width"
    sigma = "document.querySelector('#people .person .sigma').getBoundingClientRect().width"
    dot_px, sigma_px = page.evaluate(width), page.evaluate(sigma)
    box = page.locator("#plan").bounding_box()
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    page.mouse.wheel(0, -400)                                  # zoom in about 1.8x
    page.wait_for_timeout(100)
    zoom = page.evaluate("window.worldtrack.transform.width / document.getElementById('plan').viewBox.baseVal.width")
    assert zoom > 1.5
    inside = page.evaluate(DOTS_JS)
    check_frame(page, finished_run, frames[k])
    assert abs(page.evaluate(width) - dot_px) < 0.5
    if sigma_px > 2:
        assert abs(page.evaluate(sigma) / sigma_px - zoom) < 0.05
    assert inside
    page.screenshot(path=str(tmp_path / "zoomed.png"))
