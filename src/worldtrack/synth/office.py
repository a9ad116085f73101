"""Paper 002's world: an office with walls, desks and partitions seen by four cameras whose views
do not overlap (optionally with detours between them).

Registered as ``non-overlapping``.
"""

from __future__ import annotations

import numpy as np

from worldtrack.errors import InputError
from worldtrack.synth import scenes
from worldtrack.synth.environment import Environment
from worldtrack.synth.motion import Waypoint, graph_route, scripted_track
from worldtrack.synth.photometry import Light, light_direction
from worldtrack.synth.scenarios import Common, _register, _scene, _options, _lighting, _rigs, _shape
from worldtrack.synth.sequence import Person, Scenario


@_register("non-overlapping", "paper 002: an office with walls and desks seen by 4 cameras whose views do not overlap")
def non_overlapping(seed: int, common: Common, *, size=None, frames=None, people: int = 2, legs: int = 14,
                    speed: tuple = (1.0, 1.3), layout: str = "open") -> Scenario:
    """A 16 × 8 m office: a corridor along y = 4 m with desks and partitions on both sides and four
    ceiling cameras looking down on it, 4 m apart, with gaps between their views. People walk
    random routes along the corridor and stop at desks; between cameras nobody sees them.
    ``layout="detours"`` puts a screen across the corridor between every two cameras with one
    passage on alternate sides, so every walk from one view to the next is a detour.
    320×240 by default."""
    if not 1 <= int(people) <= 6:
        raise InputError(f"people: expected 1 to 6, got {people}")
    if layout not in ("open", "detours"):
        raise InputError(f"layout: expected 'open' or 'detours', got {layout!r}")
    rng = np.random.default_rng(seed)
    scene = _scene(scenes.scene_dict("office_4cams" if layout == "open" else "office_4cams_detours"), size or (320, 240))
    colours = {o.name: ((75, 105, 140) if o.name.startswith("desk") else (150, 140, 125)) for o in scene.obstacles}
    env = Environment(wall_height=3.0, floor_style="carpet", floor_colour=(120, 115, 105), wall_colour=(200, 205, 210),
                      obstacle_colours=colours, posters=8, seed=17)
    n = frames or 300
    nodes, edges, fixed = _office_graph(layout)
    persons = []
    for i in range(int(people)):
        shape = _shape(rng, env)
        lane = (i % 3 - 1) * 0.35
        route_idx = graph_route(nodes, edges, int(rng.integers(0, 15)), int(legs), rng)
        wps = []
        v = rng.uniform(*speed)
        for j in route_idx:
            x, y = nodes[j]
            dwell = float(rng.uniform(1.5, 4.0)) if fixed.get(j) == "desk" else 0.0
            wps.append(Waypoint(x, y + (lane if j not in fixed else 0.0), dwell=dwell, speed=v))
        wps[0] = Waypoint(wps[0].x, wps[0].y, dwell=float(rng.uniform(0.0, 4.0)))
        tr = scripted_track(wps, common.fps, n, shape.height)
        persons.append(Person(i + 1, shape, tr))
    light = Light(ambient=0.6, direct=0.45, direction=light_direction(70.0, 70.0))
    return Scenario("non-overlapping", scene, common.fps, n, persons, env, _lighting(common, rng, light),
                    _options(common), _rigs(scene, common), seed,
                    description="paper 002: four non-overlapping cameras in an office")


def _office_graph(layout: str = "open"):
    """Corridor nodes at y = 4 m every metre, desk stops beside each camera's desks; with detours
    the corridor nodes at the screens move into their passages. Returns nodes, edges and the nodes
    walked exactly (no lane offset): index → "desk" or "door"."""
    doors = dict(((int(x), (x, y)) for x, y in scenes.OFFICE_DOORS)) if layout == "detours" else {}
    corridor = [doors.get(x, (float(x), 4.0)) for x in range(1, 16)]
    nodes = list(corridor)
    edges = [(i, i + 1) for i in range(len(corridor) - 1)]
    fixed = {i: "door" for i, (x, _) in enumerate(corridor) if int(x) in doors}
    for xc in (2.0, 6.0, 10.0, 14.0):
        c = corridor.index((xc, 4.0))
        for y in (3.15, 4.85):
            nodes.append((xc + 0.3, y))
            fixed[len(nodes) - 1] = "desk"
            edges.append((c, len(nodes) - 1))
    return np.array(nodes), edges, fixed
