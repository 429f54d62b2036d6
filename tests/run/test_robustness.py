"""Bad input to every command: one clear line on stderr, a non-zero exit, never a traceback;
interrupted commands keep what they finished; outputs are never overwritten without --force."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from motiontrack.cli import main


@pytest.fixture
def files(tmp_path):
    """Small broken inputs of every kind."""
    f = {}
    f["empty"] = tmp_path / "empty.txt"
    f["empty"].write_text("")
    f["text"] = tmp_path / "notes.avi"
    f["text"].write_text("this is not a video\n" * 100)
    f["csv_bad"] = tmp_path / "bad.txt"
    f["csv_bad"].write_text("1,1,10,10,5,5,1\n2,1,ten,10,5,5,1\n")
    f["csv_ok"] = tmp_path / "ok.txt"
    f["csv_ok"].write_text("1,1,10,10,5,5,1,-1,-1,-1\n2,1,11,10,5,5,1,-1,-1,-1\n")
    f["xml_bad"] = tmp_path / "bad.xml"
    f["xml_bad"].write_text("<dataset><frame number='0'><objectlist><object id='1'><box xc='1'/>")
    f["xxe"] = tmp_path / "xxe.xml"
    f["xxe"].write_text('<?xml version="1.0"?><!DOCTYPE d [<!ENTITY x SYSTEM "file:///etc/passwd">]>'
                        "<dataset>&x;</dataset>")
    f["json_bad"] = tmp_path / "bad.json"
    f["json_bad"].write_text('{"format": "motiontrack", "version": 1, "tracks": [')
    f["missing"] = tmp_path / "missing.avi"
    f["out"] = tmp_path / "out"
    return f


CASES = [
    # (command line with {placeholders}, expected words in the message)
    ("track {missing}", "not found"),
    ("track {empty}", "empty"),
    ("track {text}", "video"),
    ("track synth:walker?n_frames=5 --set motion.method=nope", "unknown motion detector"),
    ("track synth:walker?n_frames=5 --set preprocess.scale=-1", "must be in"),
    ("track synth:walker?n_frames=5 --set preprocess.scale=0.01", "0 (automatic) or in"),
    ("track synth:walker?n_frames=5 --set tracker.min_iou=2", "must be in"),
    ("track synth:walker?n_frames=5 --gt {csv_bad}", "non-numeric"),
    ("track synth:walker?n_frames=5 --config {csv_ok}", "config"),
    ("evaluate --gt {missing} --pred {csv_ok}", "not found"),
    ("evaluate --gt {csv_bad} --pred {csv_ok}", "non-numeric"),
    ("evaluate --gt {xml_bad} --pred {csv_ok}", "xml"),
    ("evaluate --gt {xxe} --pred {csv_ok}", "unsafe"),
    ("evaluate --gt {json_bad} --pred {csv_ok}", "json"),
    ("evaluate --gt {csv_ok} --pred {csv_ok} --metrics nope", "unknown metric"),
    ("evaluate --gt {csv_ok} --pred {csv_ok} --xi 3", "--xi"),
    ("evaluate-masks --gt {missing} --pred {out}", "not"),
    ("world --camera {missing} {csv_ok} -o {out}/w.txt", "not found"),
    ("world --camera {xml_bad} {csv_ok} -o {out}/w.txt", ""),
    ("calibrate chessboard {text} --pattern 9x6 --square 0.025 -o {out}/c.yml", ""),
    ("follow {missing} --box 1,2,3,4", "not found"),
    ("follow synth:walker?n_frames=5 --box 1,2,-3,4", "box"),
    ("follow synth:walker?n_frames=5 --box 1,2,3,4 --tracker nope", "nope"),
    ("flow {missing}", "not found"),
]


@pytest.mark.parametrize("line, words", CASES)
def test_bad_input_gives_one_line_and_nonzero_exit(files, capsys, line, words):
    args = line.format(**{k: str(v) for k, v in files.items()}).split()
    code = main(args + (["-o", str(files["out"])] if args[0] in ("track", "follow", "flow")
                        and "-o" not in args else []))
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    errors = [ln for ln in err if "error" in ln]
    assert code not in (0, None), line
    assert "Traceback" not in "\n".join(err)
    assert len(errors) == 1, err
    assert words.lower() in errors[0].lower(), errors[0]


def test_debug_shows_the_traceback(files, capsys):
    code = main(["--debug", "evaluate", "--gt", str(files["csv_bad"]), "--pred", str(files["csv_ok"])])
    assert code != 0
    assert "Traceback" in capsys.readouterr().err


def test_evaluate_interrupted_writes_nothing_half_done(files, monkeypatch, capsys):
    import motiontrack.cli.evaluate as ev

    def boom(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(ev, "evaluate_one", boom)
    out = files["out"].with_suffix(".json")
    code = main(["evaluate", "--gt", str(files["csv_ok"]), "--pred", str(files["csv_ok"]),
                 "--json", str(out)])
    assert code == 130
    assert not out.exists()
    assert "interrupted" in capsys.readouterr().err


@pytest.mark.parametrize("flag", ["--json"])
def test_evaluate_keeps_existing_outputs_without_force(files, capsys, flag):
    out = Path(str(files["out"]) + ".json")
    out.write_text("keep me")
    base = ["evaluate", "--gt", str(files["csv_ok"]), "--pred", str(files["csv_ok"]), flag, str(out)]
    assert main(base) == 2
    assert out.read_text() == "keep me"
    assert main(base + ["--force"]) == 0
    assert json.loads(out.read_text())["MOTA"] == 1.0


def test_truncated_video_finishes_cleanly_with_what_decoded(data, tmp_path, capsys):
    video = data("pets09-s2l1", "video.avi")
    cut = tmp_path / "cut.avi"
    cut.write_bytes(video.read_bytes()[:400_000])
    out = tmp_path / "o"
    assert main(["track", str(cut), "-o", str(out), "--codec", "mjpg"]) == 0
    assert "truncated" in capsys.readouterr().err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["truncated"] is True and summary["interrupted"] is False
    assert 5 < summary["frames"] < 300
    import cv2

    cap = cv2.VideoCapture(str(out / "annotated.avi"))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == summary["frames"]


def test_stream_failing_midway_keeps_outputs_and_fails(tmp_path, capsys):
    """A camera that drops and never comes back: outputs hold every frame, exit is non-zero."""
    import itertools

    import numpy as np

    from motiontrack.config import load_config
    from motiontrack.errors import SourceError
    from motiontrack.io.sources import LiveSource
    from motiontrack.run import track_job

    class Cam:
        def __init__(self, ok):
            self.ok, self.n = ok, 0

        def isOpened(self):
            return self.ok

        def read(self):
            self.n += 1
            return (self.n <= 12, np.full((48, 64, 3), self.n * 5 % 255, np.uint8) if self.n <= 12 else None)

        def get(self, prop):
            return 0.0

        def release(self):
            pass

    opens = iter([True] + [False] * 10)
    src = LiveSource(0, reconnect_attempts=2, backoff=0.0, opener=lambda t: Cam(next(opens)),
                     sleep=lambda s: None, clock=itertools.count().__next__)
    out = tmp_path / "o"
    job = track_job(src, load_config(None, ['output.codec="mjpg"']), out)
    with pytest.raises(SourceError, match="failed after 12 frames"):
        job.run()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["frames"] == 12 and summary["status"].startswith("source failed")
    assert (out / "tracks.txt").is_file() and (out / "annotated.avi").is_file()


@pytest.mark.parametrize("argv_tail, path", [
    (["gt-stats", "{gt}", "--image-size", "64x48", "--json", "{out}"], "{out}"),
    (["ablate", "synth:walker?n_frames=20", "--rows", "1", "--json", "{out}"], "{out}"),
])
def test_json_outputs_need_force(tmp_path, capsys, argv_tail, path):
    gt = tmp_path / "gt.txt"
    gt.write_text("1,1,10,10,5,8,1,-1,-1,-1\n2,1,11,10,5,8,1,-1,-1,-1\n")
    out = tmp_path / "o.json"
    out.write_text("keep me")
    argv = [a.format(gt=gt, out=out) for a in argv_tail]
    assert main(argv) == 2
    assert "use --force" in capsys.readouterr().err and out.read_text() == "keep me"
    assert main(argv + ["--force"]) == 0
    assert out.read_text() != "keep me"


@pytest.mark.parametrize("line, words", [
    ("gt-stats {missing} --image-size 64x48", "not found"),
    ("gt-stats {csv_ok} --image-size 64by48", "wxh"),
    ("report {out}", "study.json"),
    ("overlay {missing} --gt {csv_ok} -o {out}/o.webm", "not found"),
    ("sweep synth:walker?n_frames=5 --param motion.nope=1,2 -o {out}/s", "unknown config key"),
    ("ablate synth:walker?n_frames=5 --rows 9", "--rows"),
    ("shape train {missing} --gt {csv_ok} -o {out}/m.npz", "not found"),
])
def test_more_commands_bad_input(files, capsys, line, words):
    args = line.format(**{k: str(v) for k, v in files.items()}).split()
    code = main(args)
    err = [ln for ln in capsys.readouterr().err.splitlines() if "error" in ln]
    assert code not in (0, None), line
    assert len(err) == 1 and words.lower() in err[0].lower(), err


def test_run_outcome_records_then_reraises():
    from motiontrack.errors import SourceError
    from motiontrack.run import RunOutcome

    with RunOutcome() as ok:
        pass
    assert ok.status == "complete" and not ok.interrupted and not ok.failed
    ok.reraise()                                   # nothing to raise

    with RunOutcome() as cut:
        raise KeyboardInterrupt
    assert cut.interrupted and cut.status == "interrupted"
    with pytest.raises(KeyboardInterrupt):
        cut.reraise()

    with RunOutcome() as dropped:
        raise SourceError("camera 0 failed after 3 frames")
    assert dropped.failed and dropped.status == "source failed: camera 0 failed after 3 frames"
    with pytest.raises(SourceError, match="camera 0"):
        dropped.reraise()

    with pytest.raises(ValueError):                # a bug is not swallowed
        with RunOutcome():
            raise ValueError("bug")
