"""Running one generated input through the command line and judging what came out.

A case is a file's bytes, the command that reads it, and what the input is: ``valid`` (must be
accepted, exit 0), ``invalid`` (must be refused: one ``error:`` line, exit 2) or ``either`` (a
random edit that may or may not break it). Whatever the kind, the run must end without a
traceback, within :data:`MAX_SECONDS` of CPU time and :data:`MAX_MB` of new memory (the growth of the
peak resident size, reset before each case through ``/proc/self/clear_refs``: Linux only). CPU time,
not wall time, because the machines this runs on are shared: at a load of 20 on 2 cores an input
of 0.2 CPU s takes 2 s of wall time; the wall time is recorded beside it. A case still running
after :data:`HANG_SECONDS` of CPU time (or :data:`HANG_WALL_SECONDS` of wall time) is a hang. A valid case may also
carry a ``check`` of what was read (the value a YAML 1.1 reader would have got wrong).

Used by ``tests/fuzz/test_fuzz.py`` (seeded, small) and ``benchmarks/fuzz.py`` (the same
generators, more examples, counts per class).
"""

from __future__ import annotations

import contextlib
import io
import signal
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

MAX_SECONDS = 2.0
MAX_MB = 500.0
HANG_SECONDS = 20
HANG_WALL_SECONDS = 600
LONGEST_ERROR = 1000      # characters of the error line: excerpts, not the input


@dataclass
class Case:
    """One generated input."""

    family: str                        # "scene", "tracks", "calibration"
    mutation: str                      # what was done to a valid file
    kind: str                          # "valid", "invalid" or "either"
    data: bytes
    argv: Callable[[Path], list[str]]  # the command, given the file's path
    check: Callable[[Path, "Outcome"], str | None] | None = None   # valid cases: None or what is wrong
    suffix: str = ".yaml"


@dataclass
class Outcome:
    case: Case
    code: int | None = None
    stdout: str = ""
    stderr: str = ""
    seconds: float = 0.0               # CPU time (user + system) of this process during the case
    wall_seconds: float = 0.0
    peak_mb: float = 0.0
    problems: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.problems

    def describe(self) -> str:
        last = self.stderr.strip().splitlines()[-1:] or [""]
        return (f"{self.case.family}/{self.case.mutation} ({self.case.kind}): {', '.join(self.problems)}; "
                f"exit {self.code}, {self.seconds:.2f} CPU s ({self.wall_seconds:.2f} s wall), {self.peak_mb:.0f} MB; "
                f"stderr: {last[0][:300]!r}")


def _memory_kb(field: str) -> int:
    """``VmRSS`` or ``VmHWM`` (peak) of this process, kB (Linux)."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    raise OSError(f"no {field} in /proc/self/status")


def _reset_peak() -> None:
    """Make the peak resident size (VmHWM) restart from the current one (Linux ≥ 4.0)."""
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")


class _Hang(BaseException):
    pass


def _alarm(signum, frame):
    raise _Hang()


def run_case(case: Case, folder: Path) -> Outcome:
    """Write the case's file into ``folder``, run its command in this process, judge the result."""
    from worldtrack.cli import main

    path = folder / f"input{case.suffix}"
    path.write_bytes(case.data)
    out = Outcome(case)
    stdout, stderr = io.StringIO(), io.StringIO()
    previous = signal.signal(signal.SIGPROF, _alarm), signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_PROF, HANG_SECONDS)
    signal.alarm(HANG_WALL_SECONDS)
    _reset_peak()
    rss0 = _memory_kb("VmRSS")
    t0, cpu0 = time.perf_counter(), time.process_time()
    try:
        with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
            out.code = main(case.argv(path))
    except _Hang:
        out.problems.append("hang")
    except BaseException as e:  # noqa: BLE001 - a traceback is what is being counted
        out.problems.append(f"traceback ({type(e).__name__}: {str(e)[:200]})")
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0)
        signal.alarm(0)
        signal.signal(signal.SIGPROF, previous[0])
        signal.signal(signal.SIGALRM, previous[1])
        out.seconds, out.wall_seconds = time.process_time() - cpu0, time.perf_counter() - t0
        out.peak_mb = (_memory_kb("VmHWM") - rss0) / 1024
    out.stdout, out.stderr = stdout.getvalue(), stderr.getvalue()
    _judge(out, path)
    return out


def _judge(out: Outcome, path: Path) -> None:
    if out.problems:
        return
    if out.seconds > MAX_SECONDS:
        out.problems.append(f"slow ({out.seconds:.1f} CPU s)")
    if out.peak_mb > MAX_MB:
        out.problems.append(f"memory ({out.peak_mb:.0f} MB)")
    if "Traceback" in out.stderr:
        out.problems.append("traceback printed")
    if out.code == 2:
        errors = [ln for ln in out.stderr.splitlines() if ln.startswith("error:")]
        if len(errors) != 1 or not out.stderr.rstrip().splitlines()[-1].startswith("error:"):
            out.problems.append(f"error lines: {len(errors)}, not one at the end")
        elif len(errors[0]) > LONGEST_ERROR:
            out.problems.append(f"error lines: one of {len(errors[0])} characters")
        if out.case.kind == "valid":
            out.problems.append("valid input refused")
    elif out.code == 0:
        if out.case.kind == "invalid":
            out.problems.append("wrongly accepted")
        elif out.case.kind == "valid" and out.case.check is not None:
            wrong = out.case.check(path, out)
            if wrong:
                out.problems.append(f"accepted but read wrong ({wrong})")
    else:
        out.problems.append(f"exit status {out.code}")


def count(outcomes: list[Outcome]) -> dict[str, int]:
    """Outcomes by class: inputs, accepted, refused, tracebacks, hangs, slow, memory, wrongly accepted, …"""
    def has(o: Outcome, word: str) -> bool:
        return any(p.startswith(word) for p in o.problems)

    return {"inputs": len(outcomes), "exit 0": sum(o.code == 0 for o in outcomes),
            "exit 2": sum(o.code == 2 for o in outcomes),
            "tracebacks": sum(has(o, "traceback") for o in outcomes), "hangs": sum(has(o, "hang") for o in outcomes),
            "over 2 s": sum(has(o, "slow") for o in outcomes),
            "over 2 s wall": sum(o.wall_seconds > MAX_SECONDS for o in outcomes), "over 500 MB": sum(has(o, "memory") for o in outcomes),
            "wrongly accepted": sum(has(o, "wrongly accepted") for o in outcomes),
            "accepted but read wrong": sum(has(o, "accepted but") for o in outcomes),
            "valid refused": sum(has(o, "valid input refused") for o in outcomes),
            "bad error line": sum(has(o, "error lines") for o in outcomes),
            "other exit status": sum(has(o, "exit status") for o in outcomes)}
