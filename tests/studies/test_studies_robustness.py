"""Studies under interruption and hostile input: a resumed sweep, the report of a study folder
from someone else, the bound on grids, and malformed files and options (one line, exit code 2)."""

from __future__ import annotations

import base64
import json
import re
import urllib.parse

import pytest

import motiontrack.studies.sweep as sw
from motiontrack.cli import main
from motiontrack.config import load_config
from motiontrack.errors import ConfigError, InputError
from motiontrack.io.atomic import DiskFullError
from motiontrack.io.manifest import read_manifest
from motiontrack.studies.report import build_report
from motiontrack.studies.sweep import MAX_RUNS, load_study, study_from_args, versions
from motiontrack.studies.table import read_table, write_table

WALKER = "synth:walker?n_frames=20"
CROSSING = "synth:crossing?n_frames=20"
#: a sweep of 3 thresholds x 2 sequences = 6 runs, in the order r1 walker, r1 crossing, r2 walker...
BASE = ["-q", "sweep", WALKER, CROSSING, "--set", "motion.method=median", "--no-figures"]
GRID = ["--param", "motion.median.threshold=0.1,0.2,0.3"]
SWEEP = BASE + GRID
ALL_RUNS = [(r, s) for r in (1, 2, 3) for s in ("walker", "crossing")]


def fake_run(spec):
    """A run without video: a row whose numbers depend on the grid point and on the base config
    (floats that need all 17 digits of repr, a nan), and the run's two files."""
    thr = dict(spec.params)["motion.median.threshold"]
    row = {"run": spec.run, "sequence": spec.sequence.name, "group": spec.sequence.group,
           **dict(spec.params), "frames": 20,
           "score": thr / 3 + spec.base_config["regions"]["min_area"], "undefined": float("nan")}
    files = {f"{spec.run_dir()}/tracks.txt": f"1,{spec.run},10,10,5,5,1,-1,-1,-1\n",
             f"{spec.run_dir()}/regions.txt": f"1,-1,{thr},10,5,5,1,-1,-1,-1\n"}
    return {"row": row, "files": files}


class Runs:
    """The runs executed (run, sequence), and an optional Ctrl-C at the ``stop_at``-th or a full
    disk at the ``full_at``-th."""

    def __init__(self) -> None:
        self.calls: list[tuple[int, str]] = []
        self.stop_at: int | None = None
        self.full_at: int | None = None

    def __call__(self, spec, should_stop=None):
        self.calls.append((spec.run, spec.sequence.name))
        if self.stop_at is not None and len(self.calls) == self.stop_at:
            raise KeyboardInterrupt
        if self.full_at is not None and len(self.calls) == self.full_at:
            raise DiskFullError(f"{spec.out_dir}/{spec.run_dir()}/motion.webm",
                                "No space left on device")
        return fake_run(spec)


@pytest.fixture
def runs(monkeypatch):
    """Sweeps in this test run :func:`fake_run` (serially) and record what they ran."""
    r = Runs()
    monkeypatch.setattr(sw, "execute_run", r)
    return r


def one_error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert "internal error" not in err[0], err
    return err[0]


# ------------------------------------------------------------------------------- --resume
def test_resume_runs_only_the_unfinished_runs_and_writes_the_same_table(tmp_path, runs):
    full, part = tmp_path / "full", tmp_path / "part"
    assert main(SWEEP + ["-o", str(full)]) == 0
    assert runs.calls == ALL_RUNS

    runs.calls.clear()
    runs.stop_at = 4                                  # Ctrl-C during r2 crossing
    assert main(SWEEP + ["-o", str(part)]) == 130
    assert json.loads((part / "summary.json").read_text())["runs_done"] == 3

    runs.calls.clear()
    runs.stop_at = None
    assert main(SWEEP + ["--resume", "-o", str(part)]) == 0
    assert runs.calls == [(2, "crossing"), (3, "walker"), (3, "crossing")]
    for name in ("results.csv", "summary.csv", "runs/r001/walker/tracks.txt",
                 "runs/r003/crossing/regions.txt"):
        assert (part / name).read_bytes() == (full / name).read_bytes(), name
    assert json.loads((part / "summary.json").read_text()) == {
        "status": "complete", "interrupted": False, "runs_done": 6, "runs": 6}

    runs.calls.clear()                                # a finished study: nothing left to run
    assert main(SWEEP + ["--resume", "-o", str(part)]) == 0
    assert runs.calls == []
    assert (part / "results.csv").read_bytes() == (full / "results.csv").read_bytes()


def test_a_full_disk_ends_the_sweep_with_one_line_keeping_the_finished_runs(tmp_path, runs,
                                                                           capsys):
    part = tmp_path / "part"
    runs.full_at = 3                                  # r2 walker meets a full disk
    assert main(SWEEP + ["-o", str(part)]) == 2
    line = one_error_line(capsys)
    assert "disk full writing" in line and "runs/r002/walker/motion.webm" in line
    summary = json.loads((part / "summary.json").read_text())
    assert summary == {"status": f"disk full writing {part.resolve()}/runs/r002/walker/motion.webm: "
                                 "No space left on device",
                       "interrupted": False, "runs_done": 2, "runs": 6}
    assert [(r["run"], r["sequence"]) for r in read_table(part / "results.csv")] == ALL_RUNS[:2]

    runs.calls.clear()
    runs.full_at = None                               # room again: --resume does the rest
    assert main(SWEEP + ["--resume", "-o", str(part)]) == 0
    assert runs.calls == ALL_RUNS[2:]


def test_resume_reruns_runs_whose_files_are_incomplete(tmp_path, runs):
    out = tmp_path / "study"
    assert main(SWEEP + ["-o", str(out)]) == 0
    table = (out / "results.csv").read_bytes()
    (out / "runs/r001/walker/tracks.txt").write_text("1,9,0,0,1,1,1,-1,-1,-1\n")  # not its digest
    (out / "runs/r002/crossing/regions.txt").unlink()                               # missing
    record = out / "runs/r003/walker/row.json"
    record.write_text(record.read_text()[:30])                                      # truncated
    runs.calls.clear()
    assert main(SWEEP + ["--resume", "-o", str(out)]) == 0
    assert runs.calls == [(1, "walker"), (2, "crossing"), (3, "walker")]
    assert (out / "results.csv").read_bytes() == table


def test_resume_does_not_reuse_runs_made_under_other_settings(tmp_path, runs):
    # study A's runs are in the folder, and its study.json now describes B (A with another base
    # config), as after a study B started over A was stopped before its first run finished
    out, ref = tmp_path / "study", tmp_path / "b"
    assert main(SWEEP + ["-o", str(out)]) == 0
    b_args = SWEEP + ["--set", "regions.min_area=200"]
    assert main(b_args + ["-o", str(ref)]) == 0
    (out / "study.json").write_bytes((ref / "study.json").read_bytes())
    runs.calls.clear()
    assert main(b_args + ["--resume", "-o", str(out)]) == 0
    assert runs.calls == ALL_RUNS                     # every record of A was refused
    assert (out / "results.csv").read_bytes() == (ref / "results.csv").read_bytes()


@pytest.mark.parametrize("change, difference", [
    (GRID + ["--set", "regions.min_area=200"], "base config regions.min_area: 100.0 there, 200.0 now"),
    (["--param", "motion.median.threshold=0.1,0.2,0.4"],
     "values of motion.median.threshold: [0.1,0.2,0.3] there, [0.1,0.2,0.4] now"),
    (GRID + ["--xi", "0.5"], "evaluation xi: 0.75 there, 0.5 now"),
    (GRID + ["--param", "regions.min_size=0.001"],
     "swept parameters: motion.median.threshold there, motion.median.threshold, regions.min_size now"),
])
def test_resume_refuses_a_study_with_other_settings(tmp_path, runs, capsys, change, difference):
    out = tmp_path / "study"
    assert main(SWEEP + ["-o", str(out)]) == 0
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    capsys.readouterr()
    runs.calls.clear()
    assert main(BASE + change + ["--resume", "-o", str(out)]) == 2
    err = one_error_line(capsys)
    assert "cannot resume" in err and difference in err, err
    assert runs.calls == []
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before   # untouched


def test_resume_refuses_a_changed_sequence_list(tmp_path, runs, capsys):
    out = tmp_path / "study"
    assert main(SWEEP + ["-o", str(out)]) == 0
    capsys.readouterr()
    fewer = [a for a in SWEEP if a != CROSSING]
    assert main(fewer + ["--resume", "-o", str(out)]) == 2
    assert "sequences: 2 there, 1 now" in one_error_line(capsys)


def test_resume_of_an_empty_folder_starts_the_study_and_force_conflicts(tmp_path, runs, capsys):
    assert main(SWEEP + ["--resume", "-o", str(tmp_path / "new")]) == 0
    assert runs.calls == ALL_RUNS
    capsys.readouterr()
    assert main(SWEEP + ["--resume", "--force", "-o", str(tmp_path / "new")]) == 2
    assert "--resume" in one_error_line(capsys)


@pytest.mark.slow
def test_resumed_real_sweep_equals_an_uninterrupted_one(tmp_path, monkeypatch):
    real = sw.execute_run
    calls = []

    def stop_second(spec, should_stop=None):
        calls.append(spec.run)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(spec, should_stop)

    args = ["-q", "sweep", WALKER, "--set", "motion.method=median",
            "--param", "motion.median.threshold=0.05,0.2,0.35", "--no-figures"]
    assert main(args + ["-o", str(tmp_path / "full")]) == 0
    monkeypatch.setattr(sw, "execute_run", stop_second)
    assert main(args + ["-o", str(tmp_path / "part")]) == 130
    monkeypatch.setattr(sw, "execute_run", real)
    assert main(args + ["--resume", "-o", str(tmp_path / "part")]) == 0
    for name in ("results.csv", "summary.csv", "runs/r002/walker/tracks.txt"):
        assert ((tmp_path / "part" / name).read_bytes()
                == (tmp_path / "full" / name).read_bytes()), name


# ------------------------------------------------------------------------------- report
def make_study(folder, figures=()):
    """A study folder as a sweep leaves it, without running anything."""
    st = study_from_args([WALKER], None, ["motion.median.threshold=0.1,0.2"],
                         load_config(None, ["motion.method=median"]))
    folder.mkdir(parents=True)
    (folder / "study.json").write_text(json.dumps({**st.as_dict(), "versions": versions(), "runs": 2}))
    write_table([{"run": r, "sequence": "walker", "group": "", "motion.median.threshold": t,
                  "HOTA": 0.5} for r, t in ((1, 0.1), (2, 0.2))], folder / "results.csv")
    for name, data in figures:
        (folder / "figures").mkdir(exist_ok=True)
        (folder / "figures" / name).write_bytes(data)
    return folder


HOSTILE_SVG = (b'<?xml version="1.0"?><svg xmlns="http://www.w3.org/2000/svg" '
               b'onload="alert(\'onload ran\')"><script>alert("script ran")</script>'
               b'<foreignObject><img src="x" onerror="alert(\'onerror ran\')"/></foreignObject>'
               b'</svg></figure><script>alert("after the figure")</script>')


def test_report_embeds_a_hostile_svg_as_an_image_where_no_script_runs(tmp_path):
    study = make_study(tmp_path / "study", [("evil.svg", HOSTILE_SVG), ("plain.png", b"\x89PNG\r\n")])
    html = build_report(study)
    # nothing of the SVG is markup of the page: no script, no event handler, no inline <svg>
    for text in ("<script", "<svg", "onload", "onerror", " ran", "after the figure"):
        assert text not in html, text
    imgs = dict(re.findall(r'<img alt="([^"]+)" src="data:[^;]+;base64,([^"]+)">', html))
    assert base64.b64decode(imgs["evil"]) == HOSTILE_SVG           # shown, as an image
    assert 'src="data:image/svg+xml;base64,' in html
    assert base64.b64decode(imgs["plain"]) == b"\x89PNG\r\n"


def test_report_links_are_relative_paths_whatever_the_file_names(tmp_path):
    study = make_study(tmp_path / "study")
    for name in ("javascript:alert(1).webm", "a #b?c.avi"):
        (study / name).write_bytes(b"\x1a\x45\xdf\xa3")
    html = build_report(study, study / "report.html")
    links = re.findall(r'href="([^"]+)"', html)
    assert len(links) == 2
    for link in links:
        assert not re.match(r"[A-Za-z][A-Za-z0-9+.-]*:", link), link   # no URL scheme
        assert (study / urllib.parse.unquote(link)).is_file(), link


def test_report_leaves_out_figures_outside_the_study_or_unreadable(tmp_path, capsys):
    (tmp_path / "secret.txt").write_text("TOP SECRET")
    study = make_study(tmp_path / "study", [("ok.svg", b"<svg/>"), ("bad.svg", b"\xff\xfe")])
    (study / "figures" / "leak.svg").symlink_to(tmp_path / "secret.txt")
    (study / "figures" / "gone.png").symlink_to(tmp_path / "nothing.png")
    assert main(["report", str(study), "-o", str(tmp_path / "r.html")]) == 0
    html = (tmp_path / "r.html").read_text()
    alts = re.findall(r'<img alt="([^"]+)"', html)
    assert alts == ["bad", "ok"]                      # any bytes are an image; links stay out
    assert base64.b64encode(b"TOP SECRET").decode() not in html
    assert "outside the study folder" in capsys.readouterr().err


def study_json(**change):
    st = study_from_args([WALKER], None, ["motion.median.threshold=0.1,0.2"],
                         load_config(None, ["motion.method=median"]))
    meta = {**st.as_dict(), "versions": versions(), "runs": 2}
    for k, v in change.items():
        if v is None:
            del meta[k]
        else:
            meta[k] = v
    return json.dumps(meta).encode()


#: study.json contents that both report and sweep --replay refuse: (content, message)
BAD_STUDY_JSON = [
    (study_json()[:60], "malformed"),                                         # truncated
    (b"[1, 2]", "expected a JSON object, got a list"),
    (b"\xff\xfe{}", "not UTF-8"),
    (b"[" * 100000 + b"]" * 100000, "malformed"),                            # nested too deep
    (b'{"runs": 1' + b"9" * 5000 + b"}", "malformed"),                        # too many digits
    (study_json(grid="abc"), '"grid" must be a non-empty list, got a string'),
    (study_json(grid=None), 'no "grid"'),
    (study_json(grid=[{"key": "motion.median.threshold", "values": 5}]), "grid entry 1"),
    (study_json(grid=[{"key": "motion.median.threshold", "values": [[1]]}]), "grid entry 1"),
    (study_json(sequences=[{"name": "w", "source": 5}]), '"source" must be a string, got a number'),
    (study_json(sequences=[{"name": "w", "source": WALKER, "colour": 1}]), "unknown key"),
    (study_json(base_config=[1]), '"base_config" must be an object, got a list'),
    (study_json(evaluation={"xi": "abc"}), '"xi", got a string'),
    (study_json(versions=["1"]), '"versions" must be an object'),
    (study_json(save="motion"), '"save" must be a list of strings'),
]


@pytest.mark.parametrize("content, message", BAD_STUDY_JSON)
@pytest.mark.parametrize("command", ["report", "replay"])
def test_malformed_study_json_is_one_line_and_exit_code_2(tmp_path, capsys, content, message, command):
    study = make_study(tmp_path / "study")
    (study / "study.json").write_bytes(content)
    argv = (["report", str(study)] if command == "report"
            else ["sweep", "--replay", str(study), "-o", str(tmp_path / "new")])
    assert main(argv) == 2
    err = one_error_line(capsys)
    assert "study.json" in err and message in err, err
    assert not (tmp_path / "new").exists() and not (study / "report.html").exists()


@pytest.mark.parametrize("change, message", [
    ({"format": 99}, "unsupported study format 99"),
    ({"grid": [{"key": "motion.median.threshold", "values": [2.0]}]}, "must be in"),
    ({"grid": [{"key": "motion.median.threshold=0.1 x", "values": [0.1]}]}, "dotted config key"),
    ({"sequences": [{"name": "..", "source": WALKER}]}, "sequence name"),
    ({"sequences": [{"name": "v", "source": "v.avi", "gt": "/nonexistent/gt.txt"}]},
     "ground truth of sequence v not found"),
])
def test_replay_refuses_settings_out_of_range_before_writing(tmp_path, capsys, change, message):
    study = make_study(tmp_path / "study")
    (study / "study.json").write_bytes(study_json(**change))
    assert main(["-q", "sweep", "--replay", str(study), "-o", str(tmp_path / "new")]) == 2
    assert message in one_error_line(capsys)
    assert not (tmp_path / "new" / "study.json").exists()


@pytest.mark.parametrize("name, content, message", [
    ("results.csv", b"run,sequence\n1,\xff\n", "not UTF-8"),
    ("results.csv", b"", "empty"),
    ("results.csv", b"sequence,x\nw,1\n", "no run column"),
    ("results.csv", b"x\n1\n", "no run, sequence columns"),
    ("results.csv", b"run,sequence,x\n1,w\n", "row 2 has 2 fields, the header 3"),
    ("results.csv", b"run,sequence\n1,w,3\n", "row 2 has 3 fields, the header 2"),
    ("results.csv", b"run,sequence\nabc,w\n", "run must be an integer"),
    ("results.csv", b"run,sequence,run\n1,w,1\n", "repeated column"),
    ("results.csv", b'run,sequence\n1,"' + b"x" * 200000 + b'"\n', "field larger"),
    ("summary.csv", b"a,b\n1,2\n", "no run column"),
])
def test_malformed_tables_are_one_line_and_exit_code_2(tmp_path, capsys, name, content, message):
    study = make_study(tmp_path / "study")
    (study / name).write_bytes(content)
    assert main(["report", str(study)]) == 2
    err = one_error_line(capsys)
    assert name in err and message in err, err


def test_report_to_a_folder_is_refused(tmp_path, capsys):
    study = make_study(tmp_path / "study")
    assert main(["report", str(study), "-o", str(tmp_path)]) == 2
    assert "is a folder" in one_error_line(capsys)


def test_file_names_in_messages_cannot_forge_lines(tmp_path):
    # a file name that holds a newline and a terminal escape: the message stays one line
    name = "a\nmotiontrack: INFO: all fine\x1b[2K"
    bad_manifest = tmp_path / "m.toml"
    bad_manifest.write_text('[[sequence]]\nsource = "synth:walker"\n"b\\nmotiontrack: INFO: x" = 1\n')
    for call in (lambda: build_report(tmp_path / name),
                 lambda: load_study(tmp_path / name),
                 lambda: read_table(tmp_path / name),
                 lambda: read_manifest(bad_manifest)):
        with pytest.raises(InputError) as exc:
            call()
        assert str(exc.value).isprintable(), str(exc.value)


# ------------------------------------------------------------------------------- grid bound
def test_a_grid_over_the_bound_is_refused_before_walking_it():
    with pytest.raises(ConfigError, match=rf"100000000 runs, more than the bound of {MAX_RUNS}"):
        study_from_args([WALKER], None, ["regions.min_area=1:10000:1", "regions.max_area=1:10000:1"],
                        load_config(None))


def test_cli_refuses_a_grid_over_the_bound_before_writing(tmp_path, runs, capsys):
    # 317 x 316 = 100172 runs: just over the bound
    out = tmp_path / "study"
    runs.stop_at = 1                                  # a run that starts ends the sweep at once
    assert main(["sweep", WALKER, "--param", "regions.min_area=1:317:1",
                 "--param", "regions.max_area=1:316:1", "-o", str(out)]) == 2
    err = one_error_line(capsys)
    assert "100172 runs" in err and str(MAX_RUNS) in err, err
    assert not out.exists() and runs.calls == []


def test_param_range_beyond_decimal_is_refused(capsys, tmp_path):
    assert main(["sweep", WALKER, "--param", "regions.min_area=0:1e999999:1e-999999",
                 "-o", str(tmp_path / "s")]) == 2
    assert "too many values" in one_error_line(capsys)


# ------------------------------------------------------------------------------- options
@pytest.mark.parametrize("argv", [
    ["sweep", WALKER, "--param", "motion.median.threshold=0.1", "-j", "0", "-o", "{out}"],
    ["sweep", "--replay", "{study}", "-j", "0", "-o", "{out}"],
    ["tune", "--train", WALKER, "--param", "motion.knn.dist2_threshold=100:400", "-j", "0",
     "-o", "{out}"],
    ["ablate", WALKER, "-j", "0", "--json", "{out}"],
])
def test_zero_jobs_is_refused_before_anything_is_written(tmp_path, capsys, argv):
    if argv[0] == "tune":
        pytest.importorskip("optuna", reason="optuna not installed")
    study = make_study(tmp_path / "study")
    out = tmp_path / "out"
    assert main([a.format(out=out, study=study) for a in argv]) == 2
    assert "-j must be >= 1, got 0" in one_error_line(capsys)
    assert not out.exists()


@pytest.mark.parametrize("manifest, message", [
    ('name = ".."', "sequence name"),
    ('gt = 7', "gt must be a string, got 7"),
    ('name = "a\\u0000b"', "control characters"),
])
def test_manifest_values_that_cannot_name_a_run_folder(tmp_path, capsys, manifest, message):
    m = tmp_path / "m.toml"
    m.write_text(f'[[sequence]]\nsource = "{WALKER}"\n{manifest}\n')
    assert main(["sweep", "--sequences", str(m), "--param", "motion.median.threshold=0.1",
                 "-o", str(tmp_path / "s")]) == 2
    assert message in one_error_line(capsys)
    assert not (tmp_path / "s").exists()


@pytest.mark.parametrize("argv, message", [
    (["--param", "motion.nope=0.1:0.2"], "unknown config key 'motion.nope'"),
    (["--param", "motion.method=[1]"], "choices must be numbers, booleans or strings"),
    (["--param", "motion.method=median,median"], "repeats a choice"),
    (["--param", "motion.knn.dist2_threshold=100:400", "--xi", "5"], "--xi must be in [0, 1]"),
    (["--param", "motion.knn.dist2_threshold=100:400", "--val", "v.avi=/nonexistent/gt.txt"],
     "ground truth of sequence v not found"),
    (["--param", "motion.knn.dist2_threshold=100:400", "--trials", "0"], "--trials must be >= 1"),
])
def test_tune_refuses_bad_options_before_the_first_trial(tmp_path, capsys, monkeypatch, argv, message):
    pytest.importorskip("optuna", reason="optuna not installed")
    import motiontrack.studies.tune as tu

    monkeypatch.setattr(tu, "execute", lambda *a, **k: pytest.fail("a trial ran"))
    assert main(["tune", "--train", WALKER, *argv, "-o", str(tmp_path / "t")]) == 2
    assert message in one_error_line(capsys)
    assert not (tmp_path / "t").exists()


def test_tune_refuses_an_output_that_is_a_file(tmp_path, capsys, monkeypatch):
    pytest.importorskip("optuna", reason="optuna not installed")
    import motiontrack.studies.tune as tu

    monkeypatch.setattr(tu, "execute", lambda *a, **k: pytest.fail("a trial ran"))
    (tmp_path / "t").write_text("")
    assert main(["tune", "--train", WALKER, "--param", "motion.knn.dist2_threshold=100:400",
                 "-o", str(tmp_path / "t")]) == 2
    assert "is a file, not a folder" in one_error_line(capsys)


def test_a_report_into_a_study_a_sweep_still_writes_is_refused(tmp_path, capsys):
    from motiontrack.io.atomic import OutputLock

    study = make_study(tmp_path / "study")
    held = OutputLock(study)                                   # the sweep, still running
    try:
        assert main(["report", str(study)]) == 2
        assert "is in use by another motiontrack run" in one_error_line(capsys)
        assert not (study / "report.html").exists()
        # elsewhere it is written, from the runs finished so far, and says so
        assert main(["report", str(study), "-o", str(tmp_path / "r.html")]) == 0
        assert (tmp_path / "r.html").is_file()
        err = capsys.readouterr().err
        assert "in use by another motiontrack run" in err and "finished so far" in err
    finally:
        held.release()
    assert main(["report", str(study)]) == 0 and (study / "report.html").is_file()
    assert "finished so far" not in capsys.readouterr().err
