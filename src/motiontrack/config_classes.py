"""The config sections of object classes: the classifier (``classes``) and the user's own
detector (``detector``); docs/classes.md."""

from __future__ import annotations

from dataclasses import dataclass

from .config_section import ConfigSection as _Section
from .schema import Not, param

__all__ = ["ClassesConfig", "DetectorConfig"]


#: the classifier's keys take effect while it runs
_ON = {"enabled": True}
#: the HOG keys, while it runs with HOG
_HOG = {"enabled": True, "hog": Not("off", "daimler")}


@dataclass(frozen=True)
class ClassesConfig(_Section):
    """A class per track (``person``, ``vehicle``, ``other``) from evidence accumulated over its
    life (docs/classes.md). Lengths in metres need ``measure.camera``; without one the image
    aspect and the speed in box heights per second decide."""

    enabled: bool = param(True, doc="give every track a class and a confidence")
    min_frames: int = param(5, lo=1, hi=10000, when=_ON,
                            doc="measured frames of evidence before a track is anything but other")
    person_aspect: float = param(1.6, lo=0.1, hi=20.0, when=_ON,
                                 doc="without a camera: a box at least this much taller than wide "
                                     "(height/width) looks like a person")
    vehicle_aspect: float = param(1.2, lo=0.05, hi=20.0, when=_ON,
                                  doc="without a camera: a box no taller than this times its width "
                                      "(height/width) looks like a vehicle")
    person_max_speed: float = param(2.5, lo=0.0, hi=100.0, when=_ON,
                                    doc="without a camera: fastest person in box heights per second "
                                        "(a walker covers about one height a second)")
    person_min_height_m: float = param(1.2, lo=0.0, hi=20.0, when=_ON,
                                       doc="with a camera: shortest person (m)")
    person_max_height_m: float = param(2.3, lo=0.0, hi=20.0, when=_ON,
                                       doc="with a camera: tallest person (m)")
    person_max_width_m: float = param(1.1, lo=0.0, hi=20.0, when=_ON,
                                      doc="with a camera: widest person (m)")
    vehicle_min_width_m: float = param(1.6, lo=0.0, hi=50.0, when=_ON,
                                       doc="with a camera: narrowest vehicle box (m), seen from "
                                           "any side")
    person_max_speed_mps: float = param(4.0, lo=0.0, hi=100.0, when=_ON,
                                        doc="with a camera: fastest person (m/s); faster is a "
                                            "vehicle")
    hog: str = param("daimler", choices=("daimler", "default", "off"), when=_ON,
                     doc="OpenCV's HOG people detector on the boxes of a few tracks a frame: "
                         "daimler (48x96 window, small people), default (64x128, INRIA) or off")
    hog_vote: int = param(10, lo=1, hi=1000, when=_HOG,
                          doc="votes for person of each HOG person centred in a track's box (a "
                              "miss casts none)")
    hog_threshold: float = param(0.3, lo=-5.0, hi=5.0, when=_HOG,
                                 doc="SVM margin a HOG window needs to be a person")
    hog_every: int = param(5, lo=1, hi=10000, when=_HOG,
                           doc="measured frames of a track between two HOG looks at it")
    hog_per_frame: int = param(2, lo=1, hi=1000, when=_HOG,
                               doc="most tracks HOG looks at in a frame (vehicle-like tracks "
                                   "first)")


@dataclass(frozen=True)
class DetectorConfig(_Section):
    """The user's own object detector (docs/classes.md): its boxes replace the motion regions
    or are fused with them, and give the tracks they match their class."""

    model: str = param("", doc="onnx:PATH, a YOLO-family ONNX model (YOLOv5 [1, N, 5+C], "
                               "YOLOv8/YOLO11 [1, 4+C, N]) run by OpenCV's DNN module; empty = none "
                               "(`--detector`)")
    names: str = param("", doc="class names, one a line (`--detector-names`); empty = the "
                               "model's metadata", when={"model": Not("", "onnx:yolo.onnx")})
    input_size: int = param(640, lo=32, hi=4096, doc="side of the model's square input (px): the "
                                                      "frame is letterboxed into it",
                            when={"model": Not("", "onnx:yolo.onnx")})
    score: float = param(0.25, lo=0.0, hi=1.0, doc="lowest detection score kept",
                         when={"model": Not("", "onnx:yolo.onnx")})
    nms: float = param(0.45, lo=0.0, hi=1.0, doc="IoU above which non-maximum suppression drops "
                                                 "the weaker box of a class",
                       when={"model": Not("", "onnx:yolo.onnx")})
    every: int = param(1, lo=1, hi=1000, doc="run the detector every N frames",
                       when={"model": Not("", "onnx:yolo.onnx")})
    mode: str = param("fuse", choices=("fuse", "replace"),
                      doc="fuse: motion regions stay, a detection gives the tracks it matches its "
                          "class; replace: the detections are the regions",
                      when={"model": Not("", "onnx:yolo.onnx")})
    start_tracks: bool = param(False, doc="fuse: a detection no motion region matches becomes a "
                                          "region too (it can start a track)",
                               when={"mode": "fuse"})
    match_iou: float = param(0.3, lo=0.0, hi=1.0, doc="IoU at which a detection matches a motion "
                                                      "region or a track",
                             when={"model": Not("", "onnx:yolo.onnx")})
    vote: int = param(5, lo=1, hi=1000, doc="votes a matched detection casts for its class "
                                            "(classes.enabled)",
                      when={"model": Not("", "onnx:yolo.onnx")})
