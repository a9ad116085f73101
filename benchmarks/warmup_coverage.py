"""Does the warm-up compile everything a real run calls? Kernels a tracking run uses after it.

For each case (method, synthetic scenario, image size) a fresh interpreter runs
``worldtrack.warmup.warm_up(method)``, notes every worldtrack kernel's compiled signatures, runs
``worldtrack demo`` on the scenario (25 frames), and lists the kernels that gained a signature in the
run: each would have been compiled (or loaded) inside the tracking clock. The synthetic renderer's
kernels are listed apart: the demo renders before its clock starts, and ``python -m worldtrack.warmup``
warms them under the name ``synth``.

    .venv/bin/python benchmarks/warmup_coverage.py            # 5 cases
    .venv/bin/python benchmarks/warmup_coverage.py --quick    # 1 case, prints only
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

from common import markdown_table, save_result  # noqa: E402

CASES = [("ellipsoid", "two-crossing", "640x480"), ("ellipsoid", "crowd", "320x240"),
         ("particle", "entry", "640x480"), ("particle", "crowd", "320x240"), ("blobs", "two-crossing", "320x240")]

_CHILD = r"""
import json, sys
from numba.core.registry import CPUDispatcher
from worldtrack.warmup import warm_up

def signatures():
    seen = {}
    for name, module in list(sys.modules.items()):
        if name.startswith("worldtrack") and module is not None:
            for v in vars(module).values():
                if isinstance(v, CPUDispatcher):
                    seen[v.py_func.__module__ + "." + v.py_func.__qualname__] = set(map(str, v.signatures))
    return seen

method, scenario, size, out = sys.argv[1:5]
seconds, compiled = warm_up(method)
before = signatures()
from worldtrack.cli import main
code = main(["demo", "--out", out, "--method", method, "--scenario", scenario, "--size", size, "--frames", "25",
             "--quiet"])
after = signatures()
new = sorted(k for k, v in after.items() if v - before.get(k, set()))
print(json.dumps({"code": code, "warm_up_s": seconds, "compiled": compiled, "new": new}))
"""


def run_case(method: str, scenario: str, size: str, folder: Path) -> dict:
    out = subprocess.run([sys.executable, "-c", _CHILD, method, scenario, size, str(folder / f"{method}-{scenario}")],
                         capture_output=True, text=True, timeout=1800)
    lines = out.stdout.strip().splitlines()
    if out.returncode or not lines:
        return {"code": out.returncode, "warm_up_s": float("nan"), "compiled": -1, "new": [out.stderr.strip()[-200:]]}
    return json.loads(lines[-1])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="one case; print only")
    args = ap.parse_args()
    t0 = time.perf_counter()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for method, scenario, size in CASES[2:3] if args.quick else CASES:
            r = run_case(method, scenario, size, Path(tmp))
            tracker = [k for k in r["new"] if not k.startswith("worldtrack.synth.")]
            renderer = [k for k in r["new"] if k.startswith("worldtrack.synth.")]
            rows.append([method, scenario, size, r["code"], f"{r['warm_up_s']:.1f}", r["compiled"],
                         ", ".join(tracker) or "none", len(renderer)])
            print(rows[-1], file=sys.stderr)
    text = (markdown_table(["method", "scenario", "size", "exit", "warm-up (s)", "compiled in warm-up",
                            "tracking kernels first called after the warm-up", "renderer kernels (before the clock)"],
                           rows) + "\n")
    print(text)
    save_result("warmup_coverage", "Kernels a tracking run calls after the warm-up", text, args.quick,
                time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    sys.exit(main())
