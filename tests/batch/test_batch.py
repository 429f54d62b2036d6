"""motiontrack batch: many videos on a local Dask cluster of 2 worker processes."""

from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("distributed")

import motiontrack.batch  # noqa: E402
from motiontrack.batch import config_hash, expand_sources, run_batch  # noqa: E402
from motiontrack.cli import main  # noqa: E402
from motiontrack.config import PipelineConfig, apply_overrides, save_config  # noqa: E402
from motiontrack.errors import ConfigError  # noqa: E402
from motiontrack.io.mot import read_mot  # noqa: E402
from motiontrack.run.executor import dask_client  # noqa: E402
from motiontrack.run.jobs import track_job  # noqa: E402

from helpers import communicate_or_dump  # noqa: E402

SCENES = ["synth:walker?n_frames=30", "synth:crossing?n_frames=30", "synth:walker?n_frames=25&seed=3"]


def _cfg():
    return apply_overrides(PipelineConfig(), ["output.video=false"])


def _index(results: Path) -> dict[str, dict[str, str]]:
    with open(results / "index.csv", newline="", encoding="utf-8") as fh:
        return {r["name"]: r for r in csv.DictReader(fh)}


@pytest.fixture(scope="module")
def client(dask_session_client):
    return dask_session_client


@pytest.fixture(scope="module")
def first_batch(tmp_path_factory, client):
    """The scenes plus a missing file and a corrupt file (random bytes named .avi)."""
    base = tmp_path_factory.mktemp("batch")
    corrupt = base / "corrupt.avi"
    corrupt.write_bytes(os.urandom(20000))
    sources = [*SCENES, str(base / "missing.avi"), str(corrupt)]
    rows = run_batch(sources, base / "results", _cfg(), client=client)
    return base, sources, rows


def test_sources_expand_to_unique_names_folders_sorted_and_recursive_globs(tmp_path):
    (tmp_path / "b" / "deep").mkdir(parents=True)
    for rel in ("b/z.mp4", "b/a.avi", "b/notes.txt", "b/deep/a.avi"):
        (tmp_path / rel).write_bytes(b"x")
    folder = expand_sources([str(tmp_path / "b")])
    assert [v.name for v in folder] == ["a", "z"]          # videos only, sorted, not recursive
    deep = expand_sources([str(tmp_path / "b" / "**" / "*.avi")])
    assert [Path(v.source).relative_to(tmp_path).as_posix() for v in deep] == ["b/a.avi",
                                                                             "b/deep/a.avi"]
    assert [v.name for v in deep] == ["a", "a-2"]


def test_manifest_entries_give_name_gt_scene_and_camera(tmp_path):
    (tmp_path / "m.toml").write_text(
        '[[sequence]]\nname = "one"\nsource = "v.avi"\ngt = "gt.txt"\nscene = "s.toml"\n'
        'camera = "cam.xml"\n', encoding="utf-8")
    (v,) = expand_sources([str(tmp_path / "m.toml")])
    assert (v.name, v.source, v.gt, v.scene, v.camera) == (
        "one", str(tmp_path / "v.avi"), str(tmp_path / "gt.txt"), str(tmp_path / "s.toml"),
        str(tmp_path / "cam.xml"))


def test_index_parquet_holds_the_rows_of_index_csv_typed(tmp_path):
    pq = pytest.importorskip("pyarrow.parquet")
    from motiontrack.batch.runner import write_index

    rows = [{"name": "a", "source": "/v/a.avi", "status": "done", "frames": 30, "fps": 41.5,
             "tracks": 2, "wall_s": 0.9, "worker": "0", "attempts": 1, "HOTA": 0.5,
             "MOTA": 0.25, "IDF1": 0.75},
            {"name": "b", "source": "/v/b.avi", "status": "failed", "error": "SourceError: x",
             "attempts": "2"}]
    write_index(rows, tmp_path / "index.csv")
    table = pq.read_table(tmp_path / "index.parquet")
    assert table.column_names == list(motiontrack.batch.INDEX_COLUMNS)
    assert str(table.schema.field("frames").type) == "int64"
    assert str(table.schema.field("HOTA").type) == "double"
    with open(tmp_path / "index.csv", newline="", encoding="utf-8") as fh:
        from_csv = list(csv.DictReader(fh))
    from_parquet = [{k: "" if v is None else v for k, v in r.items()} for r in table.to_pylist()]
    assert len(from_parquet) == len(from_csv) == 2
    for c, p in zip(from_csv, from_parquet):
        assert {k: (float(v) if k in ("fps", "wall_s", "HOTA", "MOTA", "IDF1", "frames",
                                       "tracks", "attempts") and v != "" else v)
                for k, v in c.items()} == p
    assert from_parquet[1]["attempts"] == 2 and from_parquet[1]["frames"] == ""


@pytest.mark.slow
def test_batch_tracks_are_byte_identical_to_track_alone(first_batch, tmp_path):
    base, _, rows = first_batch
    done = [r for r in rows if r["status"] == "done"]
    assert len(done) == len(SCENES)
    for src, row in zip(SCENES, done):
        alone = tmp_path / row["name"]
        track_job(src, _cfg(), alone).run()
        batch_tracks = (base / "results" / row["name"] / "tracks.txt").read_bytes()
        assert batch_tracks == (alone / "tracks.txt").read_bytes()
        assert row["frames"] == int(src.split("n_frames=")[1].split("&")[0])
        assert 0 <= row["HOTA"] <= 1   # synth: scenes carry their ground truth


@pytest.mark.slow
def test_missing_and_corrupt_files_are_failed_rows_and_the_rest_done(first_batch):
    base, _, rows = first_batch
    index = _index(base / "results")
    assert [r["name"] for r in rows] == list(index)
    assert index["missing"]["status"] == "failed" and "not found" in index["missing"]["error"]
    assert index["corrupt"]["status"] == "failed" and index["corrupt"]["error"]
    assert {index[n]["status"] for n in index if n not in ("missing", "corrupt")} == {"done"}
    # only finished videos have folders; no partial folders are left
    assert sorted(p.name for p in (base / "results").iterdir()) == sorted(
        [*(n for n in index if index[n]["status"] == "done"), "combined.json", "index.csv",
         "index.parquet"])


@pytest.mark.slow
def test_combined_metrics_are_the_videos_combined_as_trackeval_does(tmp_path, shared_dask, capsys):
    from motiontrack.evaluate import mot
    from motiontrack.io.sources import open_source

    scenes = ["synth:crossing?n_frames=60", "synth:walker?n_frames=60&seed=3"]
    results = tmp_path / "results"
    code = main(["batch", *scenes, "-o", str(results), "-j", "2", "--set", "output.video=false"])
    assert code == 0
    index = _index(results)
    combined = json.loads((results / "combined.json").read_text(encoding="utf-8"))
    assert combined["sequences"] == sorted(index)
    per = []
    for name in sorted(index):   # each scene scored on its own ground truth, then combined
        with open_source(index[name]["source"]) as src:
            gt = src.ground_truth()
        pred = read_mot(results / name / "tracks.txt", kind="results")
        per.append(mot.evaluate_sequence(gt.select(gt.frames <= 60), pred))
    expected = mot.flatten(mot.combine_sequences(per))
    assert combined["metrics"] == pytest.approx(expected)
    assert combined["metrics"]["TP"] > 0
    assert f"HOTA {expected['HOTA']:.4f}" in capsys.readouterr().out


@pytest.mark.slow
def test_a_video_longer_than_the_timeout_is_a_timeout_row_and_the_batch_goes_on(tmp_path,
                                                                                 client):
    results = tmp_path / "results"
    # the short video must finish within the timeout on a loaded machine too (a worker's first
    # task imports the pipeline), the long one never does
    long, short = "synth:walker?n_frames=20000", "synth:crossing?n_frames=5"
    rows = run_batch([long, short], results, _cfg(), client=client, timeout_s=5.0)
    index = _index(results)
    assert index["synth-walker"]["status"] == "timeout"
    assert "--timeout-s 5" in index["synth-walker"]["error"]
    assert 5.0 <= float(index["synth-walker"]["wall_s"]) < 40
    assert not (results / ".synth-walker.partial").exists()
    assert not (results / "synth-walker").exists()
    assert [r["status"] for r in rows] == ["timeout", "done"]
    # the worker is free again: the next batch on the same cluster runs at once
    again = run_batch([long.replace("20000", "10")], tmp_path / "again", _cfg(), client=client,
                      timeout_s=60)
    assert [r["status"] for r in again] == ["done"]
    with pytest.raises(ConfigError, match="--timeout-s"):
        run_batch([short], tmp_path / "bad", _cfg(), client=client, timeout_s=0)


@pytest.mark.slow
def test_resume_redoes_only_the_removed_video(tmp_path, client):
    results = tmp_path / "results"
    run_batch(SCENES, results, _cfg(), client=client)
    first = _index(results)
    names = list(first)
    mtimes = {n: (results / n / "tracks.txt").stat().st_mtime_ns for n in names}
    import shutil
    shutil.rmtree(results / names[1])
    rows = run_batch(SCENES, results, _cfg(), client=client, resume=True)
    again = _index(results)
    assert [r["status"] for r in rows] == ["done"] * 3
    for n in (names[0], names[2]):   # kept: same files, same index row
        assert (results / n / "tracks.txt").stat().st_mtime_ns == mtimes[n]
        assert again[n] == first[n]
    assert (results / names[1] / "tracks.txt").is_file()
    assert again[names[1]]["wall_s"] != "" and again[names[1]]["status"] == "done"


@pytest.mark.slow
def test_resume_with_another_config_redoes_everything(tmp_path, client):
    results = tmp_path / "results"
    run_batch(SCENES[:1], results, _cfg(), client=client)
    before = (results / "synth-walker" / "tracks.txt").stat().st_mtime_ns
    first_hash = _index(results)["synth-walker"]["config_hash"]
    other = apply_overrides(_cfg(), ["regions.min_size=0.002"])
    rows = run_batch(SCENES[:1], results, other, client=client, resume=True)
    assert rows[0]["config_hash"] == _index(results)["synth-walker"]["config_hash"]
    assert (results / "synth-walker" / "tracks.txt").stat().st_mtime_ns != before
    assert rows[0]["config_hash"] != first_hash


def test_the_package_loads_no_batch_until_the_batch_subpackage_is_imported():
    # a new process: this one has imported motiontrack.batch already
    probe = ("import sys, motiontrack; print('motiontrack.batch' in sys.modules, "
             "hasattr(motiontrack, 'batch')); import motiontrack.batch; "
             "print(motiontrack.batch.run_batch.__module__)")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                         check=True, timeout=120).stdout.split()
    assert out == ["False", "False", "motiontrack.batch.runner"]


@pytest.mark.slow
def test_python_api_and_cli_write_the_index(tmp_path, client, shared_dask, capsys):
    # one SOURCE and the config as a TOML file, as the command takes them
    save_config(_cfg(), tmp_path / "cfg.toml")
    rows = motiontrack.batch.run_batch(SCENES[0], tmp_path / "api", str(tmp_path / "cfg.toml"),
                                       client=client)
    assert [r["status"] for r in rows] == ["done"]
    assert rows[0]["config_hash"] == config_hash(_cfg())
    code = main(["batch", SCENES[0], "-o", str(tmp_path / "cli"), "-j", "1",
                 "--set", "output.video=false"])
    assert code == 0
    assert _index(tmp_path / "cli")["synth-walker"]["status"] == "done"
    assert "1 done, 0 failed" in capsys.readouterr().out


def _batch_killing_the_walker_worker(results: Path, sources: list[str], retries: int):
    """run_batch on a fresh cluster of 2 workers; the worker running the first video's first
    attempt is killed (SIGKILL) once that video's partial folder appears."""
    import signal
    import threading
    import time

    killed: list[int] = []

    def kill_the_walker_worker(cl):
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and not killed:
            if (results / ".synth-walker.partial").exists():
                for addr, keys in cl.processing().items():
                    if any(str(k).endswith("-0-1") for k in keys):
                        pid = cl.run(os.getpid, workers=[addr])[addr]
                        os.kill(pid, signal.SIGKILL)
                        killed.append(pid)
            time.sleep(0.05)

    with dask_client(jobs=2) as cl:
        watcher = threading.Thread(target=kill_the_walker_worker, args=(cl,), daemon=True)
        watcher.start()
        rows = run_batch(sources, results, _cfg(), client=cl, retries=retries)
        watcher.join()
    assert killed, "the walker's worker was never seen processing it"
    return rows


@pytest.mark.slow
def test_a_worker_killed_mid_video_has_the_video_run_again_and_counted(tmp_path):
    results = tmp_path / "results"
    sources = ["synth:walker?n_frames=150", "synth:crossing?n_frames=30"]
    rows = _batch_killing_the_walker_worker(results, sources, retries=2)
    index = _index(results)
    assert index["synth-walker"]["status"] == "done"
    assert index["synth-walker"]["attempts"] == "2"
    assert index["synth-crossing"]["attempts"] == "1"
    assert [r["status"] for r in rows] == ["done", "done"]
    assert not (results / ".synth-walker.partial").exists()
    alone = tmp_path / "alone"
    track_job(sources[0], _cfg(), alone).run()
    assert (results / "synth-walker" / "tracks.txt").read_bytes() == \
        (alone / "tracks.txt").read_bytes()


@pytest.mark.slow
def test_a_worker_death_beyond_the_retries_is_a_failed_row_and_the_batch_goes_on(tmp_path):
    results = tmp_path / "results"
    sources = ["synth:walker?n_frames=150", "synth:crossing?n_frames=30"]
    rows = _batch_killing_the_walker_worker(results, sources, retries=0)
    index = _index(results)
    assert [r["status"] for r in rows] == ["failed", "done"]
    assert index["synth-walker"]["attempts"] == "1"
    assert "worker died" in index["synth-walker"]["error"]
    assert sorted(p.name for p in results.iterdir()) == ["combined.json", "index.csv",
                                                         "index.parquet", "synth-crossing"]


def _sleep_or_return(item, attempt):
    import time

    if item == "hang":
        time.sleep(600)
    return item


@pytest.mark.slow
def test_a_task_that_never_returns_is_cancelled_and_its_worker_restarted(client):
    from motiontrack.run.executor import map_tasks

    cl = client   # the session's cluster: the restarted worker rejoins it
    done = []
    res = map_tasks(cl, _sleep_or_return, ["hang", "quick"], hard_timeout_s=2.0,
                    on_timeout=lambda i, n: f"timeout {i} after {n}",
                    on_result=lambda i, r, n: done.append(i))
    assert res == ["timeout 0 after 1", "quick"]
    assert sorted(done) == [0, 1]
    # both workers are back: two tasks run at the same time again
    assert map_tasks(cl, _sleep_or_return, ["a", "b"]) == ["a", "b"]
    assert len(cl.scheduler_info()["workers"]) == 2


# ------------------------------------------------------------- scene, camera and ground truth
def _synth_video(folder: Path, n: int = 40) -> tuple[Path, Path]:
    """A synthetic scene written as an .avi file and its ground truth as gt.txt: a video file
    with no ground truth of its own."""
    from helpers.video_files import write_synth_video

    from motiontrack.io.mot import write_mot

    video, gt = folder / "walk.avi", folder / "walk-gt.txt"
    write_mot(write_synth_video(video, f"synth:walker?n_frames={n}"), gt, kind="gt")
    return video, gt


def test_batch_files_apply_to_videos_without_their_own_and_gt_from_matches_name_or_source(
        tmp_path):
    from motiontrack.batch.sources import Video, with_files

    for name in ("scene.toml", "cam.xml", "own.toml", "gt-a.txt", "gt-b.txt", "b.avi"):
        (tmp_path / name).write_text("x", encoding="utf-8")
    videos = [Video("a", "/x/a.avi"), Video("b", str(tmp_path / "b.avi")),
              Video("c", "/x/c.avi", scene=str(tmp_path / "own.toml"))]
    (tmp_path / "m.toml").write_text(
        '[[sequence]]\nname = "a"\nsource = "elsewhere.avi"\ngt = "gt-a.txt"\n'
        '[[sequence]]\nname = "other"\nsource = "b.avi"\ngt = "gt-b.txt"\ncamera = "cam.xml"\n',
        encoding="utf-8")
    out = with_files(videos, scene=str(tmp_path / "scene.toml"), gt_from=str(tmp_path / "m.toml"))
    assert [(v.name, v.gt, v.scene, v.camera) for v in out] == [
        ("a", str(tmp_path / "gt-a.txt"), str(tmp_path / "scene.toml"), None),   # by name
        ("b", str(tmp_path / "gt-b.txt"), str(tmp_path / "scene.toml"),            # by source
         str(tmp_path / "cam.xml")),
        ("c", None, str(tmp_path / "own.toml"), None)]                             # its own scene
    (tmp_path / "none.toml").write_text('[[sequence]]\nsource = "z.avi"\ngt = "g.txt"\n',
                                        encoding="utf-8")
    with pytest.raises(ConfigError, match="none of its sequences is one of the 3 videos"):
        with_files(videos, gt_from=str(tmp_path / "none.toml"))
    with pytest.raises(ConfigError, match="--camera .*no such file"):
        with_files(videos, camera=str(tmp_path / "absent.xml"))


@pytest.mark.slow
def test_batch_scene_and_gt_from_give_each_video_the_events_and_metrics_of_track_alone(
        tmp_path, shared_dask):
    from motiontrack.io.events import read_events
    from motiontrack.io.mot import read_mot as read_gt
    video, gt = _synth_video(tmp_path)
    scene = tmp_path / "scene.toml"   # the whole picture: the walker enters it
    scene.write_text('[[zone]]\nname = "all"\n'
                     'polygon = [[0, 0], [4000, 0], [4000, 4000], [0, 4000]]\n', encoding="utf-8")
    (tmp_path / "m.toml").write_text(f'[[sequence]]\nname = "walk"\nsource = "{video.name}"\n'
                                     f'gt = "{gt.name}"\n', encoding="utf-8")
    results = tmp_path / "results"
    code = main(["batch", str(video), "-o", str(results), "-j", "2", "--set",
                 "output.video=false", "--scene", str(scene), "--gt-from", str(tmp_path / "m.toml")])
    assert code == 0
    alone = track_job(str(video), _cfg(), tmp_path / "alone", gt=read_gt(gt, kind="gt"),
                      scene=scene)
    summary = alone.run()
    events = read_events(results / "walk" / "events.jsonl").events
    assert len(events) > 0
    assert events == read_events(tmp_path / "alone" / "events.jsonl").events
    row = _index(results)["walk"]
    assert float(row["HOTA"]) == pytest.approx(summary.accuracy["HOTA"], abs=1e-12)
    assert json.loads((results / "combined.json").read_text(encoding="utf-8"))["sequences"] == [
        "walk"]


@pytest.mark.slow
def test_progress_reports_frames_and_the_clusters_frame_rate_while_videos_run(tmp_path, client):
    calls = []
    scenes = ["synth:walker?n_frames=400", "synth:crossing?n_frames=400"]
    rows = run_batch(scenes, tmp_path / "results", _cfg(), client=client,
                     progress=lambda c: calls.append(dict(c)))
    assert [r["status"] for r in rows] == ["done", "done"]
    assert calls[0] == {"done": 0, "failed": 0, "running": 2, "total": 2, "frames": 0,
                        "fps": 0.0}
    during = [c for c in calls if c["done"] == 0 and c["frames"] > 0]
    assert during, "no frames reported while the videos ran"
    assert all(c["fps"] > 0 for c in during)
    assert [c["frames"] for c in calls] == sorted(c["frames"] for c in calls)
    assert calls[-1]["frames"] == 800 and calls[-1]["done"] == 2


@pytest.mark.slow
def test_ctrl_c_stops_the_batch_within_seconds_and_the_index_says_which_videos_are_done(
        tmp_path, loaded_machine):
    """SIGINT to the whole process group, as a terminal's Ctrl-C sends it (the local cluster's
    workers get it too), with every core busy."""
    import signal
    import subprocess
    import sys
    import time

    results = tmp_path / "results"
    short = ["synth:walker?n_frames=30", "synth:crossing?n_frames=30"]
    long = ["synth:walker?n_frames=20000&seed=1", "synth:crossing?n_frames=20000&seed=1"]
    proc = subprocess.Popen([sys.executable, "-m", "motiontrack", "batch", *short, *long, "-o",
                             str(results), "-j", "2", "--set", "output.video=false"],
                            start_new_session=True, stdout=subprocess.PIPE,
                            env={**os.environ, "PYTHONFAULTHANDLER": "1"},
                            stderr=subprocess.PIPE, text=True)
    try:
        t0 = time.monotonic()
        while time.monotonic() - t0 < 180:
            if (results / "index.csv").is_file() and sum(
                    r["status"] == "done" for r in _index(results).values()) == 2:
                break
            time.sleep(0.2)
        time.sleep(1.0)   # the long videos are running now
        os.killpg(proc.pid, signal.SIGINT)
        t1 = time.monotonic()
        _, err = communicate_or_dump(proc, 60)
        stopped_in = time.monotonic() - t1
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 130, err
    assert stopped_in < 20
    assert "--resume finishes them" in err
    index = _index(results)
    assert [index[n]["status"] for n in index] == ["done", "done", "interrupted", "interrupted"]
    for name in ("synth-walker", "synth-crossing"):
        assert json.loads((results / name / "summary.json").read_text())["status"] == "complete"
    assert not list(results.glob(".*.partial"))
    assert not (results / "synth-walker-2").exists()


@pytest.mark.slow
def test_cut_copies_of_the_pets_clip_give_the_tracks_of_track_alone(tmp_path, client, data):
    import cv2

    cap = cv2.VideoCapture(str(data("pets09-s2l1", "video.avi")))
    cuts = {"pets-a": range(0, 60), "pets-b": range(120, 180)}
    writers = {n: cv2.VideoWriter(str(tmp_path / f"{n}.avi"), cv2.VideoWriter_fourcc(*"MJPG"), 7,
                                  (768, 576)) for n in cuts}
    k = 0
    while k < 180:
        ok, image = cap.read()
        assert ok
        for n, frames in cuts.items():
            if k in frames:
                writers[n].write(image)
        k += 1
    for w in writers.values():
        w.release()
    results = tmp_path / "results"
    rows = run_batch([str(tmp_path / f"{n}.avi") for n in cuts], results, _cfg(), client=client)
    assert [(r["name"], r["status"], r["frames"]) for r in rows] == [("pets-a", "done", 60),
                                                                    ("pets-b", "done", 60)]
    for n in cuts:
        track_job(str(tmp_path / f"{n}.avi"), _cfg(), tmp_path / f"alone-{n}").run()
        tracks = (results / n / "tracks.txt").read_bytes()
        assert tracks == (tmp_path / f"alone-{n}" / "tracks.txt").read_bytes()
        assert tracks.count(b"\n") > 60   # people were tracked


def test_a_suite_started_with_ctrl_c_ignored_starts_its_processes_with_ctrl_c_enabled():
    """A suite run in the background of a shell (``make test &``) starts with SIGINT ignored,
    which its subprocesses would inherit: the Ctrl-C tests' SIGINT would then do nothing."""
    import signal
    import subprocess
    import sys

    from helpers import enable_ctrl_c

    probe = [sys.executable, "-c", "import signal, sys; "
             "sys.exit(signal.getsignal(signal.SIGINT) is not signal.default_int_handler)"]
    before = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        assert subprocess.run(probe).returncode == 1   # what a child inherits: ignored
        enable_ctrl_c()
        assert subprocess.run(probe).returncode == 0
    finally:
        signal.signal(signal.SIGINT, before)
