"""Foreground: what trackers read of a frame — which pixels are people, which are floor, which unsure.

* :mod:`~worldtrack.foreground.background` — the :class:`Foreground` protocol and its models: a
  fixed background image with a threshold (:class:`StaticBackground`, paper 000's), OpenCV's
  adaptive MOG2/KNN (:class:`AdaptiveBackground`);
* :mod:`~worldtrack.foreground.config` — :class:`ForegroundConfig` (``foreground.*`` settings);
* :mod:`~worldtrack.foreground.estimate` — an empty-scene image from frames with people in them;
* :mod:`~worldtrack.foreground.kernels`, :mod:`~worldtrack.foreground.texture` — the per-pixel
  colour and shadow test and the texture test of shadow-like pixels;
* :mod:`~worldtrack.foreground.evidence` — shadow or cloth from pooled texture evidence and the
  frame's shadow darkness (``foreground.shadow_test = "evidence"``);
* :mod:`~worldtrack.foreground.components` — connected components (blobs) of a mask.

:func:`make_foregrounds` builds one model per camera by name (``FOREGROUNDS``).

>>> import numpy as np
>>> from worldtrack.foreground import FOREGROUNDS
>>> model = FOREGROUNDS["colour"](np.full((4, 4, 3), 100, np.uint8), threshold=30.0, shadows=True,
...                               shadow_texture_ncc=None, shadow_test="colour")
>>> frame = np.full((4, 4, 3), 100, np.uint8); frame[1, 1] = (0, 0, 255)
>>> model.labels(frame)[1]
array([0, 1, 0, 0], dtype=uint8)
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from worldtrack.config import from_mapping
from worldtrack.errors import InputError
from worldtrack.foreground.background import AdaptiveBackground, Foreground, StaticBackground
from worldtrack.foreground.config import (DEFAULT_THRESHOLDS, FOREGROUND_KINDS, SYNTHETIC_COLOUR_THRESHOLD,
                                          ForegroundConfig)
from worldtrack.registry import Registry

#: Foreground models by name:
#: ``FOREGROUNDS[kind](background, threshold=, shadows=, shadow_texture_ncc=, shadow_test=)``.
FOREGROUNDS: Registry = Registry("--foreground")


@FOREGROUNDS.register("grey")
def _grey(background: np.ndarray, threshold: float | None, shadows: bool, shadow_texture_ncc: float | None,
         shadow_test: str = "colour"):
    return StaticBackground(background, threshold, "grey", shadows=shadows, shadow_texture_ncc=shadow_texture_ncc,
                            shadow_test=shadow_test)


@FOREGROUNDS.register("colour")
def _colour(background: np.ndarray, threshold: float | None, shadows: bool, shadow_texture_ncc: float | None,
           shadow_test: str = "colour"):
    return StaticBackground(background, threshold, "colour", shadows=shadows, shadow_texture_ncc=shadow_texture_ncc,
                            shadow_test=shadow_test)


@FOREGROUNDS.register("mog2")
def _mog2(background: np.ndarray, threshold: float | None, shadows: bool, shadow_texture_ncc: float | None,
         shadow_test: str = "colour"):
    return AdaptiveBackground("mog2", background=background, shadows=shadows)


@FOREGROUNDS.register("knn")
def _knn(background: np.ndarray, threshold: float | None, shadows: bool, shadow_texture_ncc: float | None,
        shadow_test: str = "colour"):
    return AdaptiveBackground("knn", background=background, shadows=shadows)


def make_foregrounds(scene, backgrounds: Mapping[str, np.ndarray], kind: str = "colour",
                     threshold: float | None = None, shadows: bool | None = None,
                     shadow_texture_ncc: float | None = None, shadow_test: str | None = None) -> dict[str, Foreground]:
    """One foreground model per camera from empty-scene images.

    Parameters
    ----------
    scene : Scene — the cameras the backgrounds are for
    backgrounds : {camera_id: (H, W, 3) uint8}
    kind : "grey" (the paper), "colour", "mog2" or "knn"
    threshold : grey levels / RGB distance for the static kinds; default :data:`DEFAULT_THRESHOLDS`
    shadows : treat cast shadows as unsure; default: on except for "grey" (the paper's)
    shadow_texture_ncc : for the static kinds with shadows, tell dark garments from shadows by
        texture (see :class:`StaticBackground`); default off
    shadow_test : for the static kinds with shadows, "colour" or "evidence" (see
        :class:`StaticBackground`); default "colour" (a tracker's own is
        :func:`worldtrack.trackers.method_shadow_test`)
    """
    given = {"kind": kind, "threshold": threshold, "shadows": shadows, "shadow_texture_ncc": shadow_texture_ncc}
    if shadow_test is not None:
        given["shadow_test"] = shadow_test
    cfg = from_mapping(ForegroundConfig, given, root="foreground")
    return foregrounds_from_config(scene, backgrounds, cfg)


def foregrounds_from_config(scene, backgrounds: Mapping[str, np.ndarray],
                            config: ForegroundConfig) -> dict[str, Foreground]:
    """:func:`make_foregrounds` from a :class:`ForegroundConfig`."""
    make = FOREGROUNDS[config.kind]
    out = {}
    for cid, bg in backgrounds.items():
        cam = scene.camera(cid)
        if (bg.shape[1], bg.shape[0]) != (cam.width, cam.height):
            raise InputError(f"background for {cid}: image is {bg.shape[1]}x{bg.shape[0]} but the camera is "
                             f"{cam.width}x{cam.height}")
        out[cid] = make(bg, config.resolved_threshold(), config.resolved_shadows(), config.shadow_texture_ncc,
                        config.resolved_shadow_test())
    return out


__all__ = ["DEFAULT_THRESHOLDS", "FOREGROUNDS", "FOREGROUND_KINDS", "AdaptiveBackground", "Foreground",
           "ForegroundConfig", "SYNTHETIC_COLOUR_THRESHOLD", "StaticBackground", "foregrounds_from_config",
           "make_foregrounds"]
