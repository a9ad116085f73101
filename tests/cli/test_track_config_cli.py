"""``worldtrack track``'s settings: --print-config, --config files, --set, and run.yaml."""

import pytest
import yaml

from worldtrack.cli import main
from worldtrack.runconfig import dump_run_config, resolve_run_config
from worldtrack.synth import make_scenario, write_sequence


def test_print_config_prints_every_setting_and_round_trips(tmp_path, capsys):
    assert main(["track", "--print-config"]) == 0
    text = capsys.readouterr().out
    data = yaml.safe_load(text)
    assert data["method"] == "ellipsoid" and data["preset"] == "default"
    assert set(data) == {"method", "preset", "foreground", "ellipsoid", "particle", "blobs", "map"}
    assert "# " in text                                        # each field carries its description
    (tmp_path / "all.yaml").write_text(text)
    assert main(["track", "--config", str(tmp_path / "all.yaml"), "--print-config"]) == 0
    assert capsys.readouterr().out == text                     # the file gives the same settings back
    assert resolve_run_config(data).to_mapping() == resolve_run_config().to_mapping()


def test_config_file_flags_and_set_in_that_order(tmp_path, capsys):
    (tmp_path / "c.yaml").write_text("method: blobs\nforeground: {threshold: 22}\nblobs: {filter: {gate: 4.0}}\n")
    assert main(["track", "--config", str(tmp_path / "c.yaml"), "--threshold", "24",
                 "--set", "blobs.filter.gate=5", "--print-config"]) == 0
    data = yaml.safe_load(capsys.readouterr().out)
    assert data["method"] == "blobs" and data["foreground"]["threshold"] == 24.0
    assert data["blobs"]["filter"]["gate"] == 5.0
    cfg = resolve_run_config({"preset": "paper"})
    assert cfg.preset == "paper" and cfg.section("ellipsoid") == resolve_run_config(preset="paper").section("ellipsoid")


def test_the_particle_tracker_keeps_its_own_threshold_unless_one_is_given():
    assert resolve_run_config(method="ellipsoid").foreground.threshold is None          # the kind's: 30 colour
    assert resolve_run_config(method="particle").foreground.threshold == 25.0            # its γ
    assert resolve_run_config(method="particle", flags={"threshold": 12}).foreground.threshold == 12
    assert resolve_run_config({"method": "particle", "foreground": {"threshold": 9}}).foreground.threshold == 9
    assert resolve_run_config(method="particle", sets=[("foreground.threshold", 40)]).foreground.threshold == 40
    assert resolve_run_config(method="particle", flags={"foreground": "mog2"}).foreground.threshold is None


@pytest.mark.parametrize("args, message", [
    (["--set", "blobs.filter.gat=4"], "error: blobs.filter.gat: unknown setting (expected one of: process_noise, "
                                      "measurement_noise_m, initial_speed_sigma, gate)"),
    (["--set", "blobs.filter.gate=-1"], "error: blobs.filter.gate: expected a number > 0, got -1"),
    (["--set", "blobs.filter.gate=fast"], "error: blobs.filter.gate: expected a number, got 'fast'"),
    (["--set", "foreground.threshold=0"], "error: foreground.threshold: expected a number > 0, got 0"),
    (["--set", "method=kalman"], "error: method: expected one of ellipsoid, particle, blobs, got 'kalman'"),
    (["--set", "tracker.x=1"], "error: tracker: unknown setting (expected one of: method, preset, foreground, "),
    (["--set", "blobs.filter.gate"], "error: --set 'blobs.filter.gate': expected NAME=VALUE"),
    (["--set", "blobs=3"], "error: blobs: is a section"),
])
def test_a_wrong_setting_is_one_line_exit_2(args, message, capsys):
    assert main(["track", *args, "--print-config"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(message), err


def test_a_bad_config_file_names_itself(tmp_path, capsys):
    (tmp_path / "c.yaml").write_text("blobs: {filter: {gate: -2}}\n")
    assert main(["track", "--config", str(tmp_path / "c.yaml"), "--print-config"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"error: {tmp_path / 'c.yaml'}: blobs.filter.gate: expected a number > 0, got -2"


def test_every_run_writes_run_yaml(tmp_path, capsys):
    seq = tmp_path / "seq"
    write_sequence(make_scenario("two-crossing", size=(160, 120), frames=4, seed=1), seq, png=True, progress=False)
    out = tmp_path / "out"
    assert main(["track", str(seq / "scene.yaml"), "--video", f"cam1={seq / 'cam1'}", "--out", str(out),
                 "--quiet", "--no-video", "--method", "blobs", "--set", "blobs.filter.gate=4"]) == 0
    info = yaml.safe_load((out / "run.yaml").read_text())
    assert info["worldtrack"] and "commit" in info and info["command"].startswith("worldtrack track ")
    assert info["inputs"]["scene"] == str(seq / "scene.yaml") and len(info["inputs"]["scene_sha256"]) == 64
    assert info["inputs"]["videos"] == {"cam1": str(seq / "cam1")}
    assert info["config"]["method"] == "blobs" and info["config"]["blobs"]["filter"]["gate"] == 4.0
    # The recorded settings run again as they are.
    (tmp_path / "again.yaml").write_text(yaml.safe_dump(info["config"]))
    assert main(["track", "--config", str(tmp_path / "again.yaml"), "--print-config"]) == 0
    assert yaml.safe_load(capsys.readouterr().out)["blobs"]["filter"]["gate"] == 4.0


def test_dump_is_valid_yaml_with_comments():
    text = dump_run_config(resolve_run_config())
    assert yaml.safe_load(text)["foreground"]["kind"] == "colour"
