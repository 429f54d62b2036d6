"""Configuration: one frozen dataclass per stage, defaults defined once, TOML in and out.

Every field carries its allowed range in its metadata (:func:`~motiontrack.schema.param`, the
mechanism every file schema uses); values are checked when a section is built, so an
out-of-range value is rejected with the range in the message. Unknown keys are errors.
``--set stage.param=value`` on the command line maps onto the same fields through
:func:`apply_overrides`; the options that stand for keys (``--fps``, ``--no-video``, ...) are
listed once in :mod:`motiontrack.config_flags`.
"""

from __future__ import annotations

import dataclasses
import logging
import sys
from dataclasses import dataclass, field, is_dataclass
from pathlib import Path
from typing import Any, Iterable

import tomli_w

from . import schema
from .config_classes import ClassesConfig, DetectorConfig
from .config_section import ConfigSection, section_path, section_paths, set_root  # noqa: F401
from .errors import ConfigError, printable
from .io.atomic import atomic_write_text
from .io.imagesize import DEFAULT_MAX_PIXELS
from .io.tomlfile import parse_toml, read_toml
from .schema import INT_MAX, INT_MIN, Not, Section, param  # noqa: F401 - the config's names too

log = logging.getLogger(__name__)

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = [
    "DEFAULT_MAX_PIXELS",
    "param",
    "Not",
    "SourceConfig",
    "PreprocessConfig",
    "StabilizeConfig",
    "FrameDiffParams",
    "MOG2Params",
    "KNNParams",
    "BGSLibraryParams",
    "VibeParams",
    "MedianParams",
    "CNTParams",
    "GSOCParams",
    "FarnebackParams",
    "MotionConfig",
    "CleanupConfig",
    "RegionsConfig",
    "DetectionsParams",
    "TrackerConfig",
    "OutputConfig",
    "MeasureConfig",
    "PeopleConfig",
    "ClassesConfig",
    "DetectorConfig",
    "PipelineConfig",
    "load_config",
    "save_config",
    "to_dict",
    "from_dict",
    "apply_overrides",
    "warn_if_oversized",
]


class _Section(ConfigSection):
    """A section of the pipeline config (:class:`~motiontrack.config_section.ConfigSection`)."""


# --------------------------------------------------------------------------------------- stages
@dataclass(frozen=True)
class SourceConfig(_Section):
    start: int = param(0, lo=0, doc="first frame index to process (0-based)")
    max_frames: int = param(0, lo=0, doc="stop after this many frames (0 = all)")
    fps: float = param(
        0.0, lo=0.0, hi=1000.0,
        doc="frame rate (frames per second) to use instead of the source's own, for footage "
            "stored at another rate than it was recorded at; every duration in seconds "
            "(tracker.max_lost_s, tracker.fill_gaps_s), the speeds in summary.json and the "
            "output videos follow it; 0 = the source's own (25 when it states none)")
    reconnect_attempts: int = param(
        5, lo=0, hi=1000,
        doc="live sources: reconnect tries before the run fails, counted until a reconnected "
            "stream is stable again (reconnect_reset_frames)")
    reconnect_backoff: float = param(0.5, lo=0.0, hi=60.0, doc="live sources: first back-off (s), doubling")
    reconnect_backoff_max: float = param(8.0, lo=0.0, hi=600.0, doc="live sources: longest back-off (s)")
    reconnect_reset_frames: int = param(
        250, lo=1, hi=1_000_000,
        doc="live sources: frames in a row a reconnected stream must deliver before its reconnect "
            "attempts and back-off start afresh; until then a stream that keeps dropping fails "
            "after reconnect_attempts reconnections in all")
    read_timeout_s: float = param(
        5.0, lo=0.1, hi=600.0,
        doc="streams: longest wait (s) for a connection to open or for the next frame; a stream "
            "silent this long counts as dropped (one reconnect attempt). Cameras keep their "
            "backend's own limit")
    max_pixels: int = param(
        DEFAULT_MAX_PIXELS, lo=1, hi=2**30,
        doc="most pixels (width x height) of a frame: a picture whose header, or a video whose "
            "container, states more is refused before anything is decoded (a run takes about "
            "80 bytes per pixel); at most 2**30, OpenCV's own bound on decoding a picture")


#: smallest explicit processing scale
MIN_SCALE = 0.05


@dataclass(frozen=True)
class PreprocessConfig(_Section):
    grayscale: bool = param(False, doc="detect motion on the gray image (colour keeps clothing contrast)")
    blur: str = param("gaussian", choices=("none", "gaussian", "median"),
                      doc="smoothing of each frame before motion detection")
    blur_kernel: int = param(3, lo=0, hi=51, odd=True, when={"blur": Not("none", "gaussian")},
                             doc="blur kernel size (px at processing scale; 0 or 1 = no blur)")
    scale: float = param(0.0, lo=0.0, hi=1.0,
                         doc="processing scale: detect on a smaller image, boxes reported in original "
                             "pixels; 0 = automatic: 0.5 for frames of 768x576 and larger, up to 1 for "
                             "smaller ones so that about 384x288 pixels are processed")
    roi: str = param("", doc="path to a region-of-interest mask image (non-zero = keep); empty = whole frame")

    def __post_init__(self) -> None:
        super().__post_init__()
        if 0 < self.scale < MIN_SCALE:
            raise ConfigError(f"preprocess.scale must be 0 (automatic) or in [{MIN_SCALE}, 1.0], "
                              f"got {self.scale!r}")


@dataclass(frozen=True)
class StabilizeConfig(_Section):
    """Camera-motion compensation (:mod:`motiontrack.motion.stabilize`): each frame is warped
    into a reference frame before the motion detector, and its mask back into the frame's own
    coordinates."""

    enabled: bool = param(True, doc="compensate a shaking or panning camera; a frame whose "
                                    "measured motion is below min_motion is left as it is")
    features: int = param(60, lo=10, hi=5000, doc="corners of the reference frame followed into "
                                                   "each frame (more is steadier and slower)",
                          when={"enabled": True})
    min_inliers: int = param(12, lo=3, hi=5000,
                             doc="corners that must agree on the camera's motion (RANSAC inliers); "
                                 "a frame with fewer keeps the previous frame's motion, and after "
                                 "10 such frames in a row becomes the reference (the model "
                                 "re-learns); a reference with fewer corners is not followed",
                             when={"enabled": True})
    min_motion: float = param(1.0, lo=0.0, hi=100.0,
                              doc="camera motion (px at processing scale, largest shift of an "
                                  "image corner) below which a frame is not warped: a fixed "
                                  "camera's masks are those without compensation",
                              when={"enabled": True})
    reanchor: float = param(0.1, lo=0.01, hi=0.5,
                            doc="the current frame becomes the reference once the camera has "
                                "moved this fraction of the frame's smaller side from it (a pan); "
                                "the background model is moved with it",
                            when={"enabled": True})


@dataclass(frozen=True)
class FrameDiffParams(_Section):
    threshold: int = param(25, lo=1, hi=255, doc="absolute difference (largest channel) that counts as motion")
    gap: int = param(2, lo=1, hi=100, doc="difference with the frame this many frames back")


def _protect(default: bool):
    """The ``protect`` field of the subtractors that support a selective update."""
    return param(default, doc="selective update: pixels of tracked objects that have moved are not "
                              "learnt, so people who stop stay foreground")


def _shadow_inside():
    """The ``shadow_inside`` field of the subtractors with a shadow test (MOG2, KNN)."""
    return param(True, when={"detect_shadows": True},
                 doc="a shadow pixel with its region's foreground above and below it in its "
                     "column is the object's (a dark sweater, a grey car's roof), not a cast "
                     "shadow (docs/pipeline.md, Shadows)")


def _protect_threshold():
    """The ``protect_threshold`` field that goes with :func:`_protect` (MOG2, KNN)."""
    return param(30, lo=1, hi=255, doc="inside tracked objects (not learnt): difference from the "
                                       "background that counts as foreground",
                     when={"protect": True})


@dataclass(frozen=True)
class MOG2Params(_Section):
    history: int = param(500, lo=1, doc="frames the background model remembers (OpenCV history)")
    var_threshold: float = param(16.0, lo=0.0,
                                 doc="squared Mahalanobis distance from the background model above "
                                     "which a pixel is foreground (OpenCV varThreshold)")
    detect_shadows: bool = param(True, doc="detect shadows and leave them out of the mask (slower)")
    shadow_threshold: float = param(
        0.5, lo=0.0, hi=1.0, when={"detect_shadows": True},
        doc="a shadow is the background darkened to no less than this fraction of its brightness, "
            "its colour kept (OpenCV shadowThreshold); higher where objects are darker copies of "
            "the ground, such as grey cars on asphalt (docs/pipeline.md, Shadows)")
    shadow_inside: bool = _shadow_inside()
    learning_rate: float = param(-1.0, lo=-1.0, hi=1.0, doc="-1 = automatic (1/history)")
    protect: bool = _protect(False)
    protect_threshold: int = _protect_threshold()


@dataclass(frozen=True)
class KNNParams(_Section):
    history: int = param(500, lo=1, doc="frames the background model remembers (OpenCV history)")
    dist2_threshold: float = param(300.0, lo=0.0,
                                   doc="squared colour distance within which a pixel matches a "
                                       "background sample (OpenCV dist2Threshold)")
    detect_shadows: bool = param(True, doc="detect shadows and leave them out of the mask (slower)")
    shadow_threshold: float = param(
        0.5, lo=0.0, hi=1.0, when={"detect_shadows": True},
        doc="a shadow is the background darkened to no less than this fraction of its brightness, "
            "its colour kept (OpenCV shadowThreshold); higher where objects are darker copies of "
            "the ground, such as grey cars on asphalt (docs/pipeline.md, Shadows)")
    vehicle_shadow_threshold: float = param(
        0.7, lo=0.0, hi=1.0, when={"detect_shadows": True},
        doc="shadow_threshold while most of the scene's classified tracks are vehicles (needs "
            "classes.enabled); equal to shadow_threshold to keep one")
    shadow_inside: bool = _shadow_inside()
    learning_rate: float = param(-1.0, lo=-1.0, hi=1.0, doc="-1 = automatic (1/history)")
    n_samples: int = param(7, lo=1, hi=50,
                           doc="samples kept per pixel in each of the model's three time scales "
                               "(fewer is faster: see docs/pipeline.md)")
    knn_samples: int = param(2, lo=1, hi=50,
                             doc="matching samples within dist2_threshold that make a pixel "
                                 "background, at most n_samples")
    protect: bool = _protect(False)
    protect_threshold: int = _protect_threshold()
    hold: bool = param(True, doc="keep people and objects that stop in the mask: inside the boxes "
                                 "of confirmed tracks that have moved and slowed down, pixels the "
                                 "model has learnt stay foreground while they differ from a "
                                 "background that does not learn there; their ghost is dropped "
                                 "when they leave (docs/pipeline.md, The hold); not used with "
                                 "protect")
    hold_threshold: int = param(30, lo=1, hi=255,
                                doc="difference from the hold's background (levels, largest "
                                    "colour channel) that keeps a pixel under a box foreground",
                                when={"hold": True})
    hold_speed: float = param(0.2, lo=0.0, hi=100.0,
                              doc="a track is held while its speed is below this many box heights "
                                  "a second (a walking person is about 0.8; a moving object is "
                                  "whole in the model's own mask)", when={"hold": True})
    accept_s: float = param(180.0, lo=0.0, hi=86400.0,
                            doc="seconds a held pixel stays foreground before it is learnt (a "
                                "parked car); 0 = never", when={"hold": True})
    seed: int = param(0, lo=0, hi=1_000_000,
                      doc="seed of the model's random sample updates: a run repeats exactly for a "
                          "given seed; other seeds show the spread of the scores")

    def __post_init__(self) -> None:
        super().__post_init__()
        check_knn_samples(self.n_samples, self.knn_samples)


@dataclass(frozen=True)
class BGSLibraryParams(_Section):
    """A background model of BGSLibrary (Sobral's C++ library of 43 models, its Python binding
    ``pybgs``: the optional ``bgslibrary`` extra), with our shadow test and hold on its mask."""

    algorithm: str = param("SuBSENSE", doc="the BGSLibrary model by its class name in pybgs "
                                           "(SuBSENSE, PAWCS, LOBSTER, ViBe, ...: `motiontrack "
                                           "list` shows those installed)")
    shadows: bool = param(True, doc="take shadows out of the model's mask: a foreground pixel "
                                    "that is the model's background darkened to shadow_threshold-1 "
                                    "of its brightness, its colour kept, and not inside its "
                                    "region's own foreground (docs/pipeline.md, Shadows)")
    shadow_threshold: float = param(0.5, lo=0.0, hi=1.0, when={"shadows": True},
                                    doc="darkest shadow, as a fraction of the background's "
                                        "brightness")
    hold: bool = param(True, doc="keep people and objects that stop in the mask, as KNN's hold "
                                 "does (docs/pipeline.md, The hold)")
    hold_threshold: int = param(30, lo=1, hi=255, when={"hold": True},
                                doc="difference from the hold's background (levels, largest "
                                    "colour channel) that keeps a pixel under a box foreground")
    hold_speed: float = param(0.2, lo=0.0, hi=100.0, when={"hold": True},
                              doc="a track is held while its speed is below this many box heights "
                                  "a second")
    accept_s: float = param(180.0, lo=0.0, hi=86400.0, when={"hold": True},
                            doc="seconds a held pixel stays foreground before it is learnt; 0 = "
                                "never")


@dataclass(frozen=True)
class VibeParams(_Section):
    """Sample-based background with selective update (ViBe family; docs/pipeline.md)."""

    n_samples: int = param(8, lo=1, hi=64, doc="colour samples kept per pixel")
    min_matches: int = param(2, lo=1, hi=64, doc="samples within radius that make a pixel "
                                                 "background, at most n_samples")
    radius: int = param(20, lo=1, hi=127, doc="largest difference (levels, in every colour "
                                              "channel) between the frame and a matching sample")
    subsampling: int = param(16, lo=1, hi=1000,
                             doc="a background pixel learns with probability 1/subsampling a "
                                 "frame, and as often writes its value into a neighbour's sample "
                                 "(higher is slower to learn)")
    protect: bool = param(True, doc="selective update: pixels of confirmed tracks that have moved, "
                                    "and of static objects, are not learnt, so people who stop "
                                    "stay foreground")
    absorb_s: float = param(10.0, lo=0.0, hi=86400.0,
                            doc="seconds a pixel may stay foreground before it is learnt (what "
                                "stops and is not protected joins the background); 0 = never")
    accept_s: float = param(180.0, lo=0.0, hi=86400.0,
                            doc="the same for protected pixels: something under a track that "
                                "never moves again (a parked car) becomes background after this; "
                                "0 = never",
                            when={"protect": True})
    ghost_ratio: float = param(0.7, lo=0.0, hi=10.0,
                               doc="re-learn at once the foreground components (also under tracks) "
                                   "whose outline has its edges in the model's background rather "
                                   "than in the frame: the place an object left (0 = off)")
    shadows: bool = param(True, doc="leave shadows (a darker copy of the background) out of the "
                                    "mask (colour input)")
    seed: int = param(0, lo=0, hi=1_000_000,
                      doc="seed of the model's random updates: a run repeats exactly for a given "
                          "seed")

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.min_matches > self.n_samples:
            raise ConfigError(f"motion.vibe.min_matches must be at most motion.vibe.n_samples "
                              f"({self.n_samples}), got {self.min_matches}")


def check_knn_samples(n_samples: int, knn_samples: int) -> None:
    """KNN's background vote needs ``1 <= knn_samples <= n_samples`` (the config and the
    detector, which can be built without a config, both check it here)."""
    if not 1 <= knn_samples <= n_samples:
        raise ConfigError(f"motion.knn.knn_samples must be at most motion.knn.n_samples "
                          f"({n_samples}) and at least 1, got {knn_samples}")


@dataclass(frozen=True)
class MedianParams(_Section):
    """Temporal-median background (the Reading People Tracker's motion detector)."""

    threshold: float = param(0.1, lo=0.0, hi=1.0,
                             doc="DETECT_DIFF_THRESH: |frame - background| / 255 above this is motion")
    history: int = param(25, lo=3, hi=255, doc="frames kept for the median")
    update_every: int = param(5, lo=1, doc="sample a frame into the history every N frames")
    protect: bool = _protect(True)


@dataclass(frozen=True)
class CNTParams(_Section):
    min_pixel_stability: int = param(15, lo=1, doc="frames a pixel must stay unchanged to count "
                                                   "as background")
    max_pixel_stability: int = param(15 * 60, lo=1, doc="most frames of stability credited to a "
                                                        "pixel (with use_history)")
    use_history: bool = param(True, doc="credit a pixel for staying stable a long time")
    is_parallel: bool = param(True, doc="update the model on several threads")


@dataclass(frozen=True)
class GSOCParams(_Section):
    n_samples: int = param(20, lo=1, hi=50,
                           doc="samples kept per pixel; each takes about 60 bytes per processed "
                               "pixel")
    replace_rate: float = param(0.003, lo=0.0, hi=1.0, doc="probability of replacing an old "
                                                          "sample: how fast the model adapts")
    propagation_rate: float = param(0.01, lo=0.0, hi=1.0, doc="probability of propagating a "
                                                             "sample to a neighbouring pixel")
    hits_threshold: int = param(32, lo=1, doc="hits a sample needs before it may replace a "
                                              "background sample")


@dataclass(frozen=True)
class GMGParams(_Section):
    initialization_frames: int = param(20, lo=1, doc="frames that build the first background model")
    decision_threshold: float = param(0.8, lo=0.0, hi=1.0,
                                      doc="probability of foreground above which a pixel is motion")


@dataclass(frozen=True)
class FarnebackParams(_Section):
    """Dense optical flow (Farnebäck); flow magnitude above ``threshold`` px/frame is motion."""

    threshold: float = param(0.7, lo=0.0, doc="flow magnitude (px/frame at processing scale)")
    pyr_scale: float = param(0.5, lo=0.1, hi=0.9, doc="image scale from one pyramid level to the "
                                                      "next (0.5 = half size)")
    levels: int = param(3, lo=1, hi=10, doc="pyramid levels, the full-size image included")
    winsize: int = param(15, lo=3, hi=101, doc="averaging window (px): larger is steadier and "
                                               "blurs the edges of motion")
    iterations: int = param(3, lo=1, hi=50, doc="iterations at each pyramid level")
    poly_n: int = param(5, choices=(5, 7), doc="neighbourhood (px) of each pixel's polynomial "
                                               "expansion")
    poly_sigma: float = param(1.1, lo=0.1, hi=3.0, doc="Gaussian std smoothing that neighbourhood "
                                                       "(1.1 for poly_n 5, 1.5 for 7)")


@dataclass(frozen=True)
class MotionConfig(_Section):
    method: str = param("knn", doc="motion detector: see `motiontrack list`")
    warmup: int = param(0, lo=0, doc="frames whose detections are ignored while the model settles")
    ghost_ratio: float = param(0.7, lo=0.0, hi=10.0,
                               doc="drop ghost regions (where a still object left): image gradient "
                                   "along a region's outline in the frame over that in the "
                                   "background below this (0 = off)")
    ghost_pixels: bool = param(True, doc="with the ghost filter on, also take a ghost apart pixel by "
                                         "pixel from its border (a ghost still joined to the person "
                                         "who left it)", when={"ghost_ratio": Not(0.0, 0.7)})
    light_share: float = param(0.8, lo=0.0, hi=1.0,
                               doc="with the ghost filter on, drop a region as light (ground the "
                                   "sun or a lamp brightened) when its mean colour and this share "
                                   "of its pixels show the background 1.02 to light_gain times "
                                   "brighter, alike in every channel (0 = off)",
                               when={"ghost_ratio": Not(0.0, 0.7)})
    light_gain: float = param(1.25, lo=1.0, hi=4.0, doc="brightest gain of the light test",
                              when={"light_share": Not(0.0, 0.8)})
    keep_stopped: bool = param(
        False, doc="keep people who stop walking in the mask: a dual background's static "
                   "foreground (long-term foreground, short-term background) inside the box of a "
                   "track that has moved is added to the motion mask (about 3 ms a frame at "
                   "384x288; see docs/benchmarks.md)")
    relearn_fraction: float = param(
        0.5, lo=0.0, hi=1.0,
        doc="sudden change: when more than this fraction of the frame turns foreground at once, "
            "the background model re-learns the scene (tracks coast through it); 0 = off")
    relearn_brightness: float = param(
        20.0, lo=0.0, hi=255.0,
        doc="sudden change: a jump of the frame's mean brightness (grey levels) from the previous "
            "frame that makes the background model re-learn the scene; 0 = off")
    bootstrap_s: float = param(
        0.0, lo=0.0, hi=600.0,
        doc="seconds after the start (and after each discontinuity) at which the background "
            "model re-learns from the per-pixel median of frames kept over them, so people "
            "standing in the first frame leave no ghost when they walk off; whatever stood "
            "still for half of them is learnt too (0 = off; docs/pipeline.md, The first "
            "background)")
    relearn_frames: int = param(2, lo=1, hi=1000,
                                doc="frames from a sudden change on (that frame included) whose "
                                    "regions are ignored while the model settles (tracks coast); "
                                    "no further change is looked for in them")
    frame_diff: FrameDiffParams = field(default_factory=FrameDiffParams)
    mog2: MOG2Params = field(default_factory=MOG2Params)
    knn: KNNParams = field(default_factory=KNNParams)
    vibe: VibeParams = field(default_factory=VibeParams)
    median: MedianParams = field(default_factory=MedianParams)
    cnt: CNTParams = field(default_factory=CNTParams)
    gsoc: GSOCParams = field(default_factory=GSOCParams)
    gmg: GMGParams = field(default_factory=GMGParams)
    farneback: FarnebackParams = field(default_factory=FarnebackParams)
    bgslibrary: BGSLibraryParams = field(default_factory=BGSLibraryParams)

    def params_for(self, method: str | None = None) -> dict[str, Any]:
        """The parameter section of ``method`` (default: the selected one) as a dict."""
        section = getattr(self, method or self.method, None)
        return dataclasses.asdict(section) if is_dataclass(section) else {}


@dataclass(frozen=True)
class CleanupConfig(_Section):
    """Mask clean-up, applied in this order: median filter, opening (erode), closing (dilate)."""

    median_kernel: int = param(3, lo=0, hi=31, odd=True, doc="median filter on the mask (0 = off)")
    erode_kernel: int = param(3, lo=0, hi=31, doc="square erosion kernel (0 = off)")
    erode_iterations: int = param(1, lo=0, hi=20, doc="erosions in a row (0 = off)",
                                  when={"erode_kernel": Not(0, 3)})
    dilate_kernel: int = param(3, lo=0, hi=31, doc="square dilation kernel (0 = off)")
    dilate_iterations: int = param(2, lo=0, hi=20, doc="fills gaps of about kernel*iterations px",
                                   when={"dilate_kernel": Not(0, 3)})


@dataclass(frozen=True)
class RegionsConfig(_Section):
    """Connected components → regions. Areas are in original-frame pixels.

    ``min_size``/``max_size`` are the thesis' MIN_REGION_SIZE / MAX_REGION_SIZE (fractions of the
    image area); ``min_area``/``max_area`` the same in pixels. All four apply (0 = no limit).
    """

    connectivity: int = param(8, choices=(4, 8), doc="pixels of a region touch by their 4 edges, "
                                                     "or by their 8 edges and corners")
    min_area: float = param(100.0, lo=0.0, doc="minimum region area in pixels")
    max_area: float = param(0.0, lo=0.0, doc="maximum region area in pixels (0 = none)")
    min_size: float = param(0.001, lo=0.0, hi=1.0, doc="MIN_REGION_SIZE, fraction of image area")
    max_size: float = param(0.25, lo=0.0, hi=1.0, doc="MAX_REGION_SIZE, fraction of image area (0 = none)")
    min_hw_ratio: float = param(0.0, lo=0.0, doc="minimum height/width (0 = none)")
    max_hw_ratio: float = param(0.0, lo=0.0, doc="maximum height/width (0 = none)")
    merge_threshold: float = param(0.0, lo=0.0,
                                   doc="REGION_MERGE_THRESH: merge regions whose distance D is below this (0 = off)")
    silhouettes: bool = param(True, doc="the mask reported (masks video, evaluate-masks) is the "
                                        "regions' silhouettes: components too small to be a region "
                                        "left out, holes filled, closed by a 3x3 square among "
                                        "vehicles; false = the mask as cleaned")


@dataclass(frozen=True)
class DetectionsParams(_Section):
    """The detection-driven tracker (``tracker.method = detections``, the ``detections`` preset):
    ByteTrack's two stages by score and OC-SORT's observation-centric steps
    (:mod:`motiontrack.tracking.detections`)."""

    high_score: float = param(0.7, lo=0.0, hi=1.0,
                              doc="detections at or above this score are matched first (stage 1: "
                                  "IoU and direction); those below only continue tracks (stage 2)")
    low_score: float = param(0.1, lo=0.0, hi=1.0,
                             doc="detections below this score are ignored")
    new_score: float = param(0.8, lo=0.0, hi=1.0,
                             doc="an unmatched detection starts a track only from this score")
    min_iou: float = param(0.3, lo=0.0, hi=1.0,
                           doc="gate of stages 1 and 3: IoU below this never matches")
    low_iou: float = param(0.5, lo=0.0, hi=1.0,
                           doc="gate of stage 2 (low-score detections): IoU below this never matches")
    inertia: float = param(0.2, lo=0.0, hi=10.0,
                           doc="weight of the direction-consistency term in stage 1 (OC-SORT OCM; "
                               "0 = off), times the detection's score")
    delta_t: int = param(3, lo=1, hi=100,
                         doc="a track's direction is that of its observations this many frames "
                             "apart (OC-SORT delta_t)")
    recover: bool = param(True, doc="stage 3 (OC-SORT OCR): a track left unmatched may take a "
                                    "detection left over near its last observation")
    reupdate: bool = param(True, doc="a track seen again after a gap re-runs its Kalman filter "
                                     "over a line from its last observation to the new one "
                                     "(OC-SORT ORU) instead of its coasted prediction")
    appearance_weight: float = param(0.0, lo=0.0, hi=10.0,
                                     doc="weight of the colour-histogram (Bhattacharyya) distance "
                                         "in stage 1 when the run has pictures (a video beside "
                                         "--detections); 0 = off")


@dataclass(frozen=True)
class TrackerConfig(_Section):
    method: str = param("kalman", doc="multi-object tracker: see `motiontrack list`")
    cost: str = param("iou", choices=("iou", "center"), doc="association cost",
        when={"method": "kalman"})
    min_iou: float = param(0.1, lo=0.0, hi=1.0, doc="gate: IoU below this never matches (cost=iou)",
                           when={"method": "kalman", "cost": "iou"})
    max_distance: float = param(1.0, lo=0.0,
                                doc="gate: centre distance / predicted box diagonal above this never matches",
        when={"method": "kalman"})
    confirm_hits: int = param(5, lo=1, hi=100, doc="hits needed to turn tentative into confirmed")
    max_lost_s: float = param(2.0, lo=0.0, hi=3600.0,
                              doc="seconds a confirmed track may coast unseen before deletion (converted "
                                  "with the source's frame rate, so it means the same at 10 and 30 fps)")
    position_noise: float = param(0.05, lo=1e-6, hi=10.0,
                                  doc="Kalman process noise std of position/size, fraction of box height")
    velocity_noise: float = param(0.00625, lo=1e-6, hi=10.0,
                                  doc="Kalman process noise std of velocity, fraction of box height per frame")
    measurement_noise: float = param(0.05, lo=1e-6, hi=10.0,
                                     doc="Kalman measurement noise std, fraction of box height")
    partial_ratio: float = param(0.6, lo=0.0, hi=1.0,
                                 doc="a match smaller than this fraction of the prediction's area is a "
                                     "partial view: keep the predicted size, anchor the visible edges (0 = off)",
        when={"method": "kalman"})
    search_growth: float = param(0.05, lo=0.0, hi=10.0,
                                 doc="re-detection window growth per unseen frame (fraction of max_distance)",
        when={"method": "kalman"})
    split_merged: bool = param(True, doc="split a motion blob holding several tracks' predictions "
                                      "into one synthetic measurement per track (people crossing); "
                                      "never applied to --detections boxes (one object each)",
        when={"method": "kalman"})
    absorb_pieces: bool = param(True, doc="the pieces of a tracked object's mask (head, torso, "
                                          "legs of a person who slows down) start no track of "
                                          "their own, and a track lying inside a larger one for "
                                          "half a second ends; off while the scene's tracks are "
                                          "mostly vehicles; never applied to --detections boxes",
                                when={"method": "kalman"})
    coast_frames: int = param(10, lo=0, hi=1000,
                              doc="a lost track coasts at the median pace of its last N steps, not its "
                                  "last Kalman velocity (a fragment at an occluder's edge tilts that); "
                                  "0 = Kalman velocity; never applied to --detections boxes",
        when={"method": "kalman"})
    appearance_weight: float = param(0.5, lo=0.0, hi=10.0,
                                     doc="weight of the colour-histogram (Bhattacharyya) distance in the "
                                         "association cost (0 = no appearance model)",
        when={"method": "kalman"})
    appearance_gate: float = param(0.6, lo=0.0, hi=1.0,
                                   doc="an unseen track is re-identified only below this appearance distance",
                                   when={"method": "kalman", "appearance_weight": Not(0.0, 0.5)})
    bridge: str = param("none", doc="single-object tracker (kcf, csrt, mil, mosse, medianflow, ...) "
                                    "that carries a confirmed track through motion-detection misses; none = off",
        when={"method": "kalman"})
    bridge_frames: int = param(50, lo=1, hi=100000, doc="longest bridge, frames",
                               when={"method": "kalman", "bridge": Not("none", "kcf")})
    history: int = param(64, lo=0, hi=100000, doc="trajectory points kept per track (bounded)")
    output_lost: bool = param(False, doc="report coasting (lost) tracks in tracks.txt",
        when={"method": "kalman"})
    fill_gaps_s: float = param(1.0, lo=0.0, hi=3600.0,
                               doc="when the run ends, fill each track's gaps of up to this many seconds "
                                   "in tracks.txt by linear interpolation (0 = off); tracks from "
                                   "--detections boxes, and from motion with fill_motion")
    backfill: bool = param(True, doc="once a track is confirmed, also report it in the frames where it "
                                     "was tentative (the first confirm_hits - 1); tracks from "
                                     "--detections boxes, and from motion with fill_motion")
    fill_motion: bool = param(False, doc="apply fill_gaps_s and backfill to tracks from motion regions "
                                         "too (off: a motion track's first boxes and the boxes at a "
                                         "gap's ends are often a fragment or a merged blob)")
    detections: DetectionsParams = field(default_factory=DetectionsParams)


@dataclass(frozen=True)
class OutputConfig(_Section):
    video: bool = param(True, doc="write the annotated video")
    codec: str = param("vp80", choices=("vp80", "vp90", "h264", "mp4v", "avc1", "mjpg", "xvid"),
                       doc="codec of the videos written: vp80/vp90 WebM, h264 (plays in browsers)/"
                           "mp4v/avc1 MP4, mjpg/xvid AVI; `motiontrack list` shows those this "
                           "installation encodes (`--codec`)")
    mask_video: bool = param(False, doc="also write the motion mask as a video")
    inset: str = param("none", choices=("none", "top-left", "top-right", "bottom-left", "bottom-right"),
                       doc="corner of the annotated video that shows the motion mask (none = no "
                           "inset: any corner hides where people enter; --mask-video writes the "
                           "mask in full)")
    inset_scale: float = param(0.2, lo=0.05, hi=0.5,
                               doc="width of the mask inset, as a fraction of the frame width")
    legend: bool = param(True, doc="draw a legend of the kinds of boxes in the annotated video")
    trail: int = param(32, lo=0, hi=10000, doc="trail length drawn per track (points)")


@dataclass(frozen=True)
class PeopleConfig(_Section):
    """People stage. Every module can be switched off for ablation studies.

    Lengths are original-frame pixels unless stated otherwise.
    """

    enabled: bool = param(False, doc="run the people stage at all")
    auto_split: bool = param(True, doc="with the stage off: still split merged motion regions between "
                                       "adjacent heads while the scene's regions are upright (people, "
                                       "not cars), searching only regions a third wider than the scene's "
                                       "typical one", when={"enabled": False})
    upright_ratio: float = param(1.5, lo=0.0, hi=100.0,
                                 doc="auto_split: height/width from which a region counts as upright "
                                     "(scene: running mean of each frame's median region)",
                                 when={"auto_split": True, "split": True})
    heads: bool = param(True, doc="detect heads in motion regions (thesis 4.3)",
                        when=({"enabled": True}, {"auto_split": True}))
    split: bool = param(True, doc="split merged regions between adjacent heads (needs heads)",
                        when={"heads": True})
    head_min_width: float = param(6.0, lo=1.0, hi=500.0, doc="narrowest head interval (px)",
                                  when={"heads": True})
    head_max_width: float = param(40.0, lo=1.0, hi=1000.0, doc="widest head interval (px)",
                                  when={"heads": True})
    head_tolerance: float = param(3.0, lo=0.0, hi=100.0, doc="'similar height' tolerance (px)",
                                  when={"heads": True})
    head_min_drop: float = param(4.0, lo=0.0, hi=200.0, doc="neighbours must be this much lower (px)",
                                 when={"heads": True})
    shapes: bool = param(True, doc="active shape tracker on confirmed tracks",
                         when={"enabled": True})
    shape_model: str = param("", doc="shape model .npz (empty = the shipped default)",
                             when={"shapes": True})
    shape_split: bool = param(True, doc="split a merged region between the people in it along their "
                                        "fitted outlines rather than their predicted boxes (needs shapes)",
                              when={"shapes": True})
    hypotheses: bool = param(False, doc="offer the fitted shape's box of a person the motion detector "
                                        "lost to that lost track only (never starts a track)",
                             when={"shapes": True})
    hypothesis_score: float = param(0.5, lo=0.0, hi=1.0, doc="score of shape hypotheses",
                                    when={"hypotheses": True})
    hypothesis_iou: float = param(0.3, lo=0.0, hi=1.0,
                                  doc="a shape box matched to a region at this IoU counts as covered",
                                  when=({"hypotheses": True}, {"refine": True}))
    hypothesis_coast: int = param(2, lo=0, hi=1000,
                                  doc="offer a hypothesis only while the shape found edges within "
                                      "this many frames (a pure prediction is not evidence)",
                                  when={"hypotheses": True})
    hypothesis_agreement: float = param(0.5, lo=0.0, hi=1.0,
                                        doc="offer a hypothesis only for a shape whose box agreed "
                                            "(IoU) this much with its track when last measured",
                                        when={"hypotheses": True})
    border_extend: bool = param(True, doc="a region cut off by the image border is extended past it "
                                          "to its person's fitted outline (needs shapes)",
                                when={"shapes": True})
    border_support: float = param(0.7, lo=0.0, hi=1.0,
                                   doc="fraction of an outline's visible sample points that must find "
                                       "an edge for it to extend a region past the border",
                                  when={"border_extend": True})
    refine: bool = param(False, doc="replace a region's box by the outline box of the well-fitted "
                                   "shape matched to it (tighter boxes)", when={"shapes": True})
    refine_support: float = param(0.7, lo=0.0, hi=1.0,
                                  doc="support a shape needs to refine its region's box",
                                  when={"refine": True})
    samples: int = param(48, lo=8, hi=512, doc="shape sample points along the outline",
                         when={"shapes": True})
    search: float = param(0.12, lo=0.0, hi=1.0, doc="normal search half-length, fraction of height",
                          when={"shapes": True})
    edge_threshold: float = param(8.0, lo=0.0, hi=255.0, doc="weakest difference-image edge (grey levels)",
                                  when={"shapes": True})
    iterations: int = param(2, lo=1, hi=20, doc="measure/solve rounds per frame",
                            when={"shapes": True})
    min_support: float = param(0.35, lo=0.0, hi=1.0, doc="fraction of samples with an edge for a fit",
                               when={"shapes": True})
    max_coast: int = param(25, lo=0, hi=1000, doc="frames a shape may coast without edges",
                           when={"shapes": True})
    hog: str = param("off", choices=("off", "alone", "regions"),
                     doc="HOG people detector: off, whole frame alone, or inside motion regions",
                     when={"enabled": True})
    hog_upscale: float = param(2.0, lo=0.1, hi=8.0, doc="magnification before HOG (people ~96 px)",
                               when={"hog": Not("off", "regions")})
    hog_threshold: float = param(0.0, lo=-10.0, hi=10.0, doc="SVM hit threshold",
                                 when={"hog": Not("off", "regions")})
    hog_every: int = param(1, lo=1, hi=1000, doc="run HOG every N frames (speed)",
                           when={"hog": Not("off", "regions")})


@dataclass(frozen=True)
class MeasureConfig(_Section):
    """Measurements in metres from a calibrated camera (see docs/calibration.md)."""

    camera: str = param("", doc="camera file (PETS/Tsai XML, OpenCV YAML, TOML); empty = pixels only")


@dataclass(frozen=True)
class PipelineConfig(_Section):
    source: SourceConfig = field(default_factory=SourceConfig)
    preprocess: PreprocessConfig = field(default_factory=PreprocessConfig)
    stabilize: StabilizeConfig = field(default_factory=StabilizeConfig)
    motion: MotionConfig = field(default_factory=MotionConfig)
    cleanup: CleanupConfig = field(default_factory=CleanupConfig)
    regions: RegionsConfig = field(default_factory=RegionsConfig)
    tracker: TrackerConfig = field(default_factory=TrackerConfig)
    output: OutputConfig = field(default_factory=OutputConfig)
    measure: MeasureConfig = field(default_factory=MeasureConfig)
    people: PeopleConfig = field(default_factory=PeopleConfig)
    classes: ClassesConfig = field(default_factory=ClassesConfig)
    detector: DetectorConfig = field(default_factory=DetectorConfig)


set_root(PipelineConfig)   # the key paths of the sections, for messages


# ---------------------------------------------------------------------------------- source size
#: the largest frames the defaults are sized for (4K UHD); larger sources get a warning
SIZED_FOR = (3840, 2160)
#: memory of a run with the default configuration: a fixed part plus this much per source pixel
#: (``track`` on 1920x1080, 3840x2160 and 8000x6000 videos: 0.37, 0.90 and 4.0 GB peak)
_RUN_BASE_BYTES = 250e6
_RUN_BYTES_PER_PIXEL = 80


def warn_if_oversized(width: int, height: int, what: str = "source") -> bool:
    """Log a warning when frames of ``width`` x ``height`` are far beyond what the defaults are
    sized for (:data:`SIZED_FOR`), with the memory a run is likely to take; returns whether it
    warned. Call it once per source, when its frame size is known."""
    pixels = int(width) * int(height)
    limit = SIZED_FOR[0] * SIZED_FOR[1]
    if pixels <= limit:
        return False
    gb = (_RUN_BASE_BYTES + _RUN_BYTES_PER_PIXEL * pixels) / 1e9
    log.warning("%s frames are %dx%d (%.1f Mpx), beyond the %dx%d (%.1f Mpx) the defaults are "
                "sized for: expect about %.0f GB of memory and slow processing (lower "
                "preprocess.scale, or resize the video)", printable(what), width, height,
                pixels / 1e6, *SIZED_FOR, limit / 1e6, max(1.0, gb))
    return True


# ------------------------------------------------------------------------------- (de)serialise
def to_dict(cfg: Any) -> dict[str, Any]:
    """Nested plain dict (TOML-ready) of a config dataclass."""
    return dataclasses.asdict(cfg)


def from_dict(cls: type, data: dict[str, Any], where: str = "") -> Any:
    """Build a config dataclass from a nested dict; unknown keys and bad types are errors
    (:func:`motiontrack.schema.from_dict`, the section named by its key path)."""
    return schema.from_dict(cls, data, where or section_paths().get(cls, ""))


def presets() -> dict[str, str]:
    """Shipped presets: name → first comment line (``motiontrack list``)."""
    from importlib import resources   # here: a run without a preset never reads them

    out = {}
    for entry in sorted(resources.files("motiontrack").joinpath("data", "presets").iterdir(),
                        key=lambda e: e.name):
        if entry.name.endswith(".toml"):
            first = entry.read_text(encoding="utf-8").splitlines()[0].lstrip("# ").strip()
            out[entry.name[:-5]] = first
    return out


def _merge(base: dict[str, Any], top: dict[str, Any]) -> dict[str, Any]:
    out = dict(base)
    for k, v in top.items():
        out[k] = _merge(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
    return out


def load_config(path: str | Path | None = None, overrides: Iterable[str] = (),
                preset: str | None = None) -> PipelineConfig:
    """Load the defaults, then a shipped ``preset`` (e.g. ``"people"``), then a TOML config file,
    then ``--set`` overrides; each layer changes only the keys it names."""
    data: dict[str, Any] = {}
    if preset:
        names = presets()
        if preset not in names:
            raise ConfigError(f"unknown preset {preset!r}; valid presets: {', '.join(names)}")
        from importlib import resources

        entry = resources.files("motiontrack").joinpath("data", "presets", f"{preset}.toml")
        data = parse_toml(entry.read_text(encoding="utf-8"), f"preset {preset}")
    if path is not None:
        data = _merge(data, read_toml(path, "config file"))
    cfg = from_dict(PipelineConfig, data)
    return apply_overrides(cfg, overrides)


def _parse_value(text: str) -> Any:
    """A ``--set`` value: a TOML literal (``3``, ``0.5``, ``true``, ``"a"``) or a bare string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text
    except RecursionError:
        raise ConfigError("--set value nested too deeply") from None


def apply_overrides(cfg: Any, overrides: Iterable[str]) -> Any:
    """Apply ``key.path=value`` overrides to a (frozen) config, returning a new one."""
    for item in overrides:
        if "=" not in item:
            raise ConfigError(f"--set expects stage.param=value, got {item!r}")
        key, text = item.split("=", 1)
        path = [k for k in key.strip().split(".") if k]
        if not path:
            raise ConfigError(f"--set expects stage.param=value, got {item!r}")
        cfg = _set_path(cfg, path, _parse_value(text.strip()), key.strip())
    return cfg


def _set_path(obj: Any, path: list[str], value: Any, full: str) -> Any:
    d = to_dict(obj)
    node = d
    for i, k in enumerate(path[:-1]):
        if not isinstance(node.get(k), dict):
            raise ConfigError(f"unknown config key {'.'.join(path[: i + 1])!r} in --set {full}")
        node = node[k]
    if path[-1] not in node or isinstance(node[path[-1]], dict):
        valid = ", ".join(sorted(k for k, v in node.items() if not isinstance(v, dict)))
        raise ConfigError(f"unknown config key {full!r}; valid keys here: {valid}")
    node[path[-1]] = value
    return from_dict(type(obj), d)


def save_config(cfg: Any, path: str | Path) -> None:
    """Write the resolved config as TOML (atomically)."""
    atomic_write_text(Path(path), tomli_w.dumps(to_dict(cfg)))
