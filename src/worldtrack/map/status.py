"""``worldtrack map status``: workers, cameras, leases, lag and people of a shared map, at a glance."""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from typing import Any

from worldtrack.map.connection import MapKeys
from worldtrack.map.messages import FORMAT_VERSION, decode_map_state, time_of_id


@dataclass
class FusionStats:
    """What the fusion role has done (for ``map status`` and the benchmarks)."""

    buckets: int = 0
    observations: int = 0
    late: int = 0
    malformed: int = 0
    takeovers: int = 0
    retaken: int = 0          # the lease lapsed and this process took it again
    updates: int = 0
    last_written: float = 0.0
    lag_s: list[float] = field(default_factory=list)


def map_status(client: Any, keys: MapKeys, now: float | None = None) -> dict[str, Any]:
    """Everything ``map status`` prints, as plain data (times in seconds).

    Returns
    -------
    dict with ``scene`` ({sha256, name} or None), ``workers`` ({name: heartbeat + ``age_s``}),
    ``cameras`` ({camera: holder, lease_s, entries, last_capture, lag_s}), ``fusion`` (holder,
    lease_s, map entries, last bucket time, lag_s), ``people`` (list of {id, x, y, mode}).
    """
    now = time.time() if now is None else now
    scene = client.get(keys.scene)
    workers = {}
    for name, beat in client.hgetall(keys.workers).items():
        try:
            d = json.loads(beat)
        except json.JSONDecodeError:
            continue
        d["age_s"] = now - float(d.get("t", now))
        workers[name] = d
    cameras = {}
    for cam in sorted(client.hgetall(keys.cameras)):
        pipe = client.pipeline(transaction=False)
        pipe.get(keys.camera_lease(cam))
        pipe.pttl(keys.camera_lease(cam))
        pipe.xlen(keys.observations(cam))
        pipe.xrevrange(keys.observations(cam), count=1)
        holder, ttl, n, last = pipe.execute()
        last_t = float(last[0][1].get("t", time_of_id(last[0][0]))) if last else None
        cameras[cam] = {"holder": holder, "lease_s": max(0, ttl) / 1000 if holder else 0.0, "entries": n,
                        "last_capture": last_t, "lag_s": None if last_t is None else now - last_t}
    pipe = client.pipeline(transaction=False)
    pipe.get(keys.fusion_lease)
    pipe.pttl(keys.fusion_lease)
    pipe.xlen(keys.map_stream)
    pipe.hmget(keys.current, ["map_people", "t", "written", "holder"])
    holder, ttl, n_map, (people_json, t, written, last_holder) = pipe.execute()
    people = []
    if people_json:
        state = decode_map_state({"v": FORMAT_VERSION, "t": t, "people": people_json})
        people = [{"id": p.id, "x": p.x, "y": p.y, "mode": p.mode, "workers": p.workers} for p in state.people]
    fusion = {"holder": holder, "lease_s": max(0, ttl) / 1000 if holder else 0.0, "entries": n_map,
              "last_bucket": float(t) if t else None, "lag_s": now - float(t) if t else None,
              "last_holder": last_holder}
    return {"scene": json.loads(scene) if scene else None, "workers": workers, "cameras": cameras,
            "fusion": fusion, "people": people}


def _age(v: float | None) -> str:
    return "—" if v is None else f"{v:.2f} s"


def format_status(status: dict[str, Any], where: str) -> str:
    """The status as the lines ``map status`` prints."""
    lines = [f"map {where}"]
    sc = status["scene"]
    lines.append(f"  scene: {sc['name']} (sha256 {sc['sha256'][:12]}…)" if sc else "  scene: none yet")
    lines.append(f"  workers: {len(status['workers'])}")
    for name, w in sorted(status["workers"].items()):
        role = " + fusion" if w.get("fusion") else ""
        lines.append(f"    {name}: {w.get('state', '?')}{role}, cameras {','.join(w.get('cameras', [])) or '—'}, "
                     f"{w.get('frames', 0)} frames, {w.get('dropped', 0)} dropped, "
                     f"{w.get('reconnects', 0)} reconnects, heartbeat {_age(w['age_s'])} ago")
    lines.append(f"  cameras: {len(status['cameras'])}")
    for cam, c in status["cameras"].items():
        lease = f"held by {c['holder']} ({c['lease_s']:.2f} s left)" if c["holder"] else "free"
        lines.append(f"    {cam}: {lease}, {c['entries']} observations, lag {_age(c['lag_s'])}")
    f = status["fusion"]
    lease = f"held by {f['holder']} ({f['lease_s']:.2f} s left)" if f["holder"] else "free"
    lines.append(f"  fusion: {lease}, {f['entries']} map states, lag {_age(f['lag_s'])}")
    present = [p for p in status["people"] if p["mode"] == "tracking"]
    lines.append(f"  people: {len(present)} present, {len(status['people']) - len(present)} lost")
    for p in status["people"]:
        lines.append(f"    {p['id']}: ({p['x']:.2f}, {p['y']:.2f}) m, {p['mode']}, {p['workers']} workers")
    return "\n".join(lines)


__all__ = ["FusionStats", "format_status", "map_status"]
