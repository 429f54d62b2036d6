"""Heat maps of where tracks spent time: heatmap.png over a background, heatmap_world.png in
metres (analyze and track --scene)."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from motiontrack.analytics import parse_scene
from motiontrack.analytics.heatmap import HeatGrid, WorldHeat, anchor_points, world_extent
from motiontrack.calibrate.ground import GroundHomography
from motiontrack.cli import main
from motiontrack.render.heatmap import COLORMAP, grid_step, smooth
from motiontrack.run.analyze import analyze_tracks
from motiontrack.run.folder import RunFolder
from motiontrack.run.heatmaps import HeatmapWriter, image_sigma_px
from motiontrack.types import Annotations

SCENE = parse_scene({"line": [{"name": "g", "points": [[0, 100], [200, 100]]}]})


def _tracks(rows) -> Annotations:
    """rows of (frame, id, x, y, w, h)."""
    a = np.array(rows, dtype=float).reshape(-1, 6)
    return Annotations.from_columns(a[:, 0], a[:, 1], a[:, 2:6])


def _stand_and_walk(frames: int = 30) -> Annotations:
    # track 1 stands still with its feet at (120, 80); track 2 walks along y = 150 from x = 10
    rows = []
    for f in range(1, frames + 1):
        rows.append((f, 1, 110, 40, 20, 40))
        rows.append((f, 2, 10 + 6 * f - 5, 110, 10, 40))
    return _tracks(rows)


def _top_color() -> np.ndarray:
    """The colour map's colour of the most visited place, laid at 75 % over black."""
    top = cv2.applyColorMap(np.full((1, 1), 255, np.uint8), COLORMAP)[0, 0].astype(float)
    return np.round(0.75 * top)


def test_anchor_points_are_feet_or_centre():
    boxes = np.array([[10, 20, 30, 40]], float)
    assert anchor_points(boxes).tolist() == [[25.0, 60.0]]
    assert anchor_points(boxes, "center").tolist() == [[25.0, 40.0]]
    assert anchor_points(np.zeros((0, 4))).shape == (0, 2)


def test_grid_counts_visits_per_pixel_and_drops_points_outside():
    g = HeatGrid(4, 3)
    g.add(np.array([[0.0, 0.0], [3.99, 2.5], [3.99, 2.5], [4.0, 1.0], [-0.1, 1.0],
                    [np.nan, 1.0]]))
    assert g.counts[0, 0] == 1 and g.counts[2, 3] == 2 and g.counts.sum() == 3
    assert g.visits == 3 and g.outside == 2     # x = 4 is past the last column; x < 0
    g.add(np.zeros((0, 2)))
    assert g.visits == 3


def test_a_track_standing_still_makes_the_hottest_pixel_at_its_anchor(tmp_path):
    summary = analyze_tracks(_stand_and_walk(), SCENE, 10.0, tmp_path, size=(240, 200))
    img = cv2.imread(str(tmp_path / "heatmap.png"))
    assert img.shape == (200, 240, 3)
    # 30 visits at one pixel against one visit per pixel along the walk
    grid = HeatGrid(240, 200)
    for f in range(30):
        grid.add(np.array([[120.0, 80.0], [10 + 6 * (f + 1), 150.0]]))
    density = smooth(grid.counts, image_sigma_px(240, 200))
    assert np.unravel_index(np.argmax(density), density.shape) == (80, 120)
    # on black, the anchor's pixel takes the colour map's top colour at full opacity
    assert np.abs(img[80, 120].astype(float) - _top_color()).max() <= 1
    assert not img[5, 230].any()                       # far from any track: the background
    assert summary["heatmap"]["visits"] == 60 and summary["heatmap"]["background"] == "none"


def test_heatmap_is_drawn_over_the_background_given(tmp_path):
    bg = np.full((200, 240, 3), (30, 90, 150), np.uint8)
    analyze_tracks(_stand_and_walk(), SCENE, 10.0, tmp_path, size=(240, 200), background=bg)
    img = cv2.imread(str(tmp_path / "heatmap.png"))
    assert tuple(img[195, 5]) == (30, 90, 150)         # untouched where nobody went
    assert tuple(img[80, 120]) != (30, 90, 150)


def test_heatmap_size_follows_the_frames_the_folder_states(tmp_path):
    tracks = tmp_path / "seq" / "gt" / "gt.txt"
    tracks.parent.mkdir(parents=True)
    tracks.write_text("1,1,10,10,20,40,1,-1,-1,-1\n2,1,12,10,20,40,1,-1,-1,-1\n")
    assert RunFolder.beside(tracks).frame_size() is None
    (tmp_path / "seq" / "seqinfo.ini").write_text(
        "[Sequence]\nname=seq\nframeRate=12\nseqLength=2\nimWidth=320\nimHeight=180\n")
    assert RunFolder.beside(tracks).frame_size() == (320, 180)
    assert RunFolder.beside(tracks).frame_rate() == 12.0
    scene = tmp_path / "s.toml"
    scene.write_text("[[line]]\nname = 'g'\npoints = [[0, 100], [200, 100]]\n")
    assert main(["analyze", str(tracks), "--scene", str(scene), "-o", str(tmp_path / "a")]) == 0
    assert cv2.imread(str(tmp_path / "a" / "heatmap.png")).shape == (180, 320, 3)
    # a track run's summary.json names its frame size
    run = tmp_path / "run"
    run.mkdir()
    (run / "tracks.txt").write_text(tracks.read_text())
    (run / "summary.json").write_text(json.dumps({"width": 64, "height": 48, "source_fps": 5}))
    assert RunFolder.beside(run / "tracks.txt").frame_size() == (64, 48)


def test_heatmap_without_a_stated_size_covers_the_tracks(tmp_path):
    analyze_tracks(_tracks([(1, 1, 10, 10, 20, 40), (2, 1, 50.5, 30, 20, 40)]), SCENE, 5.0,
                   tmp_path)
    assert cv2.imread(str(tmp_path / "heatmap.png")).shape == (70, 71, 3)   # ceil(70.5) wide


def test_analyze_video_draws_over_the_median_of_its_frames(tmp_path, capsys):
    frames = tmp_path / "frames"
    frames.mkdir()
    for k in range(9):
        img = np.full((48, 64, 3), 100, np.uint8)
        img[10:20, 5 * k:5 * k + 5] = 255              # someone walking through
        cv2.imwrite(str(frames / f"{k:04d}.png"), img)
    tracks = tmp_path / "tracks.txt"
    tracks.write_text("1,1,40,2,4,8,1,-1,-1,-1\n")
    scene = tmp_path / "s.toml"
    scene.write_text("[[line]]\nname = 'g'\npoints = [[0, 30], [60, 30]]\n")
    out = tmp_path / "o"
    assert main(["analyze", str(tracks), "--scene", str(scene), "--fps", "5", "--video",
                 str(frames), "-o", str(out)]) == 0
    img = cv2.imread(str(out / "heatmap.png"))
    assert img.shape == (48, 64, 3)
    assert tuple(img[15, 2]) == (100, 100, 100)         # the walker is gone from the median
    summary = json.loads((out / "summary.json").read_text())
    assert summary["heatmap"]["background"] == "given"
    assert "heatmap" in summary["outputs"]


def test_world_cells_and_extent():
    w = WorldHeat(0.5)
    w.add(np.array([[0.1, 0.1], [0.2, 0.3], [-0.1, 2.6], [np.nan, 1.0]]))
    centres, visits = w.points()
    assert sorted(zip(map(tuple, centres.tolist()), visits.tolist())) == [
        ((-0.25, 2.75), 1.0), ((0.25, 0.25), 2.0)]
    # the extent of the cells' centres plus 1 m, out to whole metres
    assert world_extent(centres) == (-2.0, 2.0, -1.0, 4.0)
    assert world_extent(np.zeros((0, 2))) == (-5.0, 5.0, -5.0, 5.0)


def test_world_map_covers_the_tracks_extent_in_metres(tmp_path):
    # ground = pixels / 10 with Y up: X = u / 10, Y = -v / 10
    cam = GroundHomography(H=np.array([[0.1, 0, 0], [0, -0.1, 0], [0, 0, 1.0]]))
    tracks = _tracks([(f, 1, 100 + 10 * f, 200, 20, 50) for f in range(1, 31)])
    # feet from (120, 250) to (410, 250): X 12.0 .. 41.0, Y -25.0
    summary = analyze_tracks(tracks, SCENE, 10.0, tmp_path, camera=cam, size=(640, 480))
    world = summary["heatmap"]["world"]
    # cell centres X 12.025 .. 41.025, Y -24.975; ± 1 m, out to whole metres
    assert world["extent_m"] == [11.0, 43.0, -26.0, -23.0]
    assert world["visits"] == 30
    ppm = world["px_per_m"]
    assert ppm == 25.0                                    # 800 px over the 32 m side
    img = cv2.imread(str(tmp_path / "heatmap_world.png"))
    assert img.shape == (2 * 40 + 3 * 25, 2 * 40 + 32 * 25, 3)
    # the path is drawn at Y = -25 m: 2 m below the top of the plot
    row = 40 + int(2 * ppm)
    assert img[row, 40 + int(15 * ppm)].max() > img[40 + 5, 40 + int(15 * ppm)].max()


def test_no_world_map_without_a_camera(tmp_path):
    summary = analyze_tracks(_stand_and_walk(5), SCENE, 10.0, tmp_path, size=(240, 200))
    assert not (tmp_path / "heatmap_world.png").exists() and "world" not in summary["heatmap"]


@pytest.mark.parametrize("span, step", [(3, 1), (20, 1), (21, 2), (40, 2), (41, 5),
                                        (100, 5), (101, 10), (300, 20), (1000, 50)])
def test_world_grid_step_keeps_at_most_twenty_lines(span, step):
    assert grid_step(span) == step


def test_heatmap_writer_refuses_nothing_when_no_tracks(tmp_path):
    w = HeatmapWriter(tmp_path, size=(8, 6))
    w.start(None)
    w.close(True)
    assert cv2.imread(str(tmp_path / "heatmap.png")).shape == (6, 8, 3)
    assert w.info["visits"] == 0


def test_track_scene_writes_heatmap_over_the_motion_background(tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text("[[line]]\nname = 'g'\npoints = [[560, 479], [560, 150]]\n")
    run = tmp_path / "run"
    assert main(["track", "synth:walker?n_frames=40", "--scene", str(scene), "--no-video",
                 "-o", str(run)]) == 0
    summary = json.loads((run / "summary.json").read_text())
    heat = summary["heatmap"]
    assert heat["background"] == "motion background"
    img = cv2.imread(str(run / "heatmap.png"))
    assert img.shape == (summary["height"], summary["width"], 3)
    # one visit per track and frame it was reported in (tracks.txt may add backfilled rows)
    assert 0 < heat["visits"] <= len((run / "tracks.txt").read_text().splitlines())
