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
from typing import Any, Mapping, Sequence

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


#: Files a run writes into its output folder (patterns): what ``--overwrite`` replaces.
RUN_OUTPUTS = ("run.yaml", "tracks.csv", "floorplan.png", "*_annotated.mp4")


def prepare_output(out_dir: Path, overwrite: bool, extra: Sequence[str | Path] = ()) -> list[Path]:
    """Make sure ``out_dir`` may take a new run's outputs; returns the files removed.

    A folder holding a previous run's outputs (:data:`RUN_OUTPUTS`) is refused with an
    :class:`InputError` unless ``overwrite``, which removes those files (and ``extra`` ones, e.g.
    the ``--mot`` file), so no stale video or plan is left beside the new tracks. Other files in
    the folder (the user's own) are never touched.
    """
    if out_dir.exists() and not out_dir.is_dir():
        raise InputError(f"--out {out_dir}: is a file, expected a folder")
    old = sorted({p for pattern in RUN_OUTPUTS for p in out_dir.glob(pattern)}) if out_dir.is_dir() else []
    old += [Path(e) for e in extra if Path(e).is_file()]
    if old and not overwrite:
        names = ", ".join(p.name for p in old[:4]) + (", …" if len(old) > 4 else "")
        raise InputError(f"--out {out_dir}: holds the outputs of a previous run ({names}); give a new "
                         "folder, or --overwrite to replace them")
    for p in old:
        try:
            p.unlink()
        except OSError as e:
            raise InputError(f"{p}: cannot remove ({e.strerror})") from None
    return old


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


__all__ = ["RUN_OUTPUTS", "file_digest", "prepare_output", "source_commit", "write_run_info"]
