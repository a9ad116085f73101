"""Run a benchmark as if the ellipsoid tracker's defaults were different: is a candidate default harmless?

An opt-in that helps one scene becomes a default only when the other benchmarks lose nothing with
it. Several benchmarks take ``--set`` for the ellipsoid's settings, but not all (``paper_kato.py``,
``peer_pom.py``), and the foreground's shadow test is a per-method default
(:func:`worldtrack.trackers.method_shadow_test`) that only some take as an option. This script
changes both where every benchmark gets them — the ellipsoid's ``default`` preset in
:func:`worldtrack.trackers.method_config` and the method's own shadow test — and then runs the
benchmark unchanged in this process. The ``paper`` preset and the other methods are untouched.
Results are only printed: no ``results/*.md`` is written.

Usage::

    .venv/bin/python benchmarks/with_defaults.py --shadow-test evidence --set feet.anchor=true \\
        -- benchmarks/paper_kato.py
    .venv/bin/python benchmarks/with_defaults.py --set depth.fuse=true -- benchmarks/real_data.py --methods ellipsoid
"""

from __future__ import annotations

import argparse
import runpy
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import common  # noqa: E402
from common import setting_value  # noqa: E402

import worldtrack.trackers as trackers  # noqa: E402
from worldtrack.trackers.ellipsoid.config import EllipsoidConfig  # noqa: E402
from worldtrack.foreground.background import SHADOW_TESTS  # noqa: E402


def changed_defaults(overrides: dict, shadow_test: str | None) -> None:
    """Make ``overrides`` ({dotted path: value}) part of the ellipsoid's default preset, and
    ``shadow_test`` (when given) its own foreground shadow test, for the rest of this process."""
    if shadow_test is not None:
        EllipsoidConfig.foreground_shadow_test = shadow_test
    original = trackers.method_config

    def method_config(method: str, preset: str = "default", extra=None):
        if method == "ellipsoid" and preset == "default" and overrides:
            extra = {**overrides, **dict(extra or {})}
        return original(method, preset, extra)

    trackers.method_config = method_config


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if "--" not in argv:
        print("error: expected the benchmark after --, e.g. -- benchmarks/paper_kato.py", file=sys.stderr)
        return 2
    cut = argv.index("--")
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="an ellipsoid default by dotted path (e.g. feet.anchor=true)")
    p.add_argument("--shadow-test", choices=SHADOW_TESTS, default=None,
                   help="the ellipsoid's own foreground shadow test")
    args = p.parse_args(argv[:cut])
    bench = argv[cut + 1:]
    if not bench or not Path(bench[0]).is_file():
        print(f"error: no benchmark script {bench[0] if bench else ''!r}", file=sys.stderr)
        return 2
    overrides = {k: setting_value(v) for k, v in (s.split("=", 1) for s in args.set)}
    changed_defaults(overrides, args.shadow_test)
    common.save_result = lambda name, *_: print(f"with_defaults: results/{name}.md not written", file=sys.stderr)
    print(f"with_defaults: ellipsoid defaults {overrides}, shadow test "
          f"{args.shadow_test or 'unchanged'}", file=sys.stderr)
    sys.argv = bench
    sys.path.insert(0, str(Path(bench[0]).resolve().parent))
    runpy.run_path(bench[0], run_name="__main__")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
