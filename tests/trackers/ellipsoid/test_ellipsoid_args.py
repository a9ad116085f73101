"""The kernels' typed arguments, and the package's size limits (modules, functions, parameters)."""

import ast
import inspect
from pathlib import Path

import numba
import numpy as np
from _ellipsoid_scenes import lab_scene

import worldtrack.trackers.ellipsoid as package
from worldtrack.trackers.ellipsoid.args import NO_GRID, Forms, camera_args

PACKAGE = Path(package.__file__).parent


def test_cameras_with_and_without_distortion_have_one_kernel_type():
    # The compiled rounds index a tuple of cameras at run time: it must be a tuple of one type.
    lab = lab_scene()
    plain = camera_args(lab.cameras["cam1"], 5.0, lab.occlusion("cam1").floor_distance)
    barrel = camera_args(lab.cameras["cam2"], 5.0)
    assert not plain.has_dist and barrel.has_dist and plain.grid.shape == NO_GRID.shape
    assert numba.typeof(plain) == numba.typeof(barrel)
    assert isinstance(numba.typeof((plain, barrel)), numba.types.UniTuple)
    for args in (plain, barrel):
        arrays = [v for v in args if isinstance(v, np.ndarray)]
        assert all(a.flags.c_contiguous and a.flags.writeable for a in arrays)
        assert args.grid.dtype == np.float32 and args.occ.dtype == np.float32 and args.P.dtype == np.float64
    np.testing.assert_array_equal(plain.occ, lab.occlusion("cam1").floor_distance)
    assert np.isinf(barrel.occ).all()
    empty = Forms.empty(2)
    assert empty.box.dtype == np.int64 and not empty.valid.any() and empty.dist.shape == (2,)


def _functions():
    for path in sorted(PACKAGE.glob("*.py")):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                yield path, node


def test_modules_functions_and_kernels_stay_small():
    # Issue 33: modules ≤ 400 lines, functions ≤ 100 (a compiled kernel may be longer, with a
    # comment saying why), no function with more than 12 parameters.
    for path in PACKAGE.glob("*.py"):
        assert len(path.read_text().splitlines()) <= 400, path.name
    for path, fn in _functions():
        a = fn.args
        n = len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs) + (a.vararg is not None) + (a.kwarg is not None)
        assert n <= 12, f"{path.name}: {fn.name} takes {n} parameters"
        length = fn.end_lineno - fn.lineno + 1
        compiled = any("njit" in ast.unparse(d) for d in fn.decorator_list)
        if length > 100:
            doc = ast.get_docstring(fn) or ""
            assert compiled and "Compiled" in doc, f"{path.name}: {fn.name} is {length} lines"


def test_no_kernel_writes_the_lens_polynomial_itself():
    # One lens kernel: geometry/_kernels. The radial factor 1 + r²(k1 + r²(k2 + r²·k3)) appears
    # nowhere in this package.
    for path in PACKAGE.glob("*.py"):
        text = path.read_text().replace(" ", "")
        assert "r2*(k1+r2*(k2" not in text and "_distort_ideal_pixel" not in text, path.name


def test_every_compiled_kernel_has_a_reference_or_a_test_of_its_caller():
    # Each public compiled kernel has a plain version beside it, or is checked through one.
    # (adapt_step, the adaptive step rule, is shared by both rounds: scalar logic, not a second copy.)
    checked_through = {"ellipse_forms": "score_candidates_reference", "score_camera": "score_candidates_reference",
                       "adapt_step": "rounds_python",
                       "run_rounds": "rounds_python", "walkable_lookup": "rounds_python",
                       "owner_crop": "owner_map", "inside": "ellipse_crop_reference",
                       "ideal_position": "ellipse_crop_reference", "pixels_by_rows": "score_candidates_reference",
                       "pixels_distorted": "score_candidates_reference",
                       "sample_region": "score_candidates_reference"}
    import importlib
    for path in PACKAGE.glob("*.py"):
        module = importlib.import_module(f"worldtrack.trackers.ellipsoid.{path.stem}")
        for name, obj in vars(module).items():
            if isinstance(obj, numba.core.registry.CPUDispatcher) and obj.__module__ == module.__name__ \
                    and not name.startswith("_"):
                reference = checked_through.get(name, f"{name}_reference")
                assert any(hasattr(importlib.import_module(f"worldtrack.trackers.ellipsoid.{p.stem}"), reference)
                           for p in PACKAGE.glob("*.py")), f"{path.stem}.{name}: no {reference}"
        assert inspect.getdoc(module), path.stem
