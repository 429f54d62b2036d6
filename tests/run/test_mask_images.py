"""``track --mask-images DIR``: one CDnet-style ``bin%06d.png`` per frame at the source's size,
scored by ``evaluate-masks`` from the command line, under the run layer's output rules."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

import motiontrack
from motiontrack.cli import main
from motiontrack.config import load_config
from motiontrack.errors import InputError
from motiontrack.evaluate.masks import evaluate_masks, read_roi
from motiontrack.io.atomic import DiskFullError, OutputLock, free_bytes
from motiontrack.io.sources import open_source
from motiontrack.io.video import DISK_RESERVE
from motiontrack.run import track_job
from helpers.writers import FailAt
from test_outputs import small_disk  # noqa: F401 (the fixture: a 2 MB file system)

HIGHWAY = "cdnet-highway"
WALKER = "synth:walker?n_frames=12"


def _names(folder):
    return sorted(p.name for p in folder.iterdir()) if folder.exists() else []


def _bins(first, last):
    return [f"bin{f:06d}.png" for f in range(first, last + 1)]


@pytest.mark.data
def test_highway_masks_score_from_the_command_line_as_the_pipeline_masks_do_in_process(
        data, tmp_path, capsys):
    # frames 470-529 (0-based start 469), the pipeline at half size: the images are enlarged back
    source, gt = data(HIGHWAY, "input"), data(HIGHWAY, "groundtruth")
    sets = ["source.start=469", "source.max_frames=60", "preprocess.scale=0.5"]
    argv = ["track", str(source), "-o", str(tmp_path / "run"), "--no-video",
            "--mask-images", str(tmp_path / "masks")]
    for s in sets:
        argv += ["--set", s]
    assert main(argv) == 0
    assert "60 masks in" in capsys.readouterr().out
    assert _names(tmp_path / "masks") == _bins(470, 529)
    for name in ("bin000470.png", "bin000500.png", "bin000529.png"):
        img = cv2.imread(str(tmp_path / "masks" / name), cv2.IMREAD_UNCHANGED)
        assert img.shape == (240, 320) and img.dtype == np.uint8     # the source's size, 1 channel
        assert set(np.unique(img)) <= {0, 255}
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["processing_scale"] == 0.5
    assert summary["mask_images"] == {"folder": str(tmp_path / "masks"), "images": 60,
                                      "first": 470, "last": 529}

    assert main(["evaluate-masks", "--gt", str(gt), "--pred", str(tmp_path / "masks"),
                 "--frames", "470:529", "--json", str(tmp_path / "m.json")]) == 0
    cli = json.loads((tmp_path / "m.json").read_text())

    roi = read_roi(data(HIGHWAY, "ROI.bmp"))
    pairs, shapes = [], set()
    with motiontrack.track(str(source), load_config(None, sets)) as frames:
        for r in frames:
            shapes.add(r.mask.shape)
            pairs.append((r.index + 1,
                          cv2.imread(str(gt / f"gt{r.index + 1:06d}.png"), cv2.IMREAD_GRAYSCALE),
                          cv2.resize(r.mask, (320, 240), interpolation=cv2.INTER_NEAREST)))
    assert [f for f, _, _ in pairs] == list(range(470, 530))
    assert shapes == {(120, 160)}                               # processed at half size
    in_process = evaluate_masks(pairs, roi).as_dict()
    assert {k: cli[k] for k in ("frames", "tp", "fp", "fn", "tn")} == \
        {k: in_process[k] for k in ("frames", "tp", "fp", "fn", "tn")}
    assert cli["frames"] == 60
    assert cli["recall"] > 0.5 and cli["precision"] > 0.5 and cli["pwc"] < 1.0


def test_the_first_image_is_numbered_start_plus_one(tmp_path):
    cfg = load_config(None, ["output.video=false", "source.start=3", "source.max_frames=4"])
    summary = track_job(WALKER, cfg, tmp_path / "o", mask_images=tmp_path / "m").run()
    assert _names(tmp_path / "m") == _bins(4, 7)
    info = open_source(WALKER).info
    img = cv2.imread(str(tmp_path / "m" / "bin000004.png"), cv2.IMREAD_UNCHANGED)
    assert img.shape == (info.height, info.width)
    assert summary.extra["mask_images"]["images"] == 4


def test_mask_images_in_the_run_folder_share_its_lock(tmp_path):
    cfg = load_config(None, ["output.video=false"])
    track_job(WALKER, cfg, tmp_path / "o", mask_images=tmp_path / "o").run()
    assert _names(tmp_path / "o") == sorted(
        [*_bins(1, 12), "config.toml", "gt.txt", "summary.json", "tracks.txt"])


def test_existing_mask_images_are_refused_and_replaced_with_force(tmp_path):
    cfg = load_config(None, ["output.video=false", "source.max_frames=5"])
    masks = tmp_path / "m"
    masks.mkdir()
    (masks / "bin000999.png").write_bytes(b"old")
    (masks / "notes.txt").write_text("mine\n")
    with pytest.raises(InputError, match=r"output exists: .*1 mask image.*--force"):
        track_job(WALKER, cfg, tmp_path / "o", mask_images=masks)
    assert not (tmp_path / "o").exists()
    track_job(WALKER, cfg, tmp_path / "o", mask_images=masks, force=True).run()
    assert _names(masks) == [*_bins(1, 5), "notes.txt"]     # the old run's image is gone


def test_a_mask_folder_in_use_by_another_run_is_refused(tmp_path):
    cfg = load_config(None, ["output.video=false"])
    with OutputLock(tmp_path / "m"):
        with pytest.raises(InputError, match="in use by another motiontrack run"):
            track_job(WALKER, cfg, tmp_path / "o", mask_images=tmp_path / "m").run()
    assert _names(tmp_path / "o") == []


def test_a_failed_run_removes_its_mask_images_and_a_stopped_one_keeps_them(tmp_path):
    cfg = load_config(None, ["output.video=false"])
    job = track_job(WALKER, cfg, tmp_path / "o", mask_images=tmp_path / "m")
    job.writers.append(FailAt(6))
    with pytest.raises(RuntimeError, match="encoder gave up"):
        job.run()
    assert _names(tmp_path / "m") == []                   # no image, no temporary, no lock
    seen = []
    with pytest.raises(KeyboardInterrupt):
        track_job(WALKER, cfg, tmp_path / "o", mask_images=tmp_path / "m").run(
            should_stop=lambda: seen.append(1) or len(seen) == 4)
    assert _names(tmp_path / "m") == _bins(1, 4)
    assert json.loads((tmp_path / "o" / "summary.json").read_text())["mask_images"]["images"] == 4


def test_mask_images_need_motion_masks(tmp_path, capsys):
    det = tmp_path / "det.txt"
    det.write_text("1,-1,10,10,20,40,0.9,-1,-1,-1\n")
    code = main(["track", WALKER, "--detections", str(det), "-o", str(tmp_path / "o"),
                 "--mask-images", str(tmp_path / "m")])
    assert code == 2
    assert "--mask-images needs motion masks" in capsys.readouterr().err
    assert _names(tmp_path) == ["det.txt"]


def test_mask_images_filling_the_disk_go_and_the_tracks_and_summary_stay(small_disk):
    # leave the reserve a video leaves plus a few images: the images stop at the reserve
    filler = small_disk / "filler"
    with open(filler, "wb") as fh:
        fh.write(b"\0" * (free_bytes(small_disk) - DISK_RESERVE - 8192))
    cfg = load_config(None, ["output.video=false"])
    out, masks = small_disk / "o", small_disk / "m"
    with pytest.raises(DiskFullError, match=r"disk full writing .*bin0000\d\d\.png"):
        track_job("synth:walker?n_frames=60", cfg, out, mask_images=masks).run()
    assert not masks.exists()                                # no image, temporary or lock
    assert _names(out) == ["config.toml", "gt.txt", "summary.json", "tracks.txt"]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"].startswith("disk full writing") and 0 < summary["frames"] < 60
    assert summary["mask_images"]["images"] == 0
