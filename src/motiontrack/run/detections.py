"""Tracking public detections without the images: one sequence's ``det.txt`` (``motiontrack
track --detections det.txt`` without a SOURCE) or every sequence of a MOTChallenge split
(``motiontrack track --detections-folder SPLIT``).

A sequence's frame count, size and rate come from its ``seqinfo.ini`` (beside ``det.txt`` or in
the folder above: ``SEQ/seqinfo.ini``, ``SEQ/det/det.txt``), or from the options ``--size WxH``
and ``--fps``, which take precedence. The frames are a
:class:`~motiontrack.io.pictureless.PicturelessSource`: the run is the pipeline's with external
detections, frame by frame, as with a video.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from ..config import PipelineConfig, save_config
from ..errors import ConfigError, InputError, location
from ..io.atomic import writing_outputs
from ..io.mot import read_mot, read_seqinfo, write_mot
from ..io.mot_layout import detection_files, seqinfo_for
from ..io.pictureless import PicturelessSource
from ..pipeline import fill_gap_frames, run
from ..tracking.gaps import fill_gaps
from ..types import Annotations, frame_number

__all__ = ["DetectionsSequence", "detections_sequence", "read_detections",
           "pictureless_source", "track_detections", "track_split"]


@dataclass(frozen=True)
class DetectionsSequence:
    """What a run of one sequence's detections needs besides them: its name, frame size,
    frame rate (None = unknown) and number of frames."""

    name: str
    width: int
    height: int
    fps: float | None
    frames: int


def _whole(info: dict, key: str) -> int | None:
    v = info.get(key)
    return v if isinstance(v, int) and v >= 1 else None


def read_detections(path: str | Path, min_score: float | None = None) -> Annotations:
    """A MOTChallenge ``det.txt`` (score in column 7), without the rows below ``min_score``."""
    det = read_mot(path, kind="det")
    return det.select(det.scores >= min_score) if min_score is not None else det


def detections_sequence(det_path: str | Path, det: Annotations,
                        size: tuple[int, int] | None = None,
                        fps: float | None = None) -> DetectionsSequence:
    """The sequence of the detections ``det`` read from ``det_path``: ``size`` and ``fps`` when
    given, else its ``seqinfo.ini``'s ``imWidth`` x ``imHeight`` and ``frameRate``; the frame
    count is ``seqLength``, or without a ``seqinfo.ini`` the last frame of ``det``.

    Raises
    ------
    ConfigError
        No size: neither ``size`` nor a ``seqinfo.ini`` with ``imWidth`` and ``imHeight``.
    InputError
        A detection beyond the sequence's ``seqLength``, or no detections and no length.
    """
    path = Path(det_path)
    ini = seqinfo_for(path)
    info = read_seqinfo(ini) if ini is not None else {}
    if size is None:
        w, h = _whole(info, "imwidth"), _whole(info, "imheight")
        if w is None or h is None:
            where = (f"{location(ini)} states no imWidth/imHeight" if ini is not None else
                     f"no seqinfo.ini beside {location(path)} or in the folder above")
            raise ConfigError(f"{where}: give the frame size with --size WxH (and --fps)")
        size = (w, h)
    if fps is None:
        rate = info.get("framerate")
        fps = float(rate) if isinstance(rate, (int, float)) and rate > 0 else None
    last = int(det.frames.max()) if len(det) else 0
    frames = _whole(info, "seqlength")
    if frames is not None and last > frames:
        raise InputError(f"{location(path)}: detection at frame {last}, beyond the sequence's "
                         f"seqLength {frames} ({location(ini)})")
    if frames is None and not last:
        raise InputError(f"{location(path)}: no detections, and no seqinfo.ini states the "
                         "sequence's length")
    name = info.get("name") if isinstance(info.get("name"), str) else None
    if not name:
        name = path.parent.parent.name if path.parent.name == "det" else path.stem
    return DetectionsSequence(name, size[0], size[1], fps, frames or last)


def pictureless_source(seq: DetectionsSequence, cfg: PipelineConfig) -> PicturelessSource:
    """The frames of ``seq`` without pictures, from ``source.start`` for ``source.max_frames``,
    at ``source.fps`` when it is set."""
    sc = cfg.source
    return PicturelessSource(seq.name, seq.width, seq.height, sc.fps or seq.fps, seq.frames,
                             sc.start, sc.max_frames)


def track_detections(seq: DetectionsSequence, det: Annotations,
                     cfg: PipelineConfig) -> Annotations:
    """The tracks ``motiontrack track`` writes for the detections ``det`` of ``seq``: each
    frame's tracks, the tentative frames of the tracks confirmed later (``tracker.backfill``)
    and the gaps of up to ``tracker.fill_gaps_s`` filled (1-based frames)."""
    src = pictureless_source(seq, cfg)
    rows: list[tuple] = []
    with run(src, cfg, detections=det) as frames:
        for r in frames:
            rows.extend((frame_number(f), t.id, *t.box.as_array().tolist()) for f, t in r.reported)
    a = np.array(rows, np.float64).reshape(-1, 6)
    tracks = Annotations.from_columns(a[:, 0].astype(np.int64), a[:, 1].astype(np.int64),
                                      a[:, 2:6])
    return fill_gaps(tracks, fill_gap_frames(cfg, src.info.fps, True))


def track_split(split: str | Path, out_dir: str | Path, cfg: PipelineConfig, *,
                size: tuple[int, int] | None = None, fps: float | None = None,
                min_score: float | None = None, force: bool = False,
                done: Callable[[str, Annotations], None] | None = None) -> list[Path]:
    """Every sequence of the split (``<SEQ>/det/det.txt``) tracked into ``out_dir/<SEQ>.txt``,
    the layout ``motiontrack evaluate --trackers-folder`` reads in ``TRACKERS/<name>/data``,
    and the resolved config as ``out_dir/config.toml``. Every input is read and checked before
    anything is written; existing outputs are refused without ``force``. ``done(name, tracks)``
    is called after each sequence. Returns the files written."""
    out = Path(out_dir)
    work = []
    for name, path in detection_files(split):
        det = read_detections(path, min_score)
        work.append((name, det, detections_sequence(path, det, size, fps)))
    targets = [out / f"{name}.txt" for name, _, _ in work]
    out.mkdir(parents=True, exist_ok=True)
    with writing_outputs([*targets, out / "config.toml"], force):
        for target, (name, det, seq) in zip(targets, work):
            tracks = track_detections(seq, det, cfg)
            write_mot(tracks, target)
            if done is not None:
                done(name, tracks)
        save_config(cfg, out / "config.toml")
    return targets
