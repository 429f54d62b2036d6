"""The user's own detector: a YOLO-family ONNX model run through OpenCV's DNN module.

Output layouts read (the model's first output; ``C`` classes, ``N`` candidate boxes):

* **YOLOv5** ``[1, N, 5 + C]``: ``cx, cy, w, h, objectness, C class scores``; a box's score is
  objectness times its best class score.
* **YOLOv8 / YOLO11** ``[1, 4 + C, N]``: ``cx, cy, w, h, C class scores`` (no objectness); a
  box's score is its best class score.

Boxes are in the pixels of the model's square input. The frame is letterboxed into it: scaled
by ``r = min(S / width, S / height)`` to ``round(width * r) x round(height * r)`` and padded
evenly with grey 114 to ``S x S`` (as ultralytics does); boxes go back as ``(x - pad_x) / r``.
Boxes under the score threshold are dropped, the rest go through OpenCV's non-maximum
suppression (``cv2.dnn.NMSBoxes``, per class). When ``C`` fits both layouts (a square output),
the class names decide, else the longer axis is taken for ``N``.

Class names come from a text file (one a line, ``--detector-names``), else from the model's
metadata (``names``, as ultralytics writes it: ``{0: 'person', 1: 'bicycle', ...}``), else
they are ``class0, class1, ...``.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from ..errors import InputError

__all__ = ["Detections", "OnnxDetector", "decode", "letterbox", "model_metadata",
           "read_names", "LAYOUTS"]

#: the output layouts read, by name
LAYOUTS = ("yolov5", "yolov8")
#: the grey of the letterbox's padding
PAD_GREY = 114


@dataclass(frozen=True)
class Detections:
    """One frame's detections: ``boxes`` (N, 4) ``x, y, w, h`` frame pixels, ``scores`` (N,),
    ``classes`` (N,) int indices into ``names``."""

    boxes: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))
    scores: np.ndarray = field(default_factory=lambda: np.zeros(0))
    classes: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    names: tuple[str, ...] = ()

    def __len__(self) -> int:
        return len(self.boxes)

    def name(self, i: int) -> str:
        """The class name of detection ``i``."""
        k = int(self.classes[i])
        return self.names[k] if 0 <= k < len(self.names) else f"class{k}"


def letterbox(image: np.ndarray, size: int) -> tuple[np.ndarray, float, tuple[float, float]]:
    """``image`` scaled into a ``size`` x ``size`` square, padded evenly with grey: the square
    (uint8, same channels), the scale ``r`` and the padding ``(pad_x, pad_y)`` in pixels."""
    h, w = image.shape[:2]
    r = min(size / w, size / h)
    nw, nh = int(round(w * r)), int(round(h * r))
    scaled = cv2.resize(image, (nw, nh), interpolation=cv2.INTER_LINEAR) if (nw, nh) != (w, h) \
        else image
    pad_x, pad_y = (size - nw) / 2.0, (size - nh) / 2.0
    top, left = int(round(pad_y - 0.1)), int(round(pad_x - 0.1))
    out = cv2.copyMakeBorder(scaled, top, size - nh - top, left, size - nw - left,
                             cv2.BORDER_CONSTANT, value=(PAD_GREY,) * 3)
    return out, r, (float(left), float(top))


def _layout(shape: tuple[int, ...], n_names: int) -> str:
    """The layout of an output of ``shape`` (:data:`LAYOUTS`), or raise naming it."""
    if len(shape) != 3 or shape[0] != 1:
        raise InputError(f"detector output of shape {list(shape)}: unknown layout; expected "
                         f"YOLOv5 [1, N, 5+C] or YOLOv8/YOLO11 [1, 4+C, N]")
    _, a, b = shape
    v5 = b >= 6 and (not n_names or b == 5 + n_names)
    v8 = a >= 5 and (not n_names or a == 4 + n_names)
    if v5 and v8:
        return "yolov8" if a < b else "yolov5"
    if v5 or v8:
        return "yolov5" if v5 else "yolov8"
    c = f"C = {n_names} class names" if n_names else "C classes"
    raise InputError(f"detector output of shape {list(shape)}: unknown layout; expected "
                     f"YOLOv5 [1, N, 5+C] or YOLOv8/YOLO11 [1, 4+C, N] ({c})")


def decode(output: np.ndarray, r: float, pad: tuple[float, float], frame_size: tuple[int, int],
           score: float, nms: float, n_names: int = 0) -> tuple[np.ndarray, np.ndarray,
                                                                 np.ndarray]:
    """An output tensor → ``(boxes (N, 4) x, y, w, h frame pixels, scores, classes)`` after
    the score threshold and per-class non-maximum suppression (module docstring)."""
    out = np.asarray(output, dtype=np.float32)
    layout = _layout(tuple(out.shape), n_names)
    rows = out[0] if layout == "yolov5" else out[0].T
    if layout == "yolov5":
        cls_scores = rows[:, 5:] * rows[:, 4:5]
    else:
        cls_scores = rows[:, 4:]
    classes = np.argmax(cls_scores, axis=1)
    scores = cls_scores[np.arange(len(rows)), classes]
    keep = scores >= score
    rows, scores, classes = rows[keep], scores[keep], classes[keep]
    cx, cy, w, h = rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3]
    boxes = np.column_stack([(cx - w / 2 - pad[0]) / r, (cy - h / 2 - pad[1]) / r, w / r, h / r])
    fw, fh = frame_size
    x1 = np.clip(boxes[:, 0], 0, fw)
    y1 = np.clip(boxes[:, 1], 0, fh)
    x2 = np.clip(boxes[:, 0] + boxes[:, 2], 0, fw)
    y2 = np.clip(boxes[:, 1] + boxes[:, 3], 0, fh)
    boxes = np.column_stack([x1, y1, x2 - x1, y2 - y1]).astype(np.float64)
    ok = (boxes[:, 2] > 0) & (boxes[:, 3] > 0)
    boxes, scores, classes = boxes[ok], scores[ok].astype(np.float64), classes[ok]
    if not len(boxes):
        return np.zeros((0, 4)), np.zeros(0), np.zeros(0, dtype=np.int64)
    kept = cv2.dnn.NMSBoxesBatched(boxes.tolist(), scores.tolist(), classes.tolist(),
                                   float(score), float(nms))
    kept = np.sort(np.asarray(kept, dtype=np.int64).reshape(-1))
    return boxes[kept], scores[kept], classes[kept].astype(np.int64)


def read_names(path: str | Path) -> tuple[str, ...]:
    """Class names from a text file, one a line (blank lines and ``#`` comments skipped)."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise InputError(f"{p}: cannot read the class names ({exc.strerror or exc})") from None
    except UnicodeDecodeError:
        raise InputError(f"{p}: the class names are not UTF-8 text") from None
    names = tuple(ln.strip() for ln in text.splitlines()
                  if ln.strip() and not ln.lstrip().startswith("#"))
    if not names:
        raise InputError(f"{p}: no class names (one a line)")
    return names


def _varint(buf: bytes, i: int) -> tuple[int, int]:
    shift = value = 0
    while True:
        if i >= len(buf) or shift > 63:
            raise ValueError("truncated varint")
        b = buf[i]
        value |= (b & 0x7F) << shift
        i += 1
        if not b & 0x80:
            return value, i
        shift += 7


def _fields(buf: bytes):
    """The ``(number, value)`` of each field of a protobuf message (length-delimited values as
    bytes, numbers as int)."""
    i = 0
    while i < len(buf):
        key, i = _varint(buf, i)
        number, kind = key >> 3, key & 7
        if kind == 0:
            value, i = _varint(buf, i)
        elif kind == 2:
            n, i = _varint(buf, i)
            value, i = buf[i:i + n], i + n
        elif kind in (1, 5):
            value, i = buf[i:i + (8 if kind == 1 else 4)], i + (8 if kind == 1 else 4)
        else:
            raise ValueError(f"protobuf wire type {kind}")
        yield number, value


def model_metadata(data: bytes) -> dict[str, str]:
    """The ``metadata_props`` of an ONNX model (``ModelProto`` field 14: key 1, value 2)."""
    out: dict[str, str] = {}
    try:
        for number, value in _fields(data):
            if number == 14 and isinstance(value, bytes):
                entry = dict(_fields(value))
                out[bytes(entry.get(1, b"")).decode("utf-8", "replace")] = \
                    bytes(entry.get(2, b"")).decode("utf-8", "replace")
    except ValueError:
        return {}
    return out


def _metadata_names(meta: dict[str, str]) -> tuple[str, ...]:
    """ultralytics' ``names`` (a Python dict literal of index → name), or ()."""
    text = meta.get("names")
    if not text:
        return ()
    try:
        names = ast.literal_eval(text)
    except (ValueError, SyntaxError):
        return ()
    if isinstance(names, dict):
        return tuple(str(names[k]) for k in sorted(names))
    if isinstance(names, (list, tuple)):
        return tuple(str(n) for n in names)
    return ()


class OnnxDetector:
    """A YOLO-family ONNX model (module docstring) on frames (:meth:`detect`).

    Parameters
    ----------
    model : path of the ``.onnx`` file.
    names : path of a class-names file ("" = the model's metadata).
    input_size : side of the model's square input (pixels).
    score, nms : score threshold and NMS IoU threshold.
    """

    def __init__(self, model: str | Path, names: str | Path = "", input_size: int = 640,
                 score: float = 0.25, nms: float = 0.45) -> None:
        p = Path(model)
        try:
            data = p.read_bytes()
        except OSError as exc:
            raise InputError(f"{p}: cannot read the detector model "
                             f"({exc.strerror or exc})") from None
        try:
            self.net = cv2.dnn.readNetFromONNX(str(p))
        except cv2.error:
            raise InputError(f"{p}: not an ONNX model OpenCV can load") from None
        if self.net.empty():
            raise InputError(f"{p}: not an ONNX model OpenCV can load")
        self.names = read_names(names) if names else _metadata_names(model_metadata(data))
        self.size, self.score, self.nms = int(input_size), float(score), float(nms)
        self.path = p

    def detect(self, image: np.ndarray) -> Detections:
        """The detections of one ``(H, W, 3) uint8`` BGR frame (gray frames are expanded)."""
        if image.ndim == 2:
            image = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
        square, r, pad = letterbox(image, self.size)
        blob = cv2.dnn.blobFromImage(square, 1 / 255.0, swapRB=True)
        self.net.setInput(blob)
        try:
            out = self.net.forward()
        except cv2.error as exc:
            first = str(exc).strip().splitlines()[-1][:160] if str(exc).strip() else "error"
            raise InputError(f"{self.path}: the detector model failed on a "
                             f"{self.size}x{self.size} input: {first}") from None
        boxes, scores, classes = decode(out, r, pad, (image.shape[1], image.shape[0]),
                                        self.score, self.nms, len(self.names))
        n = int(classes.max()) + 1 if len(classes) else 0
        names = self.names or tuple(f"class{k}" for k in range(n))
        return Detections(boxes, scores, classes, names)


def create(spec: str, **options: Any) -> OnnxDetector:
    """The detector a ``detector.model`` spec names: ``onnx:PATH``."""
    kind, _, path = spec.partition(":")
    if kind != "onnx" or not path:
        raise InputError(f"detector {spec!r}: expected onnx:PATH (a YOLO-family ONNX model)")
    return OnnxDetector(path, **options)
