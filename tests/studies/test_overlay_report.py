"""Overlays (ground truth and runs in distinct colours), figures and the HTML report."""

from __future__ import annotations

import re

import numpy as np
import pytest

from motiontrack.config import load_config
from motiontrack.errors import ConfigError
from motiontrack.studies.sweep import run_sweep, study_from_args
from motiontrack.io.sources import ArraySource
from motiontrack.render.overlay import GT_COLOR, PALETTE, draw_overlay
from motiontrack.run import overlay_job

from helpers import ann


def test_draw_overlay_colours_and_legend():
    img = np.zeros((100, 120, 3), np.uint8)
    layers = [("ground truth", GT_COLOR, np.array([[40.0, 60, 20, 20]]), np.array([1])),
              ("run a", PALETTE[0], np.array([[90.0, 70, 10, 10]]), np.array([7]))]
    out = draw_overlay(img, layers, legend=False)
    assert img.max() == 0                                   # input not modified
    assert tuple(out[60, 50]) == GT_COLOR                   # top edge of the gt box
    assert tuple(out[70, 95]) == PALETTE[0]                 # top edge of the run's box
    assert tuple(out[5, 5]) == (0, 0, 0)                    # no legend asked for
    with_legend = draw_overlay(img, layers, legend=True)
    corner = with_legend[:50, :80].reshape(-1, 3)   # the legend, away from the boxes
    assert (corner == GT_COLOR).all(axis=1).any()           # legend swatch of the gt colour
    assert (corner == PALETTE[0]).all(axis=1).any()


def _legend_rows(w, h):
    """Rows (px) the one-line legend of a single layer covers on a black frame."""
    img = np.zeros((h, w, 3), np.uint8)
    out = draw_overlay(img, [("run a", PALETTE[0], np.zeros((0, 4)), np.zeros(0))])
    rows = np.flatnonzero((out[:, : w // 2] == PALETTE[0]).all(axis=2).any(axis=1))
    return rows.max() - rows.min() + 1


def test_overlay_text_is_as_tall_relative_to_the_frame_at_320x240_and_1920x1080():
    small, large = _legend_rows(320, 240) / 240, _legend_rows(1920, 1080) / 1080
    assert small == pytest.approx(large, rel=0.25)


def test_palette_is_distinct():
    assert len(set(PALETTE)) == len(PALETTE) and GT_COLOR not in PALETTE


def test_render_overlay_video_and_pngs(tmp_path):
    frames = [np.full((48, 64, 3), 40 + 10 * i, np.uint8) for i in range(6)]
    gt = ann([(f, 1, 5 + f, 5, 10, 20) for f in range(1, 7)])
    run = ann([(f, 3, 6 + f, 6, 10, 20) for f in range(2, 7)])
    job = overlay_job(ArraySource(frames, fps=10), tmp_path / "ov.avi", [("run", run)], gt,
                      first=2, last=5, png_frames=[3, 9], codec="mjpg")
    res = job.run()
    assert res.frames == 4                                  # frames 2..5
    assert (tmp_path / "ov.avi").stat().st_size > 0
    assert sorted(p.name for p in tmp_path.glob("*.png")) == ["frame_000003.png"]
    assert not (tmp_path / "summary.json").exists()
    import cv2

    still = cv2.imread(str(tmp_path / "frame_000003.png"))
    assert tuple(still[5, 5 + 3 + 5]) == GT_COLOR           # gt box of frame 3, top edge


def test_render_overlay_needs_an_output(tmp_path):
    with pytest.raises(ConfigError):
        overlay_job(ArraySource([np.zeros((8, 8, 3), np.uint8)]), None, [])


def test_cli_overlay(tmp_path):
    from motiontrack.cli import main

    pred = tmp_path / "r001" / "walker" / "tracks.txt"
    pred.parent.mkdir(parents=True)
    pred.write_text("5,1,100,100,30,60,1,-1,-1,-1\n")
    code = main(["-q", "overlay", "synth:walker?n_frames=8", "--pred", str(pred),
                 "--pred", f"other={pred}", "-o", str(tmp_path / "ov.avi"), "--png-frames", "5"])
    assert code == 0
    assert (tmp_path / "ov.avi").is_file() and (tmp_path / "frame_000005.png").is_file()


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("study")
    manifest = out.parent / "sequences.toml"
    manifest.write_text('[[sequence]]\nsource = "synth:walker?n_frames=30"\ngroup = "single"\n'
                        '[[sequence]]\nsource = "synth:crossing?n_frames=30"\ngroup = "crossing"\n')
    st = study_from_args([], None, ["motion.median.threshold=0.05,0.2"],
                         load_config(None, ["motion.method=median", "output.codec=mjpg"]),
                         manifest=manifest, save=("annotated",))
    run_sweep(st, out)
    return out


@pytest.mark.slow
def test_single_parameter_figures(study):
    for stem in ("pr_regions", "pr_tracks", "tracking"):
        assert (study / "figures" / f"{stem}.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        svg = (study / "figures" / f"{stem}.svg").read_text()
        assert "<svg" in svg
    svg = (study / "figures" / "pr_regions.svg").read_text()
    # several sequences: both names, one average per group and the thick overall average
    for label in ("walker", "crossing", "average single", "average crossing", ">average<", "y = x"):
        assert label in svg, label


@pytest.mark.slow
def test_report_is_self_contained(study, tmp_path):
    from motiontrack.cli import main

    out = tmp_path / "report.html"
    assert main(["-q", "report", str(study), "-o", str(out)]) == 0
    html = out.read_text()
    assert html.startswith("<!DOCTYPE html>")
    # pr_regions, pr_tracks, tracking: SVG images (no SVG markup in the page, where it could run)
    assert html.count('src="data:image/svg+xml;base64,') == 3 and "<svg" not in html
    # nothing fetched from elsewhere: no external scripts, styles, images or fonts
    assert not re.search(r'<(script|link)\b', html)
    assert not re.search(r'(src|href)="(https?:)?//', html)
    for text in ("motion.median.threshold", "walker", "crossing", "xi", "motiontrack", "opencv",
                 "HOTA", "det_pixel_recall", "preprocess.scale"):
        assert text in html, text
    # links to the annotated clips, relative to the report
    links = re.findall(r'href="([^"]+\.avi)"', html)
    assert len(links) == 2 * 2
    assert all((out.parent / link).resolve().is_file() for link in links)


def test_report_of_a_non_study_folder_is_an_error(tmp_path, capsys):
    from motiontrack.cli import main

    assert main(["report", str(tmp_path)]) != 0
    assert "not a sweep output folder" in capsys.readouterr().err


def test_cli_overlay_takes_a_glob_of_runs_as_one_run_per_file(tmp_path, monkeypatch):
    import motiontrack.run
    from motiontrack.cli import main

    for run in ("r001", "r002", "r010"):
        pred = tmp_path / run / "walker" / "tracks.txt"
        pred.parent.mkdir(parents=True)
        pred.write_text("5,1,100,100,30,60,1,-1,-1,-1\n")
    given = []

    def overlay_job(source, out, runs, gt, **kw):
        given.extend(name for name, _ in runs)
        raise KeyboardInterrupt   # what was asked is all this test needs

    monkeypatch.setattr(motiontrack.run, "overlay_job", overlay_job)
    code = main(["-q", "overlay", "synth:walker?n_frames=8", "--pred",
                 str(tmp_path / "r*" / "walker" / "tracks.txt"), "--pred",
                 f"mine={tmp_path / 'r001' / 'walker' / 'tracks.txt'}", "-o",
                 str(tmp_path / "ov.avi")])
    assert code == 130
    assert given == ["r001/walker", "r002/walker", "r010/walker", "mine"]
