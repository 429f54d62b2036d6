"""Outputs under pressure: a full disk, special files in the place of outputs, standard output as
``-``, ``--force`` over old outputs and two runs into one folder."""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import stat
import subprocess
import sys
import time

import pytest

from helpers.disk import small_disk as mount_small_disk
from motiontrack.cli import main
from motiontrack.config import load_config
from motiontrack.errors import InputError
from motiontrack.io import video
from motiontrack.io.atomic import AtomicFile, DiskFullError, OutputLock, commit_leftovers
from motiontrack.pipeline import open_configured_source
from motiontrack.run import Job, Writer
from motiontrack.run.processors import TrackProcessor
from motiontrack.run.writers import TracksWriter, VideoWriter
from motiontrack.studies.sweep import load_study, run_sweep, study_from_args

WALKER = "synth:walker?n_frames={n}"


def _files(folder):
    return sorted(p.name for p in folder.iterdir()) if folder.exists() else []


def _hidden(folder):
    """Temporary (``.part``) and other hidden files anywhere under ``folder``."""
    return sorted(str(p.relative_to(folder)) for p in folder.rglob(".*"))


def _error_lines(err: str) -> list[str]:
    return [ln for ln in err.splitlines() if "error" in ln]


# ----------------------------------------------------------------------------- a full disk
@pytest.fixture
def small_disk(tmp_path):
    """A 2 MB file system (tmpfs, mounted as root), unmounted after the test."""
    with mount_small_disk(tmp_path / "disk") as disk:
        yield disk


def _track_onto_full_disk(disk, capsys, codec, n):
    out = disk / "o"
    code = main(["track", WALKER.format(n=n), "-o", str(out), "--codec", codec])
    err = capsys.readouterr().err
    return out, code, err


def test_a_video_filling_the_disk_goes_first_and_the_tracks_and_summary_stay(small_disk, capsys):
    # mjpg goes through cv2.VideoWriter, which writes on silently when the disk is full: the video
    # stops while 1 MiB is left (video.DISK_RESERVE), at about frame 32 of 60
    out, code, err = _track_onto_full_disk(small_disk, capsys, "mjpg", 60)
    assert code == 2
    errors = _error_lines(err)
    assert len(errors) == 1 and "disk full writing" in errors[0] and "annotated.avi" in errors[0]
    assert _files(out) == ["config.toml", "gt.txt", "summary.json", "tracks.txt"]
    assert _hidden(small_disk) == []                       # no .part file, no lock file
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"].startswith("disk full writing") and summary["truncated"] is True
    assert 0 < summary["frames"] < 60
    assert "video" not in summary["outputs"]
    frames = [int(ln.split(",")[0]) for ln in (out / "tracks.txt").read_text().splitlines()]
    assert frames and max(frames) <= summary["frames"]     # the tracks end where the run ended
    assert shutil.disk_usage(small_disk).used < 200_000    # the video's space is given back


@pytest.mark.slow
def test_an_encoder_meeting_a_full_disk_loses_its_video_only(small_disk, capsys, monkeypatch):
    # no reserve: PyAV's WebM muxer holds clusters in memory, the disk fills and the error comes
    # from the encoder (at a frame or when the file is finished)
    if not video.pyav_available():
        pytest.skip("PyAV is not installed")
    monkeypatch.setattr(video, "DISK_RESERVE", 0)
    out, code, err = _track_onto_full_disk(small_disk, capsys, "vp80", 150)
    assert code == 2
    errors = _error_lines(err)
    assert len(errors) == 1 and "disk full writing" in errors[0] and "annotated.webm" in errors[0]
    assert "No space left on device" in errors[0]
    assert _files(out) == ["config.toml", "gt.txt", "summary.json", "tracks.txt"]
    assert _hidden(small_disk) == []
    assert json.loads((out / "summary.json").read_text())["status"].startswith("disk full")


def _fill(path):
    """Fill the device of ``path`` to its last byte with the file ``path``."""
    fd = os.open(path, os.O_WRONLY | os.O_CREAT)
    try:
        for size in (1 << 16, 1 << 12, 1):
            try:
                while True:
                    os.write(fd, b"\0" * size)
            except OSError:
                pass
    finally:
        os.close(fd)


def test_a_file_that_meets_a_full_disk_keeps_what_it_could_not_write(small_disk):
    filler = small_disk / "filler"
    _fill(filler)
    f = AtomicFile(small_disk / "tracks.txt")
    line = "1,1,10.00,10.00,5.00,8.00,1.0,-1,-1,-1\n"
    written = 0
    with pytest.raises(DiskFullError, match="disk full writing .*tracks.txt: No space left"):
        while written < 10_000:                              # 390 kB: no room for any of it
            written += 1
            f.write(line)
    filler.unlink()                                          # another output makes room
    for _ in range(10_000 - written):
        f.write(line)
    f.commit()
    assert (small_disk / "tracks.txt").read_text() == line * 10_000
    assert _files(small_disk) == ["tracks.txt"]


def test_a_file_that_cannot_be_finished_leaves_nothing_behind(small_disk):
    f = AtomicFile(small_disk / "big.txt")
    with pytest.raises(DiskFullError):
        for _ in range(100):
            f.write("x" * 65536)                             # 6.5 MB onto a 2 MB disk
    with pytest.raises(DiskFullError):
        f.commit()                                           # still no room: removed
    assert _files(small_disk) == []
    assert shutil.disk_usage(small_disk).used < 100_000


@pytest.mark.slow
def test_a_killed_run_blocks_nobody_and_its_temporary_files_go_with_the_next_run(tmp_path, capsys):
    out = tmp_path / "o"
    proc = subprocess.Popen([sys.executable, "-m", "motiontrack", "track",
                             WALKER.format(n=5000), "-o", str(out), "--codec", "mjpg"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.time() + 60
        while not list(out.glob(".annotated.*.part.avi")) and time.time() < deadline:
            time.sleep(0.1)
        # a second run into the folder is refused at once, whatever --force says
        t0 = time.perf_counter()
        assert main(["track", WALKER.format(n=5), "-o", str(out), "--force"]) == 2
        assert time.perf_counter() - t0 < 5
        errors = _error_lines(capsys.readouterr().err)
        assert len(errors) == 1 and f"output folder {out} is in use" in errors[0]
        assert f"process {proc.pid}" in errors[0]
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=60)
    left = _hidden(out)
    assert any(n.startswith(".tracks.txt.") for n in left), left
    assert any(n.startswith(".annotated.") for n in left), left
    # the system freed the lock of the killed process; nothing it committed needs --force
    assert main(["track", WALKER.format(n=5), "-o", str(out), "--codec", "mjpg"]) == 0
    assert _hidden(out) == []
    assert _files(out) == ["annotated.avi", "config.toml", "gt.txt", "summary.json", "tracks.txt"]


def test_a_file_writes_out_what_it_collected_once_a_second(tmp_path, monkeypatch):
    from motiontrack.io import atomic

    clock = [100.0]
    monkeypatch.setattr(atomic.time, "monotonic", lambda: clock[0])
    f = AtomicFile(tmp_path / "tracks.txt")
    f.write("1,1,10,20,30,40\n")
    assert f.tmp.read_text() == ""                      # collected: far less than a block
    clock[0] += atomic.FLUSH_S
    f.write("2,1,11,21,30,40\n")
    assert f.tmp.read_text() == "1,1,10,20,30,40\n2,1,11,21,30,40\n"
    f.commit()


def test_a_killed_writers_leftovers_are_committed_up_to_their_last_whole_line(tmp_path):
    from motiontrack.io.atomic import temp_path_for

    tracks = AtomicFile(tmp_path / "tracks.txt")
    tracks.write("1,1,10,20,30,40\n2,1,11,21,30,40\n3,1,1")   # cut inside the third row
    tracks._flush()                                    # on disk, as a killed run leaves it
    events = AtomicFile(tmp_path / "events.jsonl")               # nothing reached the disk
    video_tmp = temp_path_for(tmp_path / "annotated.webm")
    video_tmp.write_bytes(b"\x1aE\xdf\xa3 webm as far as written")
    still = temp_path_for(tmp_path / "heatmap.png")
    still.write_bytes(b"\x89PNG cut short")
    (tmp_path / "counts.csv").write_text("committed\n")
    counts = AtomicFile(tmp_path / "counts.csv")                 # its final name is taken
    counts.write("newer\n")
    counts._flush()
    kept = commit_leftovers(tmp_path)
    assert kept == [tmp_path / "annotated.webm", tmp_path / "tracks.txt"]
    assert (tmp_path / "tracks.txt").read_text() == "1,1,10,20,30,40\n2,1,11,21,30,40\n"
    assert (tmp_path / "annotated.webm").read_bytes().endswith(b"as far as written")
    assert not events.tmp.exists()                                # empty: removed
    assert still.exists() and counts.tmp.exists()                 # left as they are
    assert (tmp_path / "counts.csv").read_text() == "committed\n"
    assert commit_leftovers(tmp_path) == []


# ----------------------------------------------------------------------------- special files
def _special(tmp_path, kind):
    """A non-regular file at ``tmp_path / 'o.json'``; returns it and a test of its kind."""
    p = tmp_path / "o.json"
    if kind == "fifo":
        os.mkfifo(p)
        return p, stat.S_ISFIFO
    if kind == "symlink to /proc":
        p.symlink_to("/proc/self/fd/1")                     # what /dev/stdout is
        return p, stat.S_ISLNK
    if kind == "folder":
        p.mkdir()
        return p, stat.S_ISDIR
    try:                                                     # a copy of /dev/full (1, 7)
        os.mknod(p, stat.S_IFCHR | 0o666, os.makedev(1, 7))
    except PermissionError:
        pytest.skip("creating a character device needs root")
    return p, stat.S_ISCHR


def _camera(folder):
    """A ground homography camera: image pixels are ground metres."""
    camera = folder / "cam.toml"
    camera.write_text('model = "homography"\nH = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\n')
    return camera


@pytest.fixture
def gt_file(tmp_path):
    gt = tmp_path / "gt.txt"
    gt.write_text("1,1,10,10,5,8,1,-1,-1,-1\n2,1,11,10,5,8,1,-1,-1,-1\n")
    return gt


@pytest.mark.parametrize("kind", ["character device", "fifo", "symlink to /proc", "folder"])
@pytest.mark.parametrize("argv", [
    "evaluate --gt {gt} --pred {gt} --json {out} --force",
    "evaluate --gt {gt} --pred {gt} --per-frame {out} --force",
    "gt-stats {gt} --image-size 64x48 --json {out} --force",
    "world {gt} --camera {camera} -o {out} --force",
])
def test_force_replaces_only_regular_files(tmp_path, capsys, gt_file, kind, argv):
    camera = _camera(tmp_path)
    out, is_kind = _special(tmp_path, kind)
    code = main(argv.format(gt=gt_file, out=out, camera=camera).split())
    errors = _error_lines(capsys.readouterr().err)
    assert code == 2
    assert len(errors) == 1 and str(out) in errors[0]
    assert "not a regular file" in errors[0] or (kind == "folder" and "is a folder" in errors[0])
    assert is_kind(os.lstat(out).st_mode)                    # left as it was


def test_a_special_file_among_a_runs_outputs_is_refused(tmp_path, capsys):
    out = tmp_path / "o"
    out.mkdir()
    os.mkfifo(out / "tracks.txt")
    assert main(["track", WALKER.format(n=5), "-o", str(out), "--force", "--no-video"]) == 2
    errors = _error_lines(capsys.readouterr().err)
    assert len(errors) == 1 and "tracks.txt is a named pipe, not a regular file" in errors[0]
    assert stat.S_ISFIFO(os.lstat(out / "tracks.txt").st_mode)
    assert _files(out) == ["tracks.txt"]


@pytest.mark.parametrize("argv, parse", [
    ("evaluate --gt {gt} --pred {gt} --json -", json.loads),
    ("evaluate --gt {gt} --pred {gt} --per-frame -", lambda s: s.splitlines()[0].split(",")),
    ("gt-stats {gt} --image-size 64x48 --json -", json.loads),
    ("world {gt} --camera {camera} -o -", lambda s: [ln.split(",") for ln in s.splitlines()]),
])
def test_dash_writes_the_output_to_standard_output(tmp_path, capsys, monkeypatch, gt_file, argv,
                                                   parse):
    camera = _camera(tmp_path)
    monkeypatch.chdir(tmp_path)
    assert main(argv.format(gt=gt_file, camera=camera).split()) == 0
    printed = capsys.readouterr().out
    assert parse(printed)                                    # only the output, nothing else
    assert _files(tmp_path) == ["cam.toml", "gt.txt"]        # and no file named "-"


def test_two_outputs_cannot_both_be_standard_output(capsys, gt_file):
    assert main(["evaluate", "--gt", str(gt_file), "--pred", str(gt_file), "--json", "-",
                 "--per-frame", "-"]) == 2
    assert "cannot both be -" in capsys.readouterr().err


# ----------------------------------------------------------------------------- --force and locks
class _Probe(Writer):
    """Records the files of the folder when the run starts writing."""

    def __init__(self) -> None:
        self.paths = {}
        self.seen: list[str] | None = None

    def start(self, ctx) -> None:
        self.seen = [n for n in _files(ctx.out) if n != OutputLock.NAME]


def _job(out, *first, force=False, video=True):
    """The job of ``track`` with writers ``first`` before its own."""
    cfg = load_config(None, ['output.codec="mjpg"'])
    src = open_configured_source(WALKER.format(n=8), cfg.source)
    writers = [*first, TracksWriter(out)]
    if video:
        writers.append(VideoWriter("video", out / "annotated.avi", "mjpg"))
    try:
        return Job(src, TrackProcessor(cfg, src.info), writers, out, force=force,
                   config=(lambda c, p: p.write_text("cfg\n"), cfg))
    except BaseException:
        src.close()
        raise


def test_force_removes_the_old_outputs_before_the_first_new_one(tmp_path):
    out = tmp_path / "o"
    _job(out).run()
    (out / ".tracks.txt.abcd1234.part").write_text("left by a killed run")
    probe = _Probe()
    summary = _job(out, probe, force=True, video=False).run()     # no video this time
    assert probe.seen == []                      # the old set was gone before anything was written
    assert _files(out) == ["config.toml", "summary.json", "tracks.txt"]   # no stale video
    assert set(json.loads((out / "summary.json").read_text())["outputs"]) == {
        "tracks", "summary", "config"}
    assert summary.frames == 8


def test_an_interrupted_forced_run_leaves_no_old_output_beside_the_new(tmp_path):
    out = tmp_path / "o"
    _job(out).run()
    with pytest.raises(KeyboardInterrupt):
        _job(out, force=True, video=False).run(should_stop=lambda: True)
    assert _files(out) == ["config.toml", "summary.json", "tracks.txt"]
    assert json.loads((out / "summary.json").read_text())["frames"] == 1


def test_one_run_at_a_time_in_a_folder(tmp_path):
    out = tmp_path / "o"
    first = _job(out)
    with pytest.raises(InputError, match=re.escape(f"output folder {out} is in use by another "
                                                   f"motiontrack run (process {os.getpid()})")):
        _job(out, force=True)
    first.run()
    assert _job(out, force=True).run().frames == 8    # the lock went with the run
    assert ".motiontrack.lock" not in _files(out)


def test_a_failed_run_leaves_no_folder_it_created(tmp_path):
    out = tmp_path / "new" / "o"

    class Boom(Writer):
        paths = {}

        def write(self, result):
            raise RuntimeError("encoder gave up")

    with pytest.raises(RuntimeError):
        _job(out, Boom()).run()
    assert not out.exists()


def _sweep(out, values, force=False, **kw):
    study = study_from_args(["synth:walker?n_frames=4"], None,
                            [f"motion.median.threshold={values}"],
                            load_config(None, ["motion.method=median"]))
    return run_sweep(study, out, figures=False, force=force, **kw)


def test_a_forced_sweep_removes_the_old_study_first(tmp_path, monkeypatch, capsys):
    out = tmp_path / "s"
    _sweep(out, "0.05,0.1,0.2")
    assert _files(out / "runs") == ["r001", "r002", "r003"]
    (out / "figures").mkdir()
    (out / "figures" / "old.png").write_bytes(b"old")

    def killed(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr("motiontrack.studies.sweep.execute", killed)
    with pytest.raises(KeyboardInterrupt):
        _sweep(out, "0.3", force=True)
    assert not (out / "runs").exists() and not (out / "figures").exists()
    assert not (out / "results.csv").exists()            # the old table is not the new study's
    study, _ = load_study(out)
    assert study.grid == (("motion.median.threshold", (0.3,)),)
    assert main(["report", str(out)]) != 0                # nothing mixed to render
    assert "results" in capsys.readouterr().err


def test_a_second_sweep_into_a_folder_is_refused(tmp_path):
    out = tmp_path / "s"
    with OutputLock(out):
        with pytest.raises(InputError, match="is in use by another motiontrack run"):
            _sweep(out, "0.1", force=True)
    assert _sweep(out, "0.1").rows


# ------------------------------------------------------- every writer takes the folder's lock
def _writers_into(out, tmp_path):
    """The commands other than ``track`` that write into a run's folder ``out``."""
    scene = tmp_path / "scene.toml"
    scene.write_text('[[line]]\nname = "g"\npoints = [[0, 10], [20, 10]]\n')
    tracks = tmp_path / "tracks.txt"
    tracks.write_text("1,1,5,5,4,8,1,-1,-1,-1\n2,1,5,9,4,8,1,-1,-1,-1\n")
    return {
        "analyze": ["analyze", str(tracks), "--scene", str(scene), "--fps", "5", "-o", str(out)],
        "synth-events": ["synth-events", "synth:leftbag?n_frames=40", "-o", str(out)],
        "evaluate --json": ["evaluate", "--gt", str(tracks), "--pred", str(tracks), "--json",
                            str(out / "metrics.json")],
        "evaluate --per-frame": ["evaluate", "--gt", str(tracks), "--pred", str(tracks),
                                 "--per-frame", str(out / "frames.csv")],
        # tracks analysed with the scene on both sides
        "evaluate-events --json": ["evaluate-events", "--gt", str(tracks), "--pred", str(tracks),
                                   "--scene", str(scene), "--fps", "5", "--json",
                                   str(out / "events-eval.json")],
        "gt-stats --json": ["gt-stats", str(tracks), "--image-size", "64x48", "--json",
                            str(out / "gt-stats.json")],
        "overlay": ["overlay", WALKER.format(n=2), "-o", str(out / "overlay.avi")],
        "world": ["world", str(tracks), "--camera", str(_camera(tmp_path)), "-o",
                  str(out / "world.txt")],
        "calibrate ground": ["calibrate", "ground", "--points", str(_point_pairs(tmp_path)),
                             "-o", str(out / "ground.toml")],
    }


def _point_pairs(folder):
    """Four image points and their ground positions (a homography's worth)."""
    pairs = folder / "pairs.csv"
    pairs.write_text("u,v,x,y\n10,10,0,0\n50,10,4,0\n50,40,4,3\n10,40,0,3\n")
    return pairs


@pytest.mark.parametrize("command", ["analyze", "synth-events", "evaluate --json",
                                     "evaluate --per-frame", "evaluate-events --json",
                                     "gt-stats --json", "overlay", "world",
                                     "calibrate ground"])
def test_every_command_writing_into_a_run_folder_is_refused_while_a_run_holds_it(
        tmp_path, capsys, command):
    out = tmp_path / "run"
    argv = _writers_into(out, tmp_path)[command]
    held = OutputLock(out)           # a track run writing into the folder
    (out / "tracks.txt").write_text("the running track's\n")
    try:
        assert main(argv) == 2
        errors = _error_lines(capsys.readouterr().err)
        assert len(errors) == 1
        assert (f"output folder {out} is in use by another motiontrack run "
                f"(process {os.getpid()})") in errors[0]
        assert _files(out) == [".motiontrack.lock", "tracks.txt"]      # nothing written
    finally:
        held.release()
    assert main(argv) == 0                                             # free again: it writes
    assert ".motiontrack.lock" not in _files(out) and len(_files(out)) > 1


def test_a_run_removes_every_temporary_file_a_killed_run_left_whatever_it_writes(tmp_path):
    out = tmp_path / "o"
    out.mkdir()
    # a killed `track` with a video, then a `--no-video --force` run into the folder
    (out / ".annotated.k1ll3d00.part.webm").write_bytes(b"\x1aE\xdf\xa3" * 1000)
    (out / ".heatmap.png.k1ll3d01.part").write_bytes(b"png")
    (out / ".notes.txt").write_text("a hidden file of the user's")
    assert main(["track", WALKER.format(n=3), "--no-video", "--force", "-o", str(out)]) == 0
    assert _hidden(out) == [".notes.txt"]
    assert _files(out) == [".notes.txt", "config.toml", "gt.txt", "summary.json", "tracks.txt"]


def test_analyze_onto_a_full_disk_keeps_all_its_outputs_or_none(small_disk, tmp_path, capsys):
    scene = tmp_path / "scene.toml"
    scene.write_text('[[line]]\nname = "g"\npoints = [[0, 100], [200, 100]]\n'
                     '[[zone]]\nname = "z"\npolygon = [[0, 0], [200, 0], [200, 60], [0, 60]]\n')
    tracks = tmp_path / "tracks.txt"   # two tracks crossing the line every 5 frames
    tracks.write_text("".join(f"{f},{i},95,{20 if (f // 5 + i) % 2 else 110},10,20,1,-1,-1,-1\n"
                              for f in range(1, 401) for i in (1, 2)))
    argv = ["analyze", str(tracks), "--scene", str(scene), "--fps", "25", "-o"]
    assert main([*argv, str(tmp_path / "whole")]) == 0
    whole = _files(tmp_path / "whole")
    need = sum((tmp_path / "whole" / n).stat().st_size for n in whole)
    page = 4096
    kept = set()
    # the disk fills at each output (the event store needs room for its journal while it
    # runs: about 100 pages more than the outputs)
    for free in range(page, need + 120 * page, 9 * page):
        out = small_disk / "o"
        shutil.rmtree(out, ignore_errors=True)
        filler = small_disk / "filler"
        filler.unlink(missing_ok=True)
        st = os.statvfs(small_disk)
        filler.write_bytes(b"\0" * max(0, st.f_bavail * st.f_frsize - free))
        code = main([*argv, str(out)])
        err = capsys.readouterr().err
        files = _files(out)
        assert files in ([], whole), (free, files, err)   # all or nothing, as `track`
        assert _hidden(small_disk) == []
        assert code == (0 if files else 2), err
        kept.add(bool(files))
    assert kept == {True, False}


def test_force_over_a_summary_nested_100000_deep_replaces_it(tmp_path, capsys):
    out = tmp_path / "o"
    out.mkdir()
    (out / "summary.json").write_text("[" * 100_000 + "]" * 100_000)
    assert main(["track", WALKER.format(n=3), "--no-video", "--force", "-o", str(out)]) == 0
    assert "internal error" not in capsys.readouterr().err
    assert json.loads((out / "summary.json").read_text())["frames"] == 3
