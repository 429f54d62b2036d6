"""Each event's snapshot and clip: which frames a clip holds, what a snapshot shows, what the
scene's ``[evidence]`` and a rule's own keys ask for."""

from __future__ import annotations

import numpy as np
import pytest

from motiontrack.analytics.scene import parse_scene
from motiontrack.io.clips import read_clip
from motiontrack.io.event_store import EventStore
from motiontrack.run.evidence import EvidenceKeeper
from motiontrack.types import Box, FrameResult, Track, TrackState

SCENE = {"line": [{"name": "gate", "points": [[0, 50], [100, 50]]}],
         "zone": [{"name": "bench", "polygon": [[0, 0], [50, 0], [50, 50]]}]}


def _picture(n: int) -> np.ndarray:
    """A frame whose grey level says its number (JPEG keeps a flat grey within a few levels)."""
    return np.full((48, 64, 3), (n * 7) % 250, np.uint8)


def _number(frame: np.ndarray, candidates) -> int:
    level = float(frame.mean())
    return min(candidates, key=lambda n: abs((n * 7) % 250 - level))


def _result(n: int) -> FrameResult:
    track = Track(id=3, box=Box(10, 12, 8, 20), state=TrackState.CONFIRMED)
    return FrameResult(index=n - 1, timestamp=0.0, frame=_picture(n), mask=None, regions=(),
                       tracks=(track,))


def _run(tmp_path, scene: dict, events: dict[int, list[dict]], frames: int, fps: float = 25.0):
    keeper = EvidenceKeeper(tmp_path, tmp_path, parse_scene(scene).evidence, fps)
    clips, snaps, ids = {}, {}, 0
    def keep(done):
        clips.update({i: path for i, path, _ in done})
        offsets.update({i: off for i, _, off in done})

    offsets: dict[int, float] = {}
    for n in range(1, frames + 1):
        keep(keeper.frame(n, _picture(n) if keeper.needs_picture(n) else None))
        for e in events.get(n, []):
            ids += 1
            snaps[ids] = keeper.event(ids, {**e, "frame": n}, _result(n), _picture(n))
    keep(keeper.close())
    _run.offsets = offsets
    return clips, snaps


def test_a_clip_holds_the_seconds_before_and_after_its_event(tmp_path):
    scene = {**SCENE, "evidence": {"clip_s": [0.4, 0.8], "clip_fps": 25}}
    clips, snaps = _run(tmp_path, scene, {30: [{"type": "line_cross", "line": "gate", "track": 3}],
                                          95: [{"type": "zone_enter", "zone": "bench", "track": 3}]},
                        frames=100)
    assert clips == {1: "evidence/1.avi", 2: "evidence/2.avi"}
    first, fps = read_clip(tmp_path / clips[1])
    # 0.4 s before (10 frames) to 0.8 s after (20 frames) at 25 fps: frames 20..50
    assert fps == 25.0 and [_number(f, range(1, 101)) for f in first] == list(range(20, 51))
    last, _ = read_clip(tmp_path / clips[2])
    assert [_number(f, range(1, 101)) for f in last] == list(range(85, 101))   # the run ended
    assert snaps == {1: "evidence/1.jpg", 2: "evidence/2.jpg"}
    assert (tmp_path / "evidence" / "1-object.jpg").is_file()


def test_a_device_failing_mid_clip_drops_that_clip_and_keeps_the_next(tmp_path, monkeypatch):
    from motiontrack.io.clips import ClipWriter

    real = ClipWriter.add
    def add(self, jpeg):                     # the device fills while the first clip is written
        if self.path.name == "1.avi" and self.frames == 12:
            raise OSError(28, "No space left on device")
        real(self, jpeg)

    monkeypatch.setattr(ClipWriter, "add", add)
    scene = {**SCENE, "evidence": {"clip_s": [0.4, 0.8], "clip_fps": 25}}
    clips, snaps = _run(tmp_path, scene, {30: [{"type": "line_cross", "line": "gate", "track": 3}],
                                          95: [{"type": "zone_enter", "zone": "bench", "track": 3}]},
                        frames=100)
    assert clips == {2: "evidence/2.avi"} and set(snaps) == {1, 2}
    assert sorted(p.name for p in (tmp_path / "evidence").glob("*.avi")) == ["2.avi"]  # no .part


def test_events_whose_seconds_overlap_share_one_clip(tmp_path):
    scene = {**SCENE, "evidence": {"clip_s": [0.4, 0.8], "clip_fps": 25}}
    clips, _ = _run(tmp_path, scene, {30: [{"type": "line_cross", "line": "gate"}],
                                      40: [{"type": "zone_enter", "zone": "bench"}],
                                      200: [{"type": "line_cross", "line": "gate"}]},
                    frames=240)
    # 30: frames 20..50; 40: 30..60, inside the open clip, which now ends at 60; 200: its own
    assert clips == {1: "evidence/1.avi", 2: "evidence/1.avi", 3: "evidence/3.avi"}
    frames, _ = read_clip(tmp_path / "evidence" / "1.avi")
    assert [_number(f, range(1, 241)) for f in frames] == list(range(20, 61))
    # where each event's own 0.4 s before it starts in the shared clip: frames 20 and 30
    assert _run.offsets == {1: 0.0, 2: 0.4, 3: 0.0}
    assert not (tmp_path / "evidence" / "2.avi").exists()


def test_a_slower_clip_keeps_every_nth_frame_at_its_width(tmp_path):
    scene = {**SCENE, "evidence": {"clip_s": [0.4, 0.4], "clip_fps": 10, "clip_width": 32}}
    clips, _ = _run(tmp_path, scene, {40: [{"type": "line_cross", "line": "gate"}]}, frames=80)
    frames, fps = read_clip(tmp_path / clips[1])
    # 25 fps → every 2nd frame, 12.5 fps; frames 30..50 that are even
    assert fps == 12.5 and [_number(f, range(1, 81)) for f in frames] == list(range(30, 51, 2))
    assert frames[0].shape == (24, 32, 3)


def test_each_rule_may_keep_its_own_evidence(tmp_path):
    scene = {"evidence": {"clip_s": [0.2, 0.2]},
             "line": [{"name": "gate", "points": [[0, 50], [100, 50]], "snapshot": False}],
             "zone": [{"name": "bench", "polygon": [[0, 0], [50, 0], [50, 50]],
                       "clip_s": [0, 0]}]}
    clips, snaps = _run(tmp_path, scene, {10: [{"type": "line_cross", "line": "gate"},
                                               {"type": "zone_enter", "zone": "bench"}]},
                        frames=30)
    assert snaps == {1: None, 2: "evidence/2.jpg"} and set(clips) == {1}


def test_the_object_crop_is_the_tracks_box_with_a_margin(tmp_path):
    import cv2

    keeper = EvidenceKeeper(tmp_path, tmp_path, parse_scene(SCENE).evidence, 25.0)
    image = np.zeros((100, 100, 3), np.uint8)
    for event_id, box in ((1, Box(40, 30, 8, 20)), (2, Box(4, 6, 8, 20))):
        result = FrameResult(index=0, timestamp=0.0, frame=image, mask=None, regions=(),
                             tracks=(Track(id=3, box=box, state=TrackState.CONFIRMED),))
        keeper.event(event_id, {"type": "line_cross", "track": 3, "frame": 1}, result, image)
    # margin max(16, 20 / 4) = 16 on each side: 20 + 32 rows, 8 + 32 columns
    assert cv2.imread(str(tmp_path / "evidence" / "1-object.jpg")).shape[:2] == (52, 40)
    # near the corner the crop stops at the picture's edge: rows 0..42, columns 0..28
    assert cv2.imread(str(tmp_path / "evidence" / "2-object.jpg")).shape[:2] == (42, 28)


def test_a_tracked_run_keeps_each_events_snapshot_and_clip(scene_runs):
    r = scene_runs("runner", 0)
    with EventStore(r.run_dir, readonly=True) as store:
        rows = list(store)
    assert rows
    last = r.summary["frames"]
    for e in rows:
        assert (r.run_dir / e.snapshot).is_file() and e.snapshot == f"evidence/{e.id}.jpg"
    # [evidence] defaults: 5 s before, 10 s after, 10 frames a second at most (every 2nd frame
    # of 25 fps); the runner's events are seconds apart, so they share one clip from 5 s before
    # the first to 10 s after the last (or the run's end)
    assert {e.clip for e in rows} == {f"evidence/{rows[0].id}.avi"}
    frames, fps = read_clip(r.run_dir / rows[0].clip)
    kept = [n for n in range(max(1, rows[0].frame - 125), min(last, rows[-1].frame + 250) + 1)
            if n % 2 == 0]
    assert fps == 12.5 and len(frames) == len(kept)
    for e in rows:   # each event's own seconds start 5 s before it, or at the clip's start
        assert e.clip_offset == pytest.approx((max(kept[0], e.frame - 125) - kept[0]) / 25,
                                              abs=0.041), e


@pytest.mark.slow
def test_a_run_killed_while_it_keeps_clips_leaves_each_clip_whole_and_recorded_or_absent(
        tmp_path):
    import os
    import signal
    import subprocess
    import sys
    import time

    from motiontrack.cli import main

    assert main(["synth-events", "synth:walker?seed=0", "-o", str(tmp_path / "gt")]) == 0
    scene = tmp_path / "scene.toml"   # short clips, so one is written soon after its event
    scene.write_text((tmp_path / "gt" / "scene.toml").read_text()
                     + "\n[evidence]\nclip_s = [1, 1]\nclip_fps = 25\n")
    out = tmp_path / "run"
    proc = subprocess.Popen([sys.executable, "-m", "motiontrack", "-q", "track",
                             "synth:walker?seed=0&n_frames=3000", "--scene", str(scene),
                             "--no-video", "-o", str(out)], stderr=subprocess.DEVNULL)
    try:
        end = time.monotonic() + 60
        while time.monotonic() < end:
            if (out / "events.db").is_file():
                with EventStore(out, readonly=True) as store:
                    if any(e.clip for e in store):
                        break
            time.sleep(0.05)
        else:
            pytest.fail("no clip recorded within 60 s")
    finally:
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(10)
    with EventStore(out, readonly=True) as store:
        rows = list(store)
    assert any(e.clip for e in rows)
    for clip in {e.clip for e in rows if e.clip}:   # recorded: whole, 1 s either side of its
        members = [e.frame for e in rows if e.clip == clip]   # events at 25 fps
        frames, fps = read_clip(out / clip)
        assert fps == 25.0 and len(frames) == max(members) + 25 - (min(members) - 25) + 1, clip
    for e in rows:
        assert e.snapshot is None or (out / e.snapshot).is_file()
    referenced = {e.clip for e in rows if e.clip}
    assert {f"evidence/{p.name}" for p in (out / "evidence").glob("*.avi")} >= referenced
