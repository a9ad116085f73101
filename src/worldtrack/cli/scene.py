"""``worldtrack scene check SCENE.yaml [--plot plan.png]``: validate a scene and summarise it."""

from __future__ import annotations

import argparse
import sys


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("scene", help="check a scene file and draw its floor plan",
                       description="Scene file tools.")
    verbs = p.add_subparsers(dest="scene_command", metavar="<scene command>", required=True)
    c = verbs.add_parser("check", help="validate a scene file, print a summary, optionally draw a plan",
                         description="Validate a scene file: report every problem with its field path, "
                                     "or print cameras, floor area, obstacles and entry regions.")
    c.add_argument("scene", help="scene YAML file")
    c.add_argument("--plot", metavar="PNG", help="write a floor plan: walls, obstacles, entry regions, "
                                                 "cameras and the floor area each camera sees")
    c.set_defaults(func=run_check)


def run_check(args: argparse.Namespace) -> int:
    import numpy as np

    from worldtrack.scene import load_scene
    from worldtrack.scene.model import Box

    scene = load_scene(args.scene)
    for line in scene.warnings:
        print(f"warning: {line}", file=sys.stderr)
    print(f"scene {scene.name!r} ({args.scene}): valid")
    print(f"cameras: {len(scene.cameras)}")
    bounds = scene.walkable.bounds
    for cam in scene.cameras.values():
        c = cam.centre
        seen = _seen_floor_area(scene, cam)
        dist = " distortion " + ",".join(f"{v:g}" for v in cam.dist) if cam.has_distortion else ""
        print(f"  {cam.id:<10} {cam.width}x{cam.height}  position ({c[0]:.2f}, {c[1]:.2f}) m, "
              f"height {c[2]:.2f} m, looking {np.degrees(np.arctan2(*cam.floor_direction[::-1])):.0f}° "
              f"from +X, sees {seen:.1f} m² of floor{dist}")
    print(f"floor: {len(scene.walkable.polygons)} polygon(s), {scene.walkable.area:.1f} m², "
          f"X {bounds[0]:.2f}…{bounds[1]:.2f} m, Y {bounds[2]:.2f}…{bounds[3]:.2f} m")
    print(f"obstacles: {len(scene.obstacles)}")
    for ob in scene.obstacles:
        kind = "box" if isinstance(ob, Box) else "patch"
        c = ob.footprint.mean(axis=0)
        print(f"  {ob.name:<14} {kind:<5} at ({c[0]:.2f}, {c[1]:.2f}) m, top {ob.top:.2f} m"
              f"{'' if ob.blocks_walking else ', walkable under'}")
    print(f"entry regions: {len(scene.entry_regions)}" +
          "".join(f"\n  {r.name}" for r in scene.entry_regions))
    p = scene.people
    print(f"people: height {p.height:.2f} m, width {p.width:.2f} m" +
          (f", {len(p.overrides)} override(s)" if p.overrides else ""))
    if args.plot:
        from worldtrack.viz.floorplan import save_floorplan
        out = save_floorplan(scene, args.plot)
        print(f"floor plan: {out}")
    return 0


def _seen_floor_area(scene, cam, resolution: float = 0.05) -> float:
    """Area (m²) of walkable floor whose Z = 0 point falls inside the camera's image."""
    import numpy as np

    from worldtrack.scene.floor import grid_resolution

    x0, x1, y0, y1 = scene.walkable.bounds
    resolution = grid_resolution(scene.walkable.bounds, resolution, max_cells=1_000_000)
    xs = np.arange(x0, x1, resolution) + resolution / 2
    ys = np.arange(y0, y1, resolution) + resolution / 2
    gx, gy = np.meshgrid(xs, ys)
    xy = np.column_stack([gx.ravel(), gy.ravel()])
    pts = np.column_stack([xy, np.zeros(len(xy))])
    seen = cam.in_image(cam.project(pts)) & scene.walkable.on_floor(xy)
    return float(seen.sum()) * resolution ** 2
