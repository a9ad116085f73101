"""Two workers on the shared map against one process with both cameras, on held-out two-rooms seeds.

Question (issue 39): do the fused tracks of two ``worldtrack track --map`` workers (one camera
each) score at least as well (MOTA, IDF1, 0.5 m gate) as one ``worldtrack track`` with both
cameras, and where they do not, in which frames and why?

Set-up: ``two-rooms`` 320x240, 10 frames/s; seeds 2 and 5-13 held out (the map was developed on
seeds 0 and 1, the test uses seed 1, issue 39e's share rule on 1, 3 and 4; 2-6 were measured by
39c/39d); ``--set map.share_rule=support-lead`` measures the rule before 39e; the workers in batch (``map.pace_files=false``: each waits for
the complete bucket of its previous frame, so runs repeat), their tracks from ``worldtrack
replay``. Per run: MOTA, IDF1, switches of both, and the frames in which the fused tracks have a
miss or a false positive the one process does not have (``worse frames``), with the first of them.

Run: ``nice -n 10 .venv/bin/python benchmarks/map_two_workers.py [--seeds 2,5,6,7,8,9,10,11,12,13,1,3,4] [--repeats 1]``
(since issue 39h batch runs repeat byte for byte: the ``map digest`` column; ``--also map.X=Y,…`` adds
a variant run per seed, e.g. ``--also map.weigh_own=true``).
Writes ``benchmarks/results/map_two_workers.md``.
"""

from __future__ import annotations

import argparse
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table, save_result  # noqa: E402
from map_rig import WORLDTRACK, Server, load_average, run_workers  # noqa: E402

from worldtrack.eval.mot import evaluate_detailed  # noqa: E402
from worldtrack.io.tracks import read_tracks  # noqa: E402
from worldtrack.map.connection import MapKeys, connect  # noqa: E402
from worldtrack.map.messages import Estimate, MapPerson  # noqa: E402
from worldtrack.map.rays import ViewRay  # noqa: E402
from worldtrack.map.replay import record_digest, replay  # noqa: E402
from worldtrack.synth import make_scenario, write_sequence  # noqa: E402


def worse_frames(one, fused) -> list[int]:
    """Frames where the fused tracks have more misses + false positives than the one process."""
    a, b = one.per_frame, fused.per_frame
    errors = {int(f): int(m + fp) for f, m, fp in zip(a["frame"], a["misses"], a["false_positives"])}
    return [int(f) for f, m, fp in zip(b["frame"], b["misses"], b["false_positives"]) if m + fp > errors.get(int(f), 0)]


def dump_run(client, cameras: list[str], seq: Path, run: int, out: Path) -> None:
    """The run's evidence as CSV files in ``out``: ``estimates.csv`` (every worker's published
    estimate of every person, per camera and frame), ``rays.csv`` (with ``map.head_rays``: their
    cameras' own head and feet rays), ``map.csv`` (the record: per bucket every
    person, their lead and how many workers), ``gt.csv`` and ``one.csv`` (the one process)."""
    import shutil

    from worldtrack.map.messages import decode_map_state, decode_observation

    out.mkdir(parents=True, exist_ok=True)
    keys = MapKeys()
    # Each observation once: its people's estimates, and (map.head_rays) each camera's own head and feet rays.
    with open(out / "estimates.csv", "w") as est, open(out / "rays.csv", "w") as rays:
        est.write("t,camera,worker,frame," + ",".join(Estimate._fields) + "\n")
        rays.write("t,camera,worker,frame," + ",".join(ViewRay._fields) + "\n")
        for cam in cameras:
            for _, fields in client.xrange(keys.observations(cam)):
                o = decode_observation(fields)
                head = f"{o.t:.3f},{o.camera},{o.worker},{o.frame},"
                est.writelines(head + ",".join(str(v) for v in e) + "\n" for e in o.people)
                rays.writelines(head + ",".join(str(v) for v in r) + "\n" for r in o.rays)
    with open(out / "map.csv", "w") as f:
        f.write("t," + ",".join(MapPerson._fields) + "\n")
        for _, fields in client.xrange(keys.map_stream):
            s = decode_map_state(fields)
            for p in s.people:
                f.write(f"{s.t:.3f}," + ",".join(str(v) for v in p) + "\n")
    with open(out / "buckets.csv", "w") as f:
        f.write("t,late,cameras\n")
        for _, fields in client.xrange(keys.map_stream):
            s = decode_map_state(fields)
            f.write(f"{s.t:.3f},{s.late},{' '.join(sorted({c for c, _, _ in s.reports}))}\n")
    shutil.copy(seq / "gt.csv", out / "gt.csv")
    shutil.copy(seq / "one" / "tracks.csv", out / "one.csv")


def incomplete_buckets(client, cameras: list[str]) -> tuple[int, int]:
    """How many buckets of the record lack some camera's report, and how many observations came
    after their bucket was written (dropped as late): a batch run that should repeat does not when
    either is above 0 (the fusion wrote a bucket ``map.max_wait_s`` after its first report)."""
    from worldtrack.map.messages import decode_map_state

    states = [decode_map_state(fields) for _, fields in client.xrange(MapKeys().map_stream)]
    missing = sum(1 for s in states[1:-1] if {c for c, _, _ in s.reports} != set(cameras))
    return missing, sum(s.late for s in states)


def any_affirms(client, cameras: list[str]) -> bool:
    """Did any worker of the run affirm another's candidate (:mod:`worldtrack.map.affirm`)?"""
    from worldtrack.map.messages import decode_observation
    return any(decode_observation(fields).affirms for cam in cameras
               for _, fields in client.xrange(MapKeys().observations(cam)))


def same_blob_folds(client, cameras: list[str], gt) -> tuple[int, int]:
    """How many same-blob claims the run's workers published (:mod:`worldtrack.map.same_blob`), and how
    many of them paired two different people: the ground-truth person nearest to the claimer's
    estimate of its id is not the one nearest to the other worker's estimate of theirs (same frame)."""
    import numpy as np

    from worldtrack.map.messages import decode_observation
    obs = [decode_observation(fields) for cam in cameras for _, fields in client.xrange(MapKeys().observations(cam))]
    where = {(o.worker, o.frame, e.id): (e.x, e.y) for o in obs for e in o.people}
    claims = [(o, a, b) for o in obs for a, b in o.same]
    wrong = 0
    for o, a, b in claims:
        at = gt.frame == o.frame
        other = next(((w, f, i) for (w, f, i) in where if f == o.frame and i == b and w != o.worker), None)
        if (o.worker, o.frame, a) not in where or other is None or not at.any():
            continue
        nearest = [int(gt.id[at][np.argmin(np.hypot(gt.x[at] - x, gt.y[at] - y))])
                   for x, y in (where[o.worker, o.frame, a], where[other])]
        wrong += nearest[0] != nearest[1]
    return len(claims), wrong


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", default="2,5,6,7,8,9,10,11,12,13,1,3,4")
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--quick", action="store_true", help="seed 2, one run; prints only")
    ap.add_argument("--set", action="append", default=[], metavar="map.NAME=VALUE",
                    help="a map setting for the workers (e.g. map.share_rule=support-lead)")
    ap.add_argument("--also", action="append", default=[], metavar="map.A=X,map.B=Y",
                    help="a variant run once more per seed with these settings (repeatable; runs are deterministic)")
    ap.add_argument("--only-if-affirmed", action="store_true",
                    help="run the --also variants only for seeds whose default run confirmed a candidate on another "
                         "worker's view (Observation.affirms; without one the variant map.affirm_candidates=false "
                         "runs the same steps and writes the same map)")
    ap.add_argument("--only-if-same", action="store_true",
                    help="run the --also variants only for seeds whose default run published a same-blob claim "
                         "(Observation.same; without one the variant map.same_blob_iou=0 writes the same map)")
    ap.add_argument("--dump", type=Path, help="write per run and variant (seedS_runK/VARIANT) the workers' published estimates, the map and the "
                                             "one process's tracks as CSV files in this folder (to find out why)")
    args = ap.parse_args()
    seeds, repeats = ([2], 1) if args.quick else ([int(s) for s in args.seeds.split(",")], args.repeats)
    variants = [("default", args.set, repeats)] + [(v, [*args.set, *v.split(",")], 1) for v in args.also]
    start, rows, gaps = time.time(), [], {(v, key): [] for v, _, _ in variants for key in ("mota", "idf1")}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        server = Server(tmp)
        try:
            for seed in seeds:
                sc = make_scenario("two-rooms", seed=seed)
                seq = tmp / f"seed{seed}"
                write_sequence(sc, seq, progress=False)
                gt = read_tracks(seq / "gt.csv")
                subprocess.run([*WORLDTRACK, "track", str(seq / "scene.yaml"),
                                *[a for c in sc.camera_ids for a in ("--video", f"{c}={seq / (c + '.mp4')}")],
                                "--out", str(seq / "one"), "--quiet", "--no-video"], check=True, capture_output=True)
                one = evaluate_detailed(gt, read_tracks(seq / "one" / "tracks.csv"))
                affirmed_run, folds_run = None, None
                for variant, sets, k in ((v, sets, k) for v, sets, n in variants for k in range(n)):
                    if variant != "default" and ((args.only_if_affirmed and affirmed_run is False) or
                                                 (args.only_if_same and folds_run == 0)):
                        why = "no affirm" if args.only_if_affirmed and affirmed_run is False else "no same-blob claim"
                        rows.append([seed, f"{variant} (= default: {why})", k, *rows[-1][3:]])   # the same steps
                        for key in ("mota", "idf1"):
                            gaps[variant, key].append(gaps["default", key][-1])
                        continue
                    server.flush()
                    run_workers(seq, server.url, sc.camera_ids, seq / f"workers{k}", sets=["map.pace_files=false", *sets])
                    fused = evaluate_detailed(gt, read_tracks(replay(connect(server.url), MapKeys(),
                                                                     seq / f"replay{k}").tracks_csv))
                    if args.dump:
                        dump_run(connect(server.url), sc.camera_ids, seq, k, args.dump / f"seed{seed}_run{k}" /
                                 re.sub(r"[^\w.=-]+", "_", variant))
                    if variant == "default":
                        affirmed_run = any_affirms(connect(server.url), sc.camera_ids)
                    folds = same_blob_folds(connect(server.url), sc.camera_ids, gt)
                    if variant == "default":
                        folds_run = folds[0]
                    missing, late = incomplete_buckets(connect(server.url), sc.camera_ids)
                    digest = record_digest(connect(server.url), MapKeys())
                    worse = worse_frames(one, fused)
                    m1, m2 = one.metrics, fused.metrics
                    rows.append([seed, variant, k, m1["mota"], m2["mota"], m1["idf1"], m2["idf1"], m1["num_switches"],
                                 m2["num_switches"], len(worse), f"{worse[0]}–{worse[-1]}" if worse else "—", "%d (%d)" % folds,
                                 missing, late, digest])
                    for key in ("mota", "idf1"):
                        gaps[variant, key].append(m2[key] - m1[key])
                    print(rows[-1], file=sys.stderr)
        finally:
            server.stop()
    table = markdown_table(["seed", "variant", "run", "MOTA one", "MOTA workers", "IDF1 one", "IDF1 workers", "switches one",
                            "switches workers", "worse frames", "from–to", "same-blob claims (wrong)",
                            "buckets missing a camera",
                           "late observations", "map digest"], rows)
    summary = "; ".join(
        f"{v}: MOTA mean {statistics.mean(gaps[v, 'mota']):+.3f} (worse in {sum(g < 0 for g in gaps[v, 'mota'])} of "
        f"{len(gaps[v, 'mota'])}), IDF1 mean {statistics.mean(gaps[v, 'idf1']):+.3f} (worse in "
        f"{sum(g < 0 for g in gaps[v, 'idf1'])})" for v, _, _ in variants)
    text = (f"{table}\n\nWorkers − one process over all runs: {summary}. "
            f"Load average at the end: {load_average()} (2 cores shared with other work).\n")
    print(text)
    save_result("map_two_workers", "Two workers on the shared map against one process (two-rooms, held-out seeds)",
                text, args.quick, time.time() - start)


if __name__ == "__main__":
    main()
