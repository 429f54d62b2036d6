"""combined.json scores each video over the frames its own accuracy covers (batch.combined)."""

from __future__ import annotations

import json

from motiontrack.batch.combined import combined_metrics


def _video(folder, summary: dict) -> None:
    folder.mkdir(parents=True)
    # one person annotated in frames 5-10; the tracks follow it there and hold a box elsewhere
    # in frames 1-4, before anyone is annotated
    (folder / "gt.txt").write_text("".join(f"{f},1,10,10,20,40,1,1,1\n" for f in range(5, 11)))
    (folder / "tracks.txt").write_text(
        "".join(f"{f},1,10,10,20,40,1,-1,-1,-1\n" for f in range(5, 11))
        + "".join(f"{f},2,200,10,20,40,1,-1,-1,-1\n" for f in range(1, 5)))
    (folder / "summary.json").write_text(json.dumps(summary))


def test_combined_scores_the_frames_of_each_videos_accuracy(tmp_path):
    # a synthetic scene's run: its accuracy covered all 10 frames, the boxes of frames 1-4 are
    # false positives there and here
    _video(tmp_path / "scene", {"frames": 10, "accuracy": {"frames_scored": [1, 10]}})
    # a run without that record: the frames gt.txt covers, 5-10
    _video(tmp_path / "file", {"frames": 10})
    rows = [{"name": n, "status": "done"} for n in ("scene", "file")]
    assert combined_metrics(tmp_path, rows[:1])["metrics"]["FP"] == 4
    assert combined_metrics(tmp_path, rows[1:])["metrics"]["FP"] == 0
    assert combined_metrics(tmp_path, rows[1:])["metrics"]["MOTA"] == 1.0
