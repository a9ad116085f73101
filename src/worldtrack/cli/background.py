"""``worldtrack background VIDEO --out bg.png``: an empty-scene image from a video with people in it.

The I/O edge of :func:`worldtrack.foreground.background.estimate_background`: reads a sample of
frames spread over the video (sequentially, which is faster and more reliable than seeking in
H.264), estimates the background and writes it as an image that ``worldtrack track
--background CAM=bg.png`` reads.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from worldtrack.cli._args import parse_size
from worldtrack.errors import InputError

if TYPE_CHECKING:
    import numpy as np

DESCRIPTION = """\
Estimate the background (the scene without people) from a video in which people walk, when
no empty frame exists. Frames are sampled evenly over the whole video.

methods:
  mode      (default) per pixel, the most frequent grey level over the sample (a smoothed
            histogram), then the median colour of the samples near it. Removes a person who
            stands still at one place for a long time - even for more than half of the video,
            or while others cross the same spot - as long as the background is still what that
            pixel shows most often.
  median    two-pass temporal median: a median, then the median again without the samples
            that differ from it by more than --threshold grey levels (grown by 2 px). Removes
            people who stand still for up to about half of the video, and the faint trails
            passers-by leave in a plain median; fails when a spot is covered in more than half
            of the samples. (This is also what 'worldtrack track' uses when given no background.)
  adaptive  OpenCV MOG2 run over the sample; its background image. Keeps faint ghosts of
            people who were present in many samples; offered for comparison.
"""

EPILOG = """\
example (PETS 2009 S2.L1, with PETS=path/to/pets2009_s2l1 as in examples/pets2009/README.md):
  worldtrack background $PETS/video/View_001_480x360.avi --out bg.png
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("background", help="estimate an empty-scene background image from a video",
                       description=DESCRIPTION, epilog=EPILOG,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("video", metavar="VIDEO", help="video file (or a folder of images)")
    p.add_argument("--out", required=True, metavar="bg.png", help="background image to write (PNG)")
    p.add_argument("--samples", default="80", metavar="N",
                   help="frames sampled evenly over the video (default 80)")
    p.add_argument("--method", default="mode", metavar="mode|median|adaptive",
                   help="estimator (default: mode, see above)")
    p.add_argument("--threshold", default="30", metavar="GREY",
                   help="median: foreground threshold of the second pass, grey levels (default 30)")
    p.add_argument("--camera-size", metavar="WxH",
                   help="resize frames to the scene camera's image size first (e.g. 480x360)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def _positive_int(text: str, flag: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value <= 0:
        raise InputError(f"{flag}: expected a positive whole number, got {text!r}")
    return value


def sample_frames(path: str | Path, samples: int, progress: bool = True) -> tuple[list[np.ndarray], int]:
    """Read ``samples`` frames spread evenly over a video (or an image folder), in order.

    Returns the frames (BGR uint8) and the number of frames in the video.

    Raises
    ------
    InputError
        No such file, not a video, or no frame can be decoded.
    """


    import numpy as np
    import cv2

    path = Path(path)
    if path.is_dir():
        files = sorted(p for p in path.iterdir()
                       if p.suffix.lower() in (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff"))
        if not files:
            raise InputError(f"{path}: folder holds no images")
        idx = np.unique(np.linspace(0, len(files) - 1, min(samples, len(files))).round().astype(int))
        frames = []
        for i in _progress(idx, progress, len(idx)):
            img = cv2.imread(str(files[i]), cv2.IMREAD_COLOR)
            if img is None:
                raise InputError(f"{files[i]}: cannot be decoded as an image")
            frames.append(img)
        return frames, len(files)
    if not path.exists():
        raise InputError(f"{path}: no such file")
    cap = cv2.VideoCapture(str(path))
    if not cap.isOpened():
        raise InputError(f"{path}: cannot open as a video")
    try:
        count = int(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
        if count <= 0:              # header without a count: read everything once to count
            count = 0
            while cap.grab():
                count += 1
            cap.release()
            cap = cv2.VideoCapture(str(path))
        if count <= 0:
            raise InputError(f"{path}: no frames could be decoded")
        wanted = set(np.linspace(0, count - 1, min(samples, count)).round().astype(int).tolist())
        frames: list[np.ndarray] = []
        bar = _progress(range(count), progress, count)
        for i in bar:
            if not cap.grab():
                break
            if i in wanted:
                ok, img = cap.retrieve()
                if ok and img is not None:
                    frames.append(img)
        if hasattr(bar, "close"):
            bar.close()
    finally:
        cap.release()
    if not frames:
        raise InputError(f"{path}: no frames could be decoded")
    return frames, count


def _progress(iterable, enabled: bool, total: int):
    if not enabled:
        return iterable
    from tqdm import tqdm
    return tqdm(iterable, total=total, unit="frame", desc="reading", leave=False, dynamic_ncols=True)


def run(args: argparse.Namespace) -> int:
    import cv2

    from worldtrack.foreground.estimate import BACKGROUND_METHODS, estimate_background

    samples = _positive_int(args.samples, "--samples")
    if args.method not in BACKGROUND_METHODS:
        raise InputError(f"--method: expected one of {', '.join(BACKGROUND_METHODS)}, got {args.method!r}")
    try:
        threshold = float(args.threshold)
    except ValueError:
        threshold = -1.0
    if not 0 < threshold < 255:
        raise InputError(f"--threshold: expected grey levels in (0, 255), got {args.threshold!r}")
    size = parse_size(args.camera_size, "--camera-size", "480x360") if args.camera_size else None
    out = Path(args.out)
    if out.suffix.lower() not in (".png", ".bmp", ".tif", ".tiff", ".jpg", ".jpeg"):
        raise InputError(f"--out {out}: expected an image file name (.png)")
    if not out.parent.exists():
        raise InputError(f"--out {out}: folder {out.parent} does not exist")

    frames, count = sample_frames(args.video, samples, progress=not args.quiet)
    h, w = frames[0].shape[:2]
    resized = ""
    if size is not None and size != (w, h):
        if abs(size[0] / w - size[1] / h) > 0.01:
            print(f"warning: --camera-size {size[0]}x{size[1]} changes the aspect ratio of the "
                  f"{w}x{h} video", file=sys.stderr)
        frames = [cv2.resize(f, size, interpolation=cv2.INTER_AREA) for f in frames]
        resized = f", resized from {w}x{h}"
        w, h = size
    bg = estimate_background(frames, method=args.method, threshold=threshold)
    if not cv2.imwrite(str(out), bg):
        raise InputError(f"--out {out}: cannot write the image")
    print(f"{args.video}: {count} frames, {len(frames)} sampled; method {args.method}; "
          f"background {w}x{h}{resized} -> {out}")
    return 0
