"""The classic OpenCV tutorial for detecting moving objects, as a script a user would write.

Each frame: gray + 5x5 Gaussian blur, MOG2 (history 500, varThreshold 16, shadows on),
threshold at 254 (drops the shadows, marked 127), one 3x3 erosion, three 3x3 dilations, external
contours with an area of at least 500 px, their bounding boxes. No identities: each box gets an
id of its own in the MOT file, so only recall and precision of its boxes compare with a tracker.

This is the baseline the throughput benchmark runs as a whole process (``benchmarks/throughput.py``)
and, through :func:`detect`, in-process (``--in-process``). It needs only OpenCV and NumPy.

Run: python benchmarks/tutorial.py VIDEO [--out boxes.txt] [--video annotated.avi
     [--fourcc MJPG]] [--frames N]
"""

from __future__ import annotations

import argparse
import sys
import time

import cv2
import numpy as np

KERNEL = np.ones((3, 3), np.uint8)
MIN_AREA = 500

#: fourcc → the container it is written in
FOURCC_EXTENSIONS = {"VP80": ".webm", "mp4v": ".mp4", "MJPG": ".avi", "XVID": ".avi"}


def new_subtractor() -> cv2.BackgroundSubtractorMOG2:
    return cv2.createBackgroundSubtractorMOG2(500, 16, True)


def detect(frame: np.ndarray, sub: cv2.BackgroundSubtractorMOG2) -> list[tuple[int, int, int, int]]:
    """Boxes ``(x, y, w, h)`` of the moving objects in ``frame`` (BGR, uint8), updating ``sub``."""
    gray = cv2.GaussianBlur(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY), (5, 5), 0)
    fg = sub.apply(gray)
    _, fg = cv2.threshold(fg, 254, 255, cv2.THRESH_BINARY)
    fg = cv2.erode(fg, KERNEL, iterations=1)
    fg = cv2.dilate(fg, KERNEL, iterations=3)
    contours, _ = cv2.findContours(fg, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    return [cv2.boundingRect(c) for c in contours if cv2.contourArea(c) >= MIN_AREA]


def fourcc_for(path: str, fourcc: str | None) -> str:
    """``fourcc`` as given, or the one :data:`FOURCC_EXTENSIONS` pairs with ``path``'s extension."""
    if fourcc:
        return fourcc
    for code, ext in FOURCC_EXTENSIONS.items():
        if path.lower().endswith(ext):
            return code
    sys.exit(f"--video {path}: give --fourcc, or a name ending in "
             + ", ".join(sorted(set(FOURCC_EXTENSIONS.values()))))


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("source", help="video file")
    ap.add_argument("--out", help="write the boxes to this MOTChallenge text file")
    ap.add_argument("--video", help="write the frames with their boxes drawn to this video file")
    ap.add_argument("--fourcc", help="codec of --video (default from its extension: "
                    + ", ".join(f"{e} {c}" for c, e in FOURCC_EXTENSIONS.items()) + ")")
    ap.add_argument("--frames", type=int, default=0, help="at most this many frames (0: all)")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    cap = cv2.VideoCapture(args.source)
    if not cap.isOpened():
        sys.exit(f"cannot open {args.source}")
    writer = None
    if args.video:
        size = (int(cap.get(cv2.CAP_PROP_FRAME_WIDTH)), int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT)))
        code = fourcc_for(args.video, args.fourcc)
        writer = cv2.VideoWriter(args.video, cv2.VideoWriter_fourcc(*code),
                                 cap.get(cv2.CAP_PROP_FPS) or 25.0, size)
        if not writer.isOpened():
            sys.exit(f"OpenCV cannot write {code} to {args.video}")
    out = open(args.out, "w", encoding="utf-8") if args.out else None
    sub = new_subtractor()
    limit = args.frames or sys.maxsize
    k = next_id = 0
    while k < limit:
        ok, frame = cap.read()
        if not ok:
            break
        k += 1
        for x, y, w, h in detect(frame, sub):
            next_id += 1
            if out:
                out.write(f"{k},{next_id},{x},{y},{w},{h},1,-1,-1,-1\n")
            if writer:
                cv2.rectangle(frame, (x, y), (x + w, y + h), (0, 255, 0), 2)
        if writer:
            writer.write(frame)
    if out:
        out.close()
    if writer:
        writer.release()
    t = time.perf_counter() - t0
    print(f"frames {k} in {t:.2f} s ({k / t:.1f} fps)")


if __name__ == "__main__":
    main()
