"""One frame numbering everywhere a run shows or writes a frame (docs/pipeline.md#frame-numbers).

The label drawn on each annotated picture is read from the text the processor hands the drawing
function; the tracks and events of that picture must be those ``tracks.txt`` and
``events.jsonl`` give under the same number.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

import motiontrack.render.scene as render_scene
import motiontrack.render.streams as streams
import motiontrack.run.processors as processors
from motiontrack.config import PipelineConfig
from motiontrack.io.events import read_events
from motiontrack.io.mot import read_mot
from motiontrack.render.annotate import frame_caption
from motiontrack.run import track_job
from motiontrack.types import FIRST_FRAME, FrameResult, frame_number

#: synth:walker at 320x240 enters at the right edge near frame 31 walking left about 1.5 px a
#: frame: its foot point crosses x = 292 (the line, the zone's right edge) near frame 45
SOURCE = "synth:walker?n_frames=60&width=320&height=240"
SCENE = """
[[line]]
name = "gate"
points = [[292, 100], [292, 239]]

[[zone]]
name = "plaza"
polygon = [[200, 100], [292, 100], [292, 239], [200, 239]]
"""


def _number(label: str) -> int:
    word, number = label.split()
    assert word == "frame"
    return int(number)


def test_frame_number_counts_from_one():
    assert FIRST_FRAME == 1
    assert [frame_number(i) for i in (0, 1, 18)] == [1, 2, 19]
    assert frame_caption(18) == "frame 19"


def test_annotated_label_is_the_number_tracks_and_events_give_that_frame(tmp_path, monkeypatch):
    scene = tmp_path / "scene.toml"
    scene.write_text(SCENE, encoding="utf-8")
    drawn: dict[int, list] = {}      # label number -> (id, box) drawn on that picture
    rings: dict[int, list] = {}      # label number -> frames of the events ringed on it
    labels: list[int] = []
    annotate, draw_scene = processors.annotate_frame, render_scene.draw_scene

    def spy_annotate(image, tracks, *args, text="", **kwargs):
        labels.append(_number(text))
        drawn[labels[-1]] = [(t.id, np.round(t.box.as_array(), 2)) for t in tracks]
        return annotate(image, tracks, *args, text=text, **kwargs)

    def spy_scene(img, lines, zones, frame):
        rings[labels[-1]] = [e.frame for e in frame.events] if frame is not None else []
        return draw_scene(img, lines, zones, frame)

    monkeypatch.setattr(processors, "annotate_frame", spy_annotate)
    monkeypatch.setattr(render_scene, "draw_scene", spy_scene)
    cfg = PipelineConfig()
    # frames 0-23 (0-based) skipped: the first picture is frame 25, as the files number it
    cfg = replace(cfg, output=replace(cfg.output, codec="mjpg"),
                  source=replace(cfg.source, start=24))
    track_job(SOURCE, cfg, tmp_path / "run", scene=scene).run()

    assert labels == list(range(25, 61))
    tracks = read_mot(tmp_path / "run" / "tracks.txt")
    shown = 0
    for n, boxes in drawn.items():
        rows = tracks.at(n)
        for tid, box in boxes:   # every track drawn on picture n is tracks.txt's row at frame n
            (k,) = np.flatnonzero(rows.ids == tid)
            np.testing.assert_allclose(rows.boxes[k], box, atol=0.006)
            shown += 1
    assert shown > 10
    events = read_events(tmp_path / "run" / "events.jsonl").events
    assert {e.type for e in events} >= {"line_cross", "zone_enter"}
    ringed = {(n, f) for n, frames in rings.items() for f in frames}
    assert ringed == {(e.frame, e.frame) for e in events}   # each event rings on its own picture


def test_intermediate_annotated_movie_carries_the_same_label(monkeypatch):
    seen = []
    monkeypatch.setattr(streams, "annotate_frame",
                        lambda *a, text="", **k: seen.append(text) or a[0])
    result = FrameResult(index=18, timestamp=0.0, frame=np.zeros((8, 8, 3), np.uint8), mask=None,
                         regions=(), tracks=())
    streams.stream_image("annotated", result)
    assert seen == ["frame 19"]
