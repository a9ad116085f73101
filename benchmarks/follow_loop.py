"""The closed loop (seed 001): the robot's camera moves by the follower's commands, frame by frame.

Question: does the simulated robot keep the target within ±0.3 m of the set distance (1.8 m) 95 %
of the time, and never drive into anybody or anything?

Each seed's ``follow-target`` sequence (:data:`follow_common.SCENARIO`, 1500 frames at 10 fps,
160×120) is rendered from where the robot is at each frame (:func:`worldtrack.follow.loop.run_closed_loop`):
a unicycle robot (1.6 m/s, 1.5 rad/s, 1.5 m/s²) with a bumper, driven by the chosen follower
(``--follower``, :data:`FOLLOWERS`; by default the PID with the depth stop, the people's velocities
and a simulated 270° range scanner round the robot). The distance is measured from the camera to the
true target over **every** frame: the robot starts at the set distance, so there is no start-up
window, and frames where the target is hidden or lost count like any other.

The other people were scripted for the scenario's planned robot, not this one, so they do not make
way for it. Every frame with a person within 0.5 m of the robot's centre is a *contact*, and each is
put down to whoever closed in faster: a *collision* (the acceptance figure) when the robot drove at
them at least as fast as they came (split into "unseen" — not visible to the camera in the last
second — and "seen, not stopped"), *walked into the robot* when the person closed in faster (the
robot standing, or slower), *side by side* when neither closed in. Episodes are runs of consecutive
contact frames with one person. While somebody stands in the robot's path it must wait, so the
fraction is also given without those frames and the 3 s after each (catching up), and the frames
outside the band are split by what was going on (held, catching up, target not found, too near).

Run: ``.venv/bin/python benchmarks/follow_loop.py [--seeds 0-9] [--follower NAME] [--plot] [--quick]``. Writes
``benchmarks/results/follow_loop.md``. A seed takes 2–3 min of CPU (rendering most of it).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table  # noqa: E402
from follow_common import SCENARIO, save_tagged, seed_cached  # noqa: E402
from follow_synth import parse_seeds  # noqa: E402

from worldtrack.follow import FollowConfig, FollowTracker, PIDFollower  # noqa: E402
from worldtrack.follow.pid import pursuit_map  # noqa: E402
from worldtrack.follow.planner import LocalPlanner  # noqa: E402
from worldtrack.errors import InputError  # noqa: E402
from worldtrack.follow.loop import run_closed_loop  # noqa: E402
from worldtrack.synth import make_scenario  # noqa: E402

DISTANCE = 1.8
TOLERANCE = 0.3
RECOVER_S = 3.0
#: Half the robot camera's horizontal field of view (66°): a target farther off the heading is out of view.
HALF_VIEW_DEG = 33.0


FOLLOWERS = {
    "pid+scan": "the PID with the depth safety layer, people's velocities (walkers) and a 270° range scanner (default)",
    "pid+scan-nosearch": "pid+scan without the search turn (a lost target's prediction is only faced)",
    "pid+walkers": "the PID with the depth safety layer and people's velocities, camera only",
    "pid+depth": "the PID with the depth safety layer (35e's default), camera only",
    "pid": "the paper's PID",
    "planner": "the dynamic-window local planner (35e)",
}


def make_follower(name: str, scene, pid_settings: dict | None = None):
    """The follower ``name`` (:data:`FOLLOWERS`) in ``scene``; ``pid_settings``: PIDFollower fields to change."""
    if name == "planner":
        return LocalPlanner(scene, distance=DISTANCE)
    return PIDFollower(distance=DISTANCE, depth_stop=name != "pid", walkers=name.startswith(("pid+walkers", "pid+scan")),
                       search_look=None if name.endswith("nosearch") else 2.0, nav=pursuit_map(scene),
                       **(pid_settings or {}))


def split_settings(settings: dict) -> tuple[dict, dict]:
    """``--set`` items as (tracker settings, follower settings): names ``pid.NAME`` go to the PIDFollower."""
    pid = {k[4:]: v for k, v in settings.items() if k.startswith("pid.")}
    return {k: v for k, v in settings.items() if not k.startswith("pid.")}, pid


def run_seed(seed: int, frames: int, size, follower: str = "pid+scan", tracker_config: dict | None = None) -> dict:
    sc = make_scenario("follow-target", size=size, frames=frames, seed=seed, distance=DISTANCE, **SCENARIO)
    tracker_config, pid_settings = split_settings(tracker_config or {})
    pid = make_follower(follower, sc.scene, pid_settings)
    tracker = FollowTracker(FollowConfig.preset("default", **tracker_config), sc.scene)
    blocked = []
    result = run_closed_loop(sc, tracker=tracker, follower=pid, on_frame=lambda b, s, c: blocked.append(pid.blocked),
                             side_scan=follower.startswith("pid+scan"))
    blocked = np.array(blocked)
    within = np.abs(result.distance - DISTANCE) <= TOLERANCE
    held = blocked.copy()
    for k in np.flatnonzero(blocked):
        held[k:k + int(RECOVER_S * sc.fps) + 1] = True
    return {"within": within, "free": ~held, "blocked": blocked, "result": result}


def out_of_band(s: dict) -> dict:
    """Frames outside the band, by what was going on, first match: held by someone in the path, the 3 s
    after a hold (catching up), the target not found (out of the camera's view, or in it), the 3 s after
    the target was found again following ≥ 0.5 s unseen (catching up after a loss), the robot too near
    (the target turned or stopped), too far with the target more than 30° off the heading (turning),
    too far, other."""
    r = s["result"]
    err = r.distance - DISTANCE
    held, after = s["blocked"], ~s["free"] & ~s["blocked"]
    fwd = r.camera_xy - r.robot_xy
    rel = r.target_xy - r.camera_xy
    off = np.abs(np.arctan2(fwd[:, 0] * rel[:, 1] - fwd[:, 1] * rel[:, 0], np.einsum("tc,tc->t", fwd, rel)))
    unseen = ~r.found
    fps = 1.0 / float(r.times[1] - r.times[0])
    after_loss = np.zeros_like(unseen)
    edges = np.flatnonzero(np.diff(unseen.astype(int)) != 0) + 1
    for run in np.split(np.arange(len(unseen)), edges):
        if unseen[run[0]] and len(run) >= 0.5 * fps:
            after_loss[run[-1] + 1:run[-1] + 1 + int(round(RECOVER_S * fps))] = True
    labels = np.select([held, after, unseen & (off > np.radians(HALF_VIEW_DEG)), unseen, after_loss, err < 0, off > np.radians(30.0)],
                       ["held", "catch-up after a hold", "target not found, out of view", "target not found, in view",
                        "catch-up after a loss", "too near (target turned or stopped)", "too far, turning"],
                       "too far, other")
    names, counts = np.unique(labels[np.abs(err) > TOLERANCE], return_counts=True)
    return dict(zip(names.tolist(), counts.tolist()))


def opening_collisions(causes: list) -> int:
    """Collision frames (the robot's doing by :class:`~worldtrack.follow.loop.Collision`'s rule) in which the
    gap was opening for every person counted: they moved away faster than the robot still moved towards
    them (often after walking into it). Reported beside the collisions, not taken off them."""
    frames: dict = {}
    for c in causes:
        if c.robot_fault:
            frames[c.frame] = frames.get(c.frame, True) and c.robot_speed + c.person_speed < 0.0
    return sum(frames.values())


def contact_episodes(causes: list) -> dict:
    """Runs of consecutive contact frames with one person: "robot" if the robot drove into them in any
    frame of the run, "walked" if they walked into it in any frame and the robot never drove."""
    runs: dict = {}
    for c in causes:
        runs.setdefault(c.person, []).append(c)
    out = {"robot": 0, "walked": 0}
    for person, cs in runs.items():
        frames = np.array([c.frame for c in cs])
        for run in np.split(np.arange(len(cs)), np.flatnonzero(np.diff(frames) > 1) + 1):
            kinds = {cs[i].cause for i in run}
            if kinds & {"unseen", "seen, not stopped"}:
                out["robot"] += 1
            elif "walked into the robot" in kinds:
                out["walked"] += 1
    return out


def plot_seed(s: dict, seed: int, frames: int, path: Path) -> None:
    """Plan view of one closed-loop run — the robot (colour: time), the target, the others, the frames
    outside the band and every collision — over the distance error with the held / not-found frames."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    r = s["result"]
    sc = make_scenario("follow-target", size=(160, 120), frames=frames, seed=seed, distance=DISTANCE, **SCENARIO)
    t = r.times
    err = r.distance - DISTANCE
    fig = plt.figure(figsize=(13, 9))
    ax, ax2 = fig.add_axes([0.05, 0.32, 0.9, 0.64]), fig.add_axes([0.05, 0.05, 0.9, 0.22])
    df = sc.scene.distance_field(0.05)
    gx, gy = np.meshgrid(np.linspace(0, 16, 321), np.linspace(0, 12, 241))
    inside = df.sample(np.column_stack([gx.ravel(), gy.ravel()]), outside=-1.0).reshape(gx.shape) < 0.01
    ax.contourf(gx, gy, inside, levels=[0.5, 1.5], colors=["#bbbbbb"])
    ax.scatter(*r.robot_xy.T, c=t, cmap="viridis", s=3, label="robot (colour: time)")
    ax.plot(*r.target_xy.T, "r-", lw=0.6, label="target (person 1)")
    for p, colour in zip(sc.people[1:], ["tab:orange", "tab:purple", "tab:brown", "tab:pink"]):
        ax.plot(*np.where(p.track.present[:, None], p.track.xy, np.nan).T, "-", color=colour, lw=0.6,
                label=f"person {p.id}")
    ax.plot(*r.robot_xy[np.abs(err) > TOLERANCE].T, "x", color="k", ms=3, label=f"robot, target outside ±{TOLERANCE} m")
    last: dict = {}
    for c in r.collision_causes:
        if c.cause != "side by side":
            ax.plot(*r.robot_xy[c.frame], "o", mfc="none", mec="red", ms=10)
            if last.get(c.person, -9) < c.frame - 1:        # label the first frame of each episode
                ax.annotate(f"{c.frame} p{c.person}: {c.cause}", r.robot_xy[c.frame], fontsize=7, color="red")
            last[c.person] = c.frame
    for k in range(0, len(t), 100):
        ax.annotate(f"{t[k]:.0f} s", r.robot_xy[k], fontsize=7)
    ax.set_aspect("equal")
    ax.legend(fontsize=7, loc="upper right")
    ax.set_title(f"seed {seed}: within ±{TOLERANCE} m {np.mean(np.abs(err) <= TOLERANCE):.3f}, "
                 f"collisions {r.collisions}, walked into {getattr(r, 'walked_into', 0)}")
    ax2.plot(t, err, "k-", lw=0.7)
    ax2.axhspan(-TOLERANCE, TOLERANCE, color="g", alpha=0.15)
    ax2.fill_between(t, -1, 3, where=s["blocked"], color="orange", alpha=0.4, label="held by someone in the path")
    ax2.fill_between(t, -1, 3, where=~r.found, color="blue", alpha=0.2, label="target not found")
    for c in r.collision_causes:
        if c.robot_fault:
            ax2.axvline(t[c.frame], color="r", lw=0.5)
    ax2.set(ylim=(-1, 2.5), xlim=(0, t[-1]), ylabel=f"distance − {DISTANCE} m", xlabel="time s")
    ax2.legend(fontsize=7, loc="upper right")
    fig.savefig(path, dpi=90)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", default="0-9")
    ap.add_argument("--frames", type=int, default=1500)
    ap.add_argument("--follower", choices=tuple(FOLLOWERS), default="pid+scan",
                    help="; ".join(f"{k}: {v}" for k, v in FOLLOWERS.items()))
    ap.add_argument("--quick", action="store_true", help="dev seed 100, 200 frames (prints only)")
    ap.add_argument("--cache", help="keep each seed's records in this folder (split seeds over processes)")
    ap.add_argument("--tag", default="", help="write results/<name><TAG>.md beside the main table")
    ap.add_argument("--plot", action="store_true", help="also draw the seed with the least time within the band "
                                                        "(results/follow_loop<TAG>_worst.png)")
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                    help="a tracker setting (FollowConfig field, a number), e.g. reid_any_track_after=inf, or a "
                         "follower one (pid.NAME: PIDFollower field), e.g. pid.search_turn_rate=1; repeatable "
                         "(s10's defaults: reid_any_track_after=inf pid.map_approach=0 pid.reverse_guard=0)")
    args = ap.parse_args(argv)
    try:
        settings = {k: float(v) for k, v in (item.split("=", 1) for item in args.set)}
        tracker_settings, pid_settings = split_settings(settings)
        FollowConfig.preset("default", **tracker_settings)
        PIDFollower(**pid_settings)
    except (ValueError, InputError, TypeError) as err:
        print(f"follow_loop: --set: {err}", file=sys.stderr)
        return 2
    setting_key = "".join(f"-{k}={v:g}" for k, v in sorted(settings.items()))
    seeds = [100] if args.quick else parse_seeds(args.seeds)
    frames = 200 if args.quick else args.frames
    t0 = time.perf_counter()
    rows, all_within, all_free_within, records = [], [], [], {}
    totals = {"contacts": 0, "collisions": 0, "walked_into": 0, "bumps": 0, "opening": 0}
    episodes = {"robot": 0, "walked": 0}
    causes: dict = {}
    where = {}
    collision_rows = []
    for seed in seeds:
        ts = time.perf_counter()
        s = seed_cached(args.cache, f"loop-{args.follower}{setting_key}-{seed}-{frames}",
                        lambda: run_seed(seed, frames, (160, 120), args.follower, settings))
        r = s["result"]
        records[seed] = s
        err = np.abs(r.distance - DISTANCE)
        all_within.append(s["within"])
        all_free_within.append(s["within"][s["free"]])
        for k in totals:
            totals[k] += getattr(r, k, 0)
        lost_by = out_of_band(s)
        for name, n_frames in lost_by.items():
            where[name] = where.get(name, 0) + n_frames
        largest = max(lost_by.items(), key=lambda kv: kv[1], default=("none", 0))
        totals["opening"] += opening_collisions(r.collision_causes)
        for kind, n_ep in contact_episodes(r.collision_causes).items():
            episodes[kind] += n_ep
        for c in r.collision_causes:
            causes[c.cause] = causes.get(c.cause, 0) + 1
            collision_rows.append([seed, c.frame, c.person, f"{c.distance:.2f}", f"{c.robot_speed:.2f}",
                                   f"{c.person_speed:.2f}", f"{c.visible:.2f}", "yes" if c.tracked else "no",
                                   "yes" if c.blocked else "no", c.cause])
        rows.append([seed, f"{s['within'].mean():.3f}", f"{s['within'][s['free']].mean():.3f}",
                     f"{s['blocked'].mean():.3f}", f"{np.median(err):.2f}", f"{np.percentile(err, 95):.2f}",
                     f"{err.max():.2f}", f"{r.found.mean():.3f}", r.contacts, r.collisions,
                     getattr(r, "walked_into", 0), r.bumps, f"{r.nearest_person.min():.2f}", f"{r.clearance.min():.2f}",
                     f"{largest[0]} {largest[1] / len(err):.3f}"])
        print(f"seed {seed}: within ±{TOLERANCE} m {s['within'].mean():.3f} (free path {s['within'][s['free']].mean():.3f}), "
              f"collisions {r.collisions}, walked into {getattr(r, 'walked_into', 0)}, contacts {r.contacts} "
              f"({time.perf_counter() - ts:.0f} s)", file=sys.stderr, flush=True)
    pooled = np.concatenate(all_within).mean()
    pooled_free = np.concatenate(all_free_within).mean()
    n_all = sum(len(w) for w in all_within)
    table = markdown_table(["seed", f"within ±{TOLERANCE} m", "same, path free", "robot held (someone in path)",
                            "median |error| m", "95th pct m", "max m", "target found", "contacts",
                            "collisions (robot's doing)", "walked into the robot", "bumper stops",
                            "nearest person m", "nearest wall m",
                            "largest share outside the band (of all frames)"], rows)
    text = (f"Follower: {args.follower} — {FOLLOWERS[args.follower]}. Tracker settings: {settings or 'defaults'}. Seeds {', '.join(map(str, seeds))}; {frames} "
            f"frames at 10 fps, 160x120; set distance {DISTANCE} m. Every frame counts (the robot starts at the set "
            f"distance; no start-up or target-unseen window is left out).\n\n"
            f"- within ±{TOLERANCE} m of the set distance: **{pooled:.3f}** of all frames (target ≥ 0.95); "
            f"{pooled_free:.3f} of the frames when nobody held the robot up (those frames and the {RECOVER_S:g} s "
            f"after left out)\n- outside ±{TOLERANCE} m, share of all frames, by what was going on: "
            + ", ".join(f"{k} {v / n_all:.3f}" for k, v in sorted(where.items(), key=lambda kv: -kv[1]))
            + f"\n- collisions (the robot driving into someone within 0.5 m, centre to centre, at least as fast as "
            f"they close in): **{totals['collisions']}** frames in {episodes['robot']} episodes (of which {totals['opening']} with the "
            f"gap opening: the person moving away faster than the robot still moved towards them); people walking "
            f"into the robot (closing faster than it): {totals['walked_into']} frames in {episodes['walked']} "
            f"episodes; contacts of any kind {totals['contacts']} frames; bumper stops {totals['bumps']}\n"
            f"- contact frames by cause: " + (", ".join(f"{k} {v}" for k, v in sorted(causes.items())) or "none")
            + f"\n\n{table}\n")
    if collision_rows:
        text += ("\n## Every contact (person within 0.5 m) per frame\n\nspeeds towards each other (m/s); visible: "
                 "the person's largest visible share in the robot's camera over the last second; tracked: a "
                 "candidate or track of the follower within 0.5 m; held: the path check held the robot.\n\n"
                 + markdown_table(["seed", "frame", "person", "distance m", "robot speed", "person speed", "visible",
                                   "tracked", "held", "cause"], collision_rows) + "\n")
    if args.plot and not args.quick:
        worst = min(records, key=lambda k: records[k]["within"].mean())
        png = Path(__file__).resolve().parent / "results" / f"follow_loop{args.tag}_worst.png"
        plot_seed(records[worst], worst, frames, png)
        text += f"\nPicture of the worst seed ({worst}): `{png.name}`.\n"
    print(text)
    save_tagged("follow_loop", args.tag, "The closed loop: a simulated robot follows (seed 001)", text, args.quick,
                time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
