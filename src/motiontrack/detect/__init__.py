"""The user's own object detector (``detector.model``): a YOLO-family ONNX model
(:mod:`.onnx_yolo`) and how its boxes join the motion regions (:mod:`.fuse`)."""

from .fuse import detector_regions, matches
from .onnx_yolo import Detections, OnnxDetector, create

__all__ = ["Detections", "OnnxDetector", "create", "detector_regions", "matches"]
