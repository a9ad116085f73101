"""The particle tracker's own foreground defaults: the evidence shadow test (floor-coloured cloth is
foreground) unless the user says otherwise, shown where the settings are shown; the other methods
and the paper preset keep the colour test."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from worldtrack import experiment
from worldtrack.cli import main
from worldtrack.foreground import foregrounds_from_config
from worldtrack.runconfig import resolve_run_config
from worldtrack.trackers import method_shadow_test

from particle_scenes import W, H, make_scene


def floor_and_cloth(seed=0):
    """A grey tiled floor (320 × 240) and a frame with, at rows 60–120 / columns 40–120, a cast shadow
    (the tiles at 0.6 of their brightness) and, at rows 60–160 / columns 180–260, shaded cloth of the
    floor's own grey with a weave of its own (neither is foreground to the colour test)."""
    rng = np.random.default_rng(seed)
    tile = 8
    tiles = 1 + rng.uniform(-0.1, 0.1, (H // tile + 1, W // tile + 1))
    f = np.kron(tiles, np.ones((tile, tile)))[:H, :W] * (1 + rng.normal(0, 0.04, (H, W)))
    f[::tile, :] *= 0.7
    f[:, ::tile] *= 0.7
    grey = np.array([0.97, 1.0, 1.03]) * 130.0
    bg = np.clip(f[..., None] * grey, 0, 255).astype(np.uint8)
    img = bg.astype(float)
    img[60:120, 40:120] *= 0.6
    img[60:160, 180:260] = grey * 0.6 * (1 + 0.03 * np.sin(np.arange(100) * 2.1))[:, None, None]
    img = np.clip(img + rng.normal(0, 2.0, img.shape), 0, 255).astype(np.uint8)
    return bg, img


@pytest.mark.parametrize("method, preset, expected", [
    ("particle", "default", "evidence"), ("particle", "paper", "colour"),
    ("ellipsoid", "default", "colour"), ("ellipsoid", "paper", "colour"), ("blobs", "default", "colour")])
def test_each_method_gets_its_own_shadow_test_when_none_is_given(method, preset, expected):
    assert resolve_run_config(method=method, preset=preset).foreground.shadow_test == expected
    assert (method_shadow_test(method, preset) or "colour") == expected


def test_a_given_shadow_test_wins_over_the_methods_own(tmp_path):
    assert resolve_run_config(method="particle", sets=[("foreground.shadow_test", "colour")]).foreground.shadow_test \
        == "colour"
    assert resolve_run_config({"method": "particle", "foreground": {"shadow_test": "colour"}}).foreground.shadow_test \
        == "colour"
    assert resolve_run_config(method="ellipsoid", sets=[("foreground.shadow_test", "evidence")]) \
        .foreground.shadow_test == "evidence"
    (tmp_path / "c.yaml").write_text("foreground: {shadow_test: colour}\n")
    assert main(["track", "--method", "particle", "--config", str(tmp_path / "c.yaml"), "--print-config"]) == 0


def test_the_printed_settings_say_which_shadow_test_runs(capsys):
    assert main(["track", "--method", "particle", "--print-config"]) == 0
    assert yaml.safe_load(capsys.readouterr().out)["foreground"]["shadow_test"] == "evidence"
    assert main(["track", "--print-config"]) == 0
    assert yaml.safe_load(capsys.readouterr().out)["foreground"]["shadow_test"] == "colour"
    assert main(["track", "--method", "particle", "--set", "foreground.shadow_test=colour", "--print-config"]) == 0
    assert yaml.safe_load(capsys.readouterr().out)["foreground"]["shadow_test"] == "colour"


def test_the_particle_trackers_foreground_calls_floor_coloured_cloth_foreground_and_the_ellipsoids_does_not():
    bg, img = floor_and_cloth()
    scene = make_scene()
    labels = {}
    for method in ("particle", "ellipsoid"):
        fg = foregrounds_from_config(scene, {"cam": bg}, resolve_run_config(method=method).foreground)["cam"]
        labels[method] = fg.labels(img)
    cloth, shadow = (slice(60, 160), slice(180, 260)), (slice(60, 120), slice(40, 120))
    # Some 15 % of the cloth is within the threshold of the floor (0); the rest is shadow-like.
    assert np.mean(labels["particle"][cloth] == 1) > 0.8           # the floor's pattern is gone: cloth
    assert np.mean(labels["particle"][cloth] == 2) < 0.01
    assert np.mean(labels["ellipsoid"][cloth] == 1) < 0.05         # the colour test: unsure (2)
    assert np.mean(labels["particle"][shadow] == 1) < 0.02         # the pattern shows through: shadow
    assert np.mean(labels["particle"][shadow] == 2) > 0.95


class _Scenario:
    """Just what :func:`worldtrack.experiment.synthetic_tracker` reads of a scenario."""

    def __init__(self, scene, background):
        self.scene, self.camera_ids, self._bg = scene, ["cam"], background

    def background(self, cid):
        return self._bg


@pytest.mark.parametrize("method, preset, given, expected", [
    ("particle", "default", None, "evidence"), ("particle", "paper", None, "colour"),
    ("ellipsoid", "default", None, "colour"), ("particle", "default", "colour", "colour"),
    ("ellipsoid", "default", "evidence", "evidence")])
def test_experiments_build_the_methods_own_foreground(monkeypatch, method, preset, given, expected):
    built = {}
    monkeypatch.setattr(experiment, "make_tracker", lambda m, scene, fgs, **kw: built.update(fgs) or "tracker")
    bg, _ = floor_and_cloth()
    assert experiment.synthetic_tracker(_Scenario(make_scene(), bg), method, preset, shadow_test=given) == "tracker"
    assert built["cam"].shadow_test == expected
