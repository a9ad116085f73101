"""Calibration files other tools write, read into worldtrack cameras (metres, OpenCV model).

Formats (detected from the content, not the file name):

* **Tsai XML** as PETS 2009 ships it (R. Willson's implementation)::

      <Camera name="View_001">
        <Geometry width="768" height="576" ncx=".." nfx=".." dx=".." dy=".." dpx=".." dpy=".."/>
        <Intrinsic focal=".." kappa1=".." cx=".." cy=".." sx=".."/>
        <Extrinsic tx=".." ty=".." tz=".." rx=".." ry=".." rz=".."/>
      </Camera>

  Sensor quantities (focal, dx, dpx, kappa1) in millimetres as Willson's code requires; the
  translation in the world unit of the calibration (PETS: millimetres). A root holding several
  ``<Camera name=…>`` elements is a multi-camera file. Converted with
  :func:`worldtrack.geometry.tsai.tsai_to_camera` (the distortion model differs).
* **OpenCV FileStorage** YAML (``%YAML:1.0`` with ``!!opencv-matrix``) or XML
  (``<opencv_storage>``), read with ``cv2.FileStorage``: ``camera_matrix``,
  ``distortion_coefficients``, ``rvec``/``tvec`` or ``R``/``t``, ``image_width``/``image_height``.
* **JSON** (or plain YAML) with ``K``, ``R`` (or ``rvec``), ``t`` and optionally ``dist`` and
  ``image_size``: one camera, or a mapping from camera name to such a block (EPFL mot3d's
  ``calibration.json``).
* **Projection text**: 3×4 matrices ``P ~ K[R|t]`` as 12 numbers each, either bare (cameras
  named 1, 2, …) or as ``NAME: p11 … p34`` lines (KITTI style); ``#`` starts a comment.

Accepted key names (case-insensitive) for K: ``K, camera_matrix, cameraMatrix, intrinsic(s),
intrinsic_matrix, mtx``; distortion: ``dist, distortion, distortion_coefficients, distCoeffs,
dist_coeffs, D``; rotation: ``R, rotation, rotation_matrix`` or ``rvec, rotation_vector``;
translation: ``t, T, tvec, translation, translation_vector``; projection: ``P,
projection_matrix``; image size: ``image_size``/``imageSize``/``size`` ([w, h]) or
``image_width``/``width`` and ``image_height``/``height``.

:func:`read_calibration` returns the parameters in the file's own units;
:func:`worldtrack.io.calibration_import.import_camera` decides the units (declared, or detected from
the size of the translation), converts to metres, converts Tsai to OpenCV and rescales to the
video's image size.
"""

from __future__ import annotations

import json
import math
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from worldtrack.errors import InputError
from worldtrack.geometry.camera import Camera
from worldtrack.geometry.rotation import rodrigues


#: Human-readable names of the formats :func:`read_calibration` recognises.
FORMATS = {
    "tsai-xml": "Tsai XML (PETS / Willson)",
    "opencv-yaml": "OpenCV FileStorage YAML",
    "opencv-xml": "OpenCV FileStorage XML",
    "json": "JSON K/R/t",
    "yaml": "YAML K/R/t",
    "projection-text": "3x4 projection matrix (text)",
}


_ALIASES = {
    "K": ("k", "camera_matrix", "cameramatrix", "intrinsic", "intrinsics", "intrinsic_matrix", "mtx"),
    "dist": ("dist", "distortion", "distortion_coefficients", "distcoeffs", "dist_coeffs", "d"),
    "R": ("r", "rotation", "rotation_matrix"),
    "rvec": ("rvec", "rotation_vector"),
    "t": ("t", "tvec", "translation", "translation_vector"),
    "P": ("p", "projection", "projection_matrix"),
    "size": ("image_size", "imagesize", "size", "resolution"),
    "width": ("image_width", "width"),
    "height": ("image_height", "height"),
}

_TSAI_FIELDS = {
    "Geometry": ("width", "height", "ncx", "nfx", "dx", "dy", "dpx", "dpy"),
    "Intrinsic": ("focal", "kappa1", "cx", "cy", "sx"),
    "Extrinsic": ("tx", "ty", "tz", "rx", "ry", "rz"),
}


@dataclass(frozen=True, eq=False)
class CalibrationFile:
    """One camera's parameters as a calibration file states them, in the file's own units.

    Attributes
    ----------
    path : str
    format : str
        A key of :data:`FORMATS`.
    camera : str
        The selected camera's name in the file.
    cameras : tuple of str
        Every camera the file holds.
    image_size : (int, int) or None
        ``(width, height)`` the calibration is for, when the file says.
    K, R, t, dist : ndarray or None
        Pinhole parameters (``t`` in file units); ``dist`` is OpenCV ``(k1, k2, p1, p2, k3)``.
    P : (3, 4) ndarray or None
        Projection matrix (world in file units), for projection-text files.
    tsai : dict of str → float, or None
        Tsai fields (``focal``, ``kappa1``, ``dpx``, ``dpy``, ``sx``, ``cx``, ``cy``, ``tx``…``rz``;
        sensor millimetres, translation in file units) for Tsai files.
    notes : list of str
        Things the reader inferred (e.g. ``dpx`` computed from ``dx·ncx/nfx``).
    """

    path: str
    format: str
    camera: str
    cameras: tuple[str, ...]
    image_size: tuple[int, int] | None = None
    K: np.ndarray | None = None
    R: np.ndarray | None = None
    t: np.ndarray | None = None
    dist: np.ndarray | None = None
    P: np.ndarray | None = None
    tsai: dict[str, float] | None = None
    notes: list[str] = field(default_factory=list)

    @property
    def format_name(self) -> str:
        return FORMATS[self.format]

    @property
    def translation_norm(self) -> float:
        """|t| in file units (distance from the camera to the world origin)."""
        if self.tsai is not None:
            return float(np.linalg.norm([self.tsai["tx"], self.tsai["ty"], self.tsai["tz"]]))
        if self.t is not None:
            return float(np.linalg.norm(self.t))
        assert self.P is not None
        return float(np.linalg.norm(Camera.from_projection("p", 1, 1, self.P).t))


# ---------------------------------------------------------------------------- reading

def read_calibration(path: str | Path, camera: str | None = None) -> CalibrationFile:
    """Read one camera from a calibration file (formats: see the module docstring).

    Parameters
    ----------
    path : str or Path
    camera : str, optional
        Which camera of a multi-camera file; required when the file holds several.

    Raises
    ------
    InputError
        One line naming the file (and camera): unreadable or unrecognised file, a missing or
        malformed field, an unknown camera name.
    """
    label = str(path)
    try:
        raw = Path(path).read_bytes()
    except FileNotFoundError:
        raise InputError(f"{label}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"{label}: is a directory, expected a calibration file") from None
    except OSError as e:
        raise InputError(f"{label}: cannot read ({e.strerror})") from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise InputError(f"{label}: not a text file (expected Tsai XML, OpenCV YAML/XML, JSON or a "
                         "3x4 matrix)") from None
    head = text.lstrip()
    if not head:
        raise InputError(f"{label}: empty file")
    if head.startswith("%YAML") or "!!opencv-matrix" in text:
        return _read_filestorage(path, label, camera, "opencv-yaml")
    if head.startswith("<"):
        try:
            root = ET.fromstring(text)
        except ET.ParseError as e:
            raise InputError(f"{label}: not valid XML ({e})") from None
        if root.tag == "opencv_storage":
            return _read_filestorage(path, label, camera, "opencv-xml")
        return _read_tsai(root, label, camera)
    if head[0] in "{[":
        try:
            data = json.loads(text)
        except json.JSONDecodeError as e:
            raise InputError(f"{label}: not valid JSON (line {e.lineno}: {e.msg})") from None
        return _from_mapping(data, label, camera, "json")
    if _looks_numeric(text):
        return _read_projection_text(text, label, camera)
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError:
        data = None
    if isinstance(data, dict):
        return _from_mapping(data, label, camera, "yaml")
    raise InputError(f"{label}: unrecognised calibration format (expected Tsai XML, OpenCV "
                     "FileStorage YAML/XML, JSON with K, R, t, or 3x4 projection matrices as text)")


# --- Tsai XML ---------------------------------------------------------------------------

def _read_tsai(root: ET.Element, label: str, camera: str | None) -> CalibrationFile:
    if root.tag == "Camera":
        elements = [root]
    else:
        elements = list(root.iter("Camera"))
    if not elements:
        raise InputError(f"{label}: XML root <{root.tag}> is neither a Tsai <Camera> nor "
                         "<opencv_storage>")
    names = tuple(e.get("name") or str(i + 1) for i, e in enumerate(elements))
    index = _select(names, camera, label)
    el, name = elements[index], names[index]
    where = f"{label}: camera {name!r}" if len(names) > 1 else label
    values: dict[str, float] = {}
    for section, keys in _TSAI_FIELDS.items():
        node = el.find(section)
        if node is None:
            raise InputError(f"{where}: missing <{section}> (a Tsai calibration needs Geometry, "
                             "Intrinsic and Extrinsic)")
        for key in keys:
            text = node.get(key)
            if text is None:
                continue
            try:
                values[key] = float(text)
            except ValueError:
                raise InputError(f"{where}: {section}.{key}: expected a number, got {text!r}") from None
            if not math.isfinite(values[key]):
                raise InputError(f"{where}: {section}.{key}: expected a finite number, got {text!r}")
    notes: list[str] = []
    if "dpx" not in values:
        if {"dx", "ncx", "nfx"} <= values.keys():
            values["dpx"] = values["dx"] * values["ncx"] / values["nfx"]
            notes.append("dpx computed as dx·ncx/nfx")
        elif "dx" in values:
            values["dpx"] = values["dx"]
            notes.append("dpx taken as dx (no ncx/nfx)")
    elif {"dx", "ncx", "nfx"} <= values.keys():
        expected = values["dx"] * values["ncx"] / values["nfx"]
        if abs(values["dpx"] - expected) > 1e-6 * expected:
            notes.append(f"dpx = {values['dpx']:.6g} differs from dx·ncx/nfx = {expected:.6g}; using dpx")
    if "dpy" not in values and "dy" in values:
        values["dpy"] = values["dy"]
        notes.append("dpy taken as dy")
    values.setdefault("sx", 1.0)
    required = {"Geometry": ("width", "height", "dpx", "dpy"), "Intrinsic": ("focal", "kappa1", "cx", "cy"),
                "Extrinsic": _TSAI_FIELDS["Extrinsic"]}
    for section, keys in required.items():
        missing = [k for k in keys if k not in values]
        if missing:
            hint = " (or dx, ncx, nfx)" if "dpx" in missing else ""
            raise InputError(f"{where}: {section}: missing {', '.join(missing)}{hint}")
    for key in ("focal", "dpx", "dpy", "sx"):
        if values[key] <= 0:
            raise InputError(f"{where}: {key}: expected a positive number, got {values[key]:g}")
    size = _size(values["width"], values["height"], where)
    return CalibrationFile(label, "tsai-xml", name, names, size, tsai=values, notes=notes)


# --- OpenCV FileStorage -----------------------------------------------------------------

def _node_value(node: Any) -> Any:
    """A cv2.FileNode as Python: matrices as ndarrays, sequences as lists, maps as dicts."""
    if node.isMap():
        try:
            mat = node.mat()
        except Exception:                      # not an opencv-matrix: a plain map
            mat = None
        if mat is not None:
            return np.asarray(mat, dtype=float)
        return {k: _node_value(node.getNode(k)) for k in node.keys()}
    if node.isSeq():
        return [_node_value(node.at(i)) for i in range(node.size())]
    if node.isInt() or node.isReal():
        return float(node.real())
    if node.isString():
        return node.string()
    return None


def _read_filestorage(path: str | Path, label: str, camera: str | None, fmt: str) -> CalibrationFile:
    import cv2

    try:
        fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    except (cv2.error, SystemError) as e:
        message = str(e.__cause__ or e)
        m = re.search(r"\((\d+)\): ([^'\n]*)", message)
        detail = f"line {m.group(1)}: {m.group(2).strip()}" if m else "cannot parse"
        raise InputError(f"{label}: not a valid OpenCV FileStorage file ({detail})") from None
    try:
        if not fs.isOpened():
            raise InputError(f"{label}: cv2.FileStorage cannot open it")
        root = fs.root()
        data = {k: _node_value(root.getNode(k)) for k in root.keys()}
    finally:
        fs.release()
    return _from_mapping(data, label, camera, fmt)


# --- JSON / YAML / FileStorage mappings -------------------------------------------------

def _lookup(block: dict, what: str) -> tuple[str, Any] | None:
    lower = {str(k).lower(): k for k in block}
    for alias in _ALIASES[what]:
        if alias in lower:
            key = lower[alias]
            return str(key), block[key]
    return None


def _has_camera_keys(block: Any) -> bool:
    return isinstance(block, dict) and any(_lookup(block, w) for w in ("K", "P"))


def _from_mapping(data: Any, label: str, camera: str | None, fmt: str) -> CalibrationFile:
    if isinstance(data, list) and data and all(isinstance(b, dict) for b in data):
        names = tuple(str(b.get("name", b.get("id", i + 1))) for i, b in enumerate(data))
        blocks = dict(zip(names, data))
    elif _has_camera_keys(data):
        if camera is not None and str(camera) not in ("1", str(data.get("name", data.get("id", "")))):
            raise InputError(f"{label}: holds a single camera (no camera named {camera!r}); leave out --camera")
        name = str(data.get("name", data.get("id", "1")))
        blocks = {name: data}
        names = (name,)
    elif isinstance(data, dict) and any(_has_camera_keys(v) for v in data.values()):
        names = tuple(str(k) for k, v in data.items() if _has_camera_keys(v))
        blocks = {str(k): v for k, v in data.items() if _has_camera_keys(v)}
    else:
        keys = ", ".join(map(str, list(data)[:8])) if isinstance(data, dict) else type(data).__name__
        raise InputError(f"{label}: no camera found: expected K (camera_matrix) with R/rvec and t/tvec, "
                         f"or P, or a mapping from camera names to such blocks; got {keys}")
    name = names[_select(names, camera, label)]
    block = blocks[name]
    where = f"{label}: camera {name!r}" if len(names) > 1 else label

    def get(what: str, rows: int | None, cols: int | None) -> np.ndarray | None:
        found = _lookup(block, what)
        if found is None:
            return None
        key, value = found
        return _array(value, rows, cols, f"{where}: {key}")

    P = get("P", 3, 4)
    K = get("K", 3, 3)
    R = get("R", 3, 3)
    rvec = get("rvec", None, None)
    t = get("t", None, None)
    dist = get("dist", None, None)
    if P is not None and K is None:
        if any(x is not None for x in (R, rvec, t)):
            raise InputError(f"{where}: give either P or K with R and t, not both")
        return CalibrationFile(label, fmt, name, names, _mapping_size(block, where),
                               P=P, dist=_dist(dist, where) if dist is not None else None)
    if K is None:
        raise InputError(f"{where}: missing the intrinsics K (camera_matrix)")
    if R is None and rvec is None:
        raise InputError(f"{where}: missing the rotation (R or rvec)")
    if t is None:
        raise InputError(f"{where}: missing the translation (t or tvec)")
    t = _vector3(t, f"{where}: translation")
    if rvec is not None:
        rvec = _vector3(rvec, f"{where}: rvec")
        R_from_rvec = rodrigues(rvec)
        if R is not None and not np.allclose(R, R_from_rvec, atol=1e-6):
            raise InputError(f"{where}: R and rvec disagree; give one of them")
        R = R_from_rvec if R is None else R
    if not (np.allclose(R @ R.T, np.eye(3), atol=1e-6) and np.linalg.det(R) > 0):
        raise InputError(f"{where}: R: expected a rotation matrix (orthonormal, det +1)")
    if not (K[0, 0] > 0 and K[1, 1] > 0 and abs(K[2, 2] - 1) < 1e-9 and np.all(K[[1, 2, 2], [0, 0, 1]] == 0)):
        raise InputError(f"{where}: K: expected [[fx, s, cx], [0, fy, cy], [0, 0, 1]] with fx, fy > 0")
    return CalibrationFile(label, fmt, name, names, _mapping_size(block, where), K=K, R=R, t=t,
                           dist=_dist(dist, where) if dist is not None else np.zeros(5))


def _mapping_size(block: dict, where: str) -> tuple[int, int] | None:
    found = _lookup(block, "size")
    if found is not None:
        key, value = found
        a = _array(value, None, None, f"{where}: {key}").ravel()
        if a.size != 2:
            raise InputError(f"{where}: {key}: expected [width, height], got {a.size} values")
        return _size(a[0], a[1], f"{where}: {key}")
    w, h = _lookup(block, "width"), _lookup(block, "height")
    if w is not None and h is not None:
        return _size(_scalar(w[1], f"{where}: {w[0]}"), _scalar(h[1], f"{where}: {h[0]}"), where)
    return None


def _scalar(value: Any, where: str) -> float:
    a = _array(value, None, None, where).ravel()
    if a.size != 1:
        raise InputError(f"{where}: expected one number, got {a.size}")
    return float(a[0])


def _array(value: Any, rows: int | None, cols: int | None, where: str) -> np.ndarray:
    if isinstance(value, dict) and {"rows", "cols", "data"} <= set(value):   # ROS / FileStorage-like
        try:
            value = np.asarray(value["data"], dtype=float).reshape(int(value["rows"]), int(value["cols"]))
        except (TypeError, ValueError):
            raise InputError(f"{where}: rows x cols does not match the number of data values") from None
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{where}: expected numbers, got {str(value)[:60]!r}") from None
    if not np.all(np.isfinite(a)):
        raise InputError(f"{where}: expected finite numbers, got NaN or infinity")
    if rows is not None and cols is not None:
        if a.size == rows * cols and a.ndim == 1:
            a = a.reshape(rows, cols)
        if a.shape != (rows, cols):
            got = "x".join(map(str, a.shape)) if a.ndim else "a scalar"
            raise InputError(f"{where}: expected a {rows}x{cols} matrix, got {got}")
    return a


def _vector3(a: np.ndarray, where: str) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    if a.size != 3:
        raise InputError(f"{where}: expected 3 values, got {a.size}")
    return a.reshape(3)


def _dist(a: np.ndarray, where: str) -> np.ndarray:
    d = np.asarray(a, dtype=float).ravel()
    if d.size > 5:
        if np.any(d[5:] != 0):
            raise InputError(f"{where}: distortion: {d.size} coefficients with non-zero k4.. terms "
                             "(rational or thin-prism model); worldtrack supports (k1, k2, p1, p2, k3)")
        d = d[:5]
    return np.concatenate([d, np.zeros(5 - d.size)])


# --- projection matrices as text --------------------------------------------------------

_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_NAMED = re.compile(rf"^\s*([A-Za-z_][\w.-]*)\s*[:=]\s*((?:{_NUMBER}[\s,;]*)+)$")


def _looks_numeric(text: str) -> bool:
    body = [ln.split("#", 1)[0].strip() for ln in text.splitlines()]
    body = [ln for ln in body if ln]
    return bool(body) and all(_NAMED.match(ln) or re.fullmatch(rf"(?:{_NUMBER}[\s,;\[\]]*)+", ln)
                              for ln in body)


def _read_projection_text(text: str, label: str, camera: str | None) -> CalibrationFile:
    named: dict[str, list[float]] = {}
    bare: list[float] = []
    for ln in text.splitlines():
        ln = ln.split("#", 1)[0].strip()
        if not ln:
            continue
        m = _NAMED.match(ln)
        if m:
            named[m.group(1)] = [float(x) for x in re.findall(_NUMBER, m.group(2))]
        else:
            bare.extend(float(x) for x in re.findall(_NUMBER, ln))
    if named and bare:
        raise InputError(f"{label}: mixes named (NAME: 12 numbers) and bare matrix lines")
    if bare:
        if len(bare) % 12:
            raise InputError(f"{label}: expected 3x4 projection matrices (12 numbers each), got "
                             f"{len(bare)} numbers")
        named = {str(i + 1): bare[12 * i:12 * i + 12] for i in range(len(bare) // 12)}
    bad = [n for n, v in named.items() if len(v) != 12]
    if bad:
        raise InputError(f"{label}: {bad[0]}: expected 12 numbers (a 3x4 matrix), got {len(named[bad[0]])}")
    names = tuple(named)
    name = names[_select(names, camera, label)]
    P = np.asarray(named[name], dtype=float).reshape(3, 4)
    where = f"{label}: camera {name!r}" if len(names) > 1 else label
    if np.linalg.matrix_rank(P[:, :3]) < 3:
        raise InputError(f"{where}: the left 3x3 block of P is singular (not a finite camera)")
    return CalibrationFile(label, "projection-text", name, names, None, P=P)


# --- helpers ----------------------------------------------------------------------------

def _select(names: tuple[str, ...], camera: str | None, label: str) -> int:
    if camera is None:
        if len(names) == 1:
            return 0
        raise InputError(f"{label}: holds {len(names)} cameras ({', '.join(names)}); choose one with --camera")
    if str(camera) in names:
        return names.index(str(camera))
    raise InputError(f"{label}: no camera {camera!r} (cameras: {', '.join(names)})")


def _size(w: float, h: float, where: str) -> tuple[int, int]:
    if not (w == int(w) and h == int(h) and w > 0 and h > 0):
        raise InputError(f"{where}: image size: expected positive whole pixels, got {w:g}x{h:g}")
    return int(w), int(h)
