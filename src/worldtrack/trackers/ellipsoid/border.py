"""Is a person at the image's edge cut by it? Told by the search box, or by the silhouette itself.

Heights and the feet are read only from a person whole in view. The search region round a person is
the tallest plausible person's ellipse with its ring (1.25 times as wide), so near the image's side
its box reaches past the edge while the person, a narrower and shorter silhouette, is whole in view:
on the line-of-sight scenario a 1.86 m person standing 35-60 px from the left edge (seed 25, issue 37)
had no feet read for 60 frames and drifted 0.5-1.1 m along the line of sight. ``border="silhouette"``
asks the foreground instead: cut only when the person's own pixels reach the edge.
"""

from __future__ import annotations

import numpy as np

from worldtrack.geometry.camera import Camera


def cut_by_border(camera: Camera, labels: np.ndarray, region: np.ndarray, box: tuple[int, int, int, int],
                  bottom: bool = True, border: str = "box") -> bool:
    """Whether the person in ``region`` of ``box`` may extend past the image's left, right or top edge
    (with ``bottom``, also its bottom edge).

    ``border="box"``: the search box meets that edge (the box is the tallest plausible person's ellipse
    with its ring, so a person whole in view near the edge is cut too); ``"silhouette"``: their
    foreground (label 1) in the region reaches that edge.

    >>> import numpy as np
    >>> from worldtrack.geometry.camera import Camera
    >>> cam = Camera.look_at("c", 64, 48, [0.0, 0, 3], [0.0, 5, 0], hfov_deg=60.0)
    >>> labels = np.zeros((48, 64), np.uint8); labels[10:30, 3:8] = 1       # a silhouette 3 px from the edge
    >>> region, box = np.ones((40, 12), bool), (0, 12, 5, 45)
    >>> cut_by_border(cam, labels, region, box), cut_by_border(cam, labels, region, box, border="silhouette")
    (True, False)
    >>> labels[10:30, 0:8] = 1                                               # now it reaches the edge
    >>> cut_by_border(cam, labels, region, box, border="silhouette")
    True
    """
    u0, u1, v0, v1 = (int(b) for b in box)
    if u0 > 0 and v0 > 0 and u1 < camera.width and (v1 < camera.height or not bottom):
        return False
    if border == "box":
        return True
    fg = (labels[v0:v1, u0:u1] == 1) & region
    return bool((u0 <= 0 and fg[:, 0].any()) or (u1 >= camera.width and fg[:, -1].any())
                or (v0 <= 0 and fg[0].any()) or (bottom and v1 >= camera.height and fg[-1].any()))


__all__ = ["cut_by_border"]
