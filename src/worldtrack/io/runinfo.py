"""``run.yaml``: what a run was — the version, the commit if known, the command line, the inputs
and the resolved settings — written into its output folder before the first frame.

Reading the ``config`` part back (``worldtrack track --config run.yaml``) repeats the run's settings.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import shlex
import subprocess
import sys
from pathlib import Path
from typing import Any, Mapping

import yaml

from worldtrack.errors import InputError


def source_commit() -> str | None:
    """The git commit of the worldtrack source in use (with ``-dirty`` if changed), or None when it is
    not a git checkout (an installed package) or git is not there."""
    here = Path(__file__).resolve().parent
    try:
        out = subprocess.run(["git", "-C", str(here), "describe", "--always", "--dirty", "--abbrev=12"],
                             capture_output=True, text=True, timeout=5)
    except (OSError, subprocess.SubprocessError):
        return None
    text = out.stdout.strip()
    return text if out.returncode == 0 and text else None


def file_digest(path: str | Path) -> str | None:
    """SHA-256 of a file's bytes (hex), or None if it cannot be read."""
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except OSError:
        return None


def write_run_info(out_dir: Path, config: Mapping[str, Any], inputs: Mapping[str, Any],
                   argv: list[str] | None = None) -> Path:
    """Write ``out_dir/run.yaml`` and return its path.

    Parameters
    ----------
    out_dir : the run's output folder (created if missing)
    config : the resolved settings as plain values (``RunConfig.to_mapping()``)
    inputs : what the run reads: ``scene`` (a path: its SHA-256 is recorded too), videos, backgrounds, …
    argv : the command line, program name first (default ``sys.argv``)
    """
    from worldtrack import __version__

    out_dir.mkdir(parents=True, exist_ok=True)
    info_inputs = dict(inputs)
    scene = info_inputs.get("scene")
    if scene is not None:
        info_inputs["scene_sha256"] = file_digest(scene)
    argv = list(sys.argv if argv is None else argv)
    info = {"worldtrack": __version__, "commit": source_commit(),
            "started": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
            "command": shlex.join(["worldtrack", *argv[1:]]) if argv else None,
            "inputs": _plain(info_inputs), "config": _plain(dict(config))}
    path = out_dir / "run.yaml"
    try:
        path.write_text(yaml.safe_dump(info, sort_keys=False, allow_unicode=True), encoding="utf-8")
    except OSError as e:
        raise InputError(f"{path}: cannot write ({e.strerror})") from None
    return path


def _plain(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, Path):
        return str(value)
    return value


__all__ = ["file_digest", "source_commit", "write_run_info"]
