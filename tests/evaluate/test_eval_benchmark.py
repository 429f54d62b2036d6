"""``motiontrack evaluate --gt-folder SPLIT --trackers-folder TRACKERS``: a MOTChallenge benchmark,
every sequence and COMBINED, as TrackEval's run_mot_challenge.py scores it."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from motiontrack.cli import main
from motiontrack.evaluate import mot
from motiontrack.io.mot import read_mot, read_seqinfo

REPO = Path(__file__).resolve().parents[2]
GOLDEN = REPO / "tests" / "golden" / "benchmark" / "mot17-mini-trackers.json"
sys.path.insert(0, str(REPO / "tools"))
from mot_benchmark_golden import TRACKERS, make_trackers  # noqa: E402

TRACKING = "clear,identity,hota"
#: our flat key -> TrackEval's pedestrian_detailed.csv column
TRACKEVAL_COLUMNS = {
    "HOTA": "HOTA___AUC", "DetA": "DetA___AUC", "AssA": "AssA___AUC", "LocA": "LocA___AUC",
    "DetRe": "DetRe___AUC", "DetPr": "DetPr___AUC", "AssRe": "AssRe___AUC",
    "AssPr": "AssPr___AUC", "HOTA(0)": "HOTA(0)", "LocA(0)": "LocA(0)", "MOTA": "MOTA",
    "MOTP": "MOTP", "MODA": "MODA", "sMOTA": "sMOTA", "recall": "CLR_Re", "precision": "CLR_Pr",
    "TP": "CLR_TP", "FN": "CLR_FN", "FP": "CLR_FP", "IDSW": "IDSW", "MT": "MT", "PT": "PT",
    "ML": "ML", "Frag": "Frag", "IDF1": "IDF1", "IDR": "IDR", "IDP": "IDP", "IDTP": "IDTP",
    "IDFN": "IDFN", "IDFP": "IDFP",
}


@pytest.fixture
def bench(data, tmp_path):
    """(split folder of mot17-mini, a trackers folder with the three golden trackers, the
    sequence names)."""
    split = data("mot17-mini", "train")
    trackers = tmp_path / "trackers"
    seqs = make_trackers(split, trackers)
    return split, trackers, seqs


def _evaluate(*args: str) -> int:
    return main(["evaluate", *map(str, args)])


def _bench_json(split, trackers, tmp_path, *extra) -> dict:
    out = tmp_path / "bench.json"
    assert _evaluate("--gt-folder", split, "--trackers-folder", trackers, "--json", out,
                     "--force", *extra) == 0
    return json.loads(out.read_text())


@pytest.mark.data
def test_each_sequence_row_equals_single_sequence_evaluate(bench, tmp_path, capsys):
    split, trackers, seqs = bench
    res = _bench_json(split, trackers, tmp_path)
    table = capsys.readouterr().out
    assert all(t in table for t in TRACKERS) and table.count("COMBINED") >= len(TRACKERS)
    single = tmp_path / "single.json"
    for t in TRACKERS:
        for s in seqs:
            assert _evaluate("--gt", split / s / "gt" / "gt.txt", "--pred",
                             trackers / t / "data" / f"{s}.txt", "--metrics", TRACKING,
                             "--json", single, "--force") == 0
            assert res[t][s] == json.loads(single.read_text()), (t, s)


@pytest.mark.data
def test_combined_is_mot_combine_sequences_with_seqinfo_lengths(bench, tmp_path):
    split, trackers, seqs = bench
    res = _bench_json(split, trackers, tmp_path)
    for t in TRACKERS:
        per = [mot.evaluate_sequence(read_mot(split / s / "gt" / "gt.txt", kind="gt"),
                                     read_mot(trackers / t / "data" / f"{s}.txt", kind="results"),
                                     num_timesteps=read_seqinfo(split / s)["seqlength"])
               for s in sorted(seqs)]
        expected = mot.flatten(mot.combine_sequences(per))
        got = {k: v for k, v in res[t]["COMBINED"].items() if k != "scoring"}
        assert got == pytest.approx(expected, rel=0, abs=0)
        # combined from counts, not the mean of the sequences' ratios
        assert got["MOTA"] != pytest.approx(np.mean([res[t][s]["MOTA"] for s in seqs]))


@pytest.mark.data
def test_combined_and_sequences_match_trackeval_run_mot_challenge(bench, tmp_path):
    """Golden values written by TrackEval 1.3.0's scripts/run_mot_challenge.py on the same
    folders (tools/mot_benchmark_golden.py)."""
    split, trackers, seqs = bench
    golden = json.loads(GOLDEN.read_text())
    assert golden["sequences"] == seqs and sorted(golden["trackers"]) == sorted(TRACKERS)
    res = _bench_json(split, trackers, tmp_path)
    checked = 0
    for t, rows in golden["trackers"].items():
        assert list(rows) == seqs + ["COMBINED"]
        for seq, ref in rows.items():
            for ours, theirs in TRACKEVAL_COLUMNS.items():
                assert res[t][seq][ours] == pytest.approx(ref[theirs], rel=0, abs=1e-12), \
                    (t, seq, ours)
                checked += 1
    assert checked == len(TRACKERS) * (len(seqs) + 1) * len(TRACKEVAL_COLUMNS)
    # the trackers differ: the golden case is not three copies of one result
    assert len({round(golden["trackers"][t]["COMBINED"]["HOTA___AUC"], 9) for t in TRACKERS}) == 3


@pytest.mark.data
def test_seqmap_selects_and_combines_only_its_sequences(bench, tmp_path):
    split, trackers, seqs = bench
    seqmap = tmp_path / "seqmap.txt"
    # TrackEval's format: a header, one name per line; blank lines and repeats are harmless
    seqmap.write_text(f"name\n{seqs[3]}\n\n{seqs[1]}\n{seqs[3]}\n")
    res = _bench_json(split, trackers, tmp_path, "--seqmap", seqmap)
    full = _bench_json(split, trackers, tmp_path)
    for t in TRACKERS:
        assert list(res[t]) == [seqs[1], seqs[3], "COMBINED"]
        assert res[t][seqs[1]] == full[t][seqs[1]]
        assert res[t]["COMBINED"]["TP"] == full[t][seqs[1]]["TP"] + full[t][seqs[3]]["TP"]
        assert res[t]["COMBINED"]["IDSW"] == full[t][seqs[1]]["IDSW"] + full[t][seqs[3]]["IDSW"]


@pytest.mark.data
def test_json_schema_tracker_sequence_metrics(bench, tmp_path):
    split, trackers, seqs = bench
    res = _bench_json(split, trackers, tmp_path)
    single = tmp_path / "single.json"
    assert _evaluate("--gt", split / seqs[0] / "gt" / "gt.txt", "--pred",
                     trackers / TRACKERS[0] / "data" / f"{seqs[0]}.txt", "--json", single,
                     "--metrics", TRACKING) == 0
    keys = set(json.loads(single.read_text()))
    assert list(res) == sorted(TRACKERS)
    for rows in res.values():
        assert list(rows) == seqs + ["COMBINED"]
        for flat in rows.values():
            assert set(flat) == keys
            assert all(isinstance(v, (int, float, str)) for v in flat.values())


# --------------------------------------------------------------------------------------------------
# a hand-built benchmark: counts written out
# --------------------------------------------------------------------------------------------------
def _write_split(root: Path, seqs: dict[str, tuple[int, str]]) -> Path:
    for name, (length, gt) in seqs.items():
        (root / name / "gt").mkdir(parents=True)
        (root / name / "gt" / "gt.txt").write_text(gt)
        (root / name / "seqinfo.ini").write_text(f"[Sequence]\nname={name}\nseqLength={length}\n")
    return root


def _rows(*rows) -> str:
    return "".join(",".join(map(str, r)) + "\n" for r in rows)


@pytest.fixture
def small(tmp_path):
    """Two sequences. A: one pedestrian in frames 1-3, tracked exactly. B: one pedestrian in
    frame 1, the tracker's box is elsewhere (a miss and a false positive)."""
    split = _write_split(tmp_path / "split", {
        "A": (10, _rows(*[(f, 1, 0, 0, 10, 10, 1, 1, 1.0) for f in (1, 2, 3)])),
        "B": (5, _rows((1, 1, 0, 0, 10, 10, 1, 1, 1.0))),
    })
    (split / "seqmaps").mkdir()  # neither gt/ nor seqinfo.ini: not a sequence
    trackers = tmp_path / "trackers"
    (trackers / "t" / "data").mkdir(parents=True)
    (trackers / "t" / "data" / "A.txt").write_text(
        _rows(*[(f, 7, 0, 0, 10, 10, 1, -1, -1, -1) for f in (1, 2, 3)]))
    (trackers / "t" / "data" / "B.txt").write_text(_rows((1, 7, 50, 50, 10, 10, 1, -1, -1, -1)))
    return split, trackers


def test_combined_sums_counts_over_sequences(small, tmp_path, capsys):
    split, trackers = small
    res = _bench_json(split, trackers, tmp_path)["t"]
    assert list(res) == ["A", "B", "COMBINED"]
    assert res["A"]["MOTA"] == 1.0                       # 3 TP
    assert res["B"]["MOTA"] == (1 - 1 - 1) / 1           # 1 FN, 1 FP
    c = res["COMBINED"]
    assert (c["TP"], c["FN"], c["FP"]) == (3, 1, 1)
    assert c["MOTA"] == (4 - 1 - 1) / 4                  # not the mean of 1 and -1
    assert c["IDF1"] == 2 * 3 / (2 * 3 + 1 + 1)
    assert "sequence" in capsys.readouterr().out


@pytest.mark.parametrize("change,msg", [
    (lambda s, t: (t / "t" / "data" / "B.txt").unlink(), "Tracker file not found: t/data/B.txt"),
    (lambda s, t: (s / "B" / "seqinfo.ini").unlink(), "seqinfo.ini not found"),
    (lambda s, t: (t / "t" / "data" / "B.txt").write_text(_rows((6, 7, 0, 0, 10, 10, 1))),
     "tracker t: tracker output of B has frame 6, beyond the sequence's seqLength 5"),
    (lambda s, t: (t / "t" / "data" / "A.txt").write_text(
        _rows((1, 7, 0, 0, 10, 10, 1), (1, 7, 5, 5, 10, 10, 1))),
     "tracker t: sequence A: tracker output has id 7 more than once in frame 1"),
], ids=["missing-tracker-file", "missing-seqinfo", "frame-beyond-seqlength", "duplicate-id"])
def test_bad_benchmark_folder_is_one_line_error(small, tmp_path, capsys, change, msg):
    split, trackers = small
    change(split, trackers)
    code = _evaluate("--gt-folder", split, "--trackers-folder", trackers)
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert msg in err and len(err.splitlines()) == 1, err


def test_seqmap_naming_a_missing_sequence_is_an_error(small, tmp_path, capsys):
    split, trackers = small
    seqmap = tmp_path / "map.txt"
    seqmap.write_text("name\nA\nC\n")
    assert _evaluate("--gt-folder", split, "--trackers-folder", trackers, "--seqmap", seqmap) == 2
    assert "sequence 'C' of the seqmap not found" in capsys.readouterr().err


@pytest.mark.parametrize("args,msg", [
    (["--gt-folder", "{split}", "--trackers-folder", "{trackers}", "--gt", "x.txt"],
     "cannot be combined with --gt/--pred"),
    (["--gt-folder", "{split}", "--trackers-folder", "{trackers}", "--pred", "x.txt"],
     "cannot be combined with --gt/--pred"),
    (["--gt-folder", "{split}"], "needs both --gt-folder and --trackers-folder"),
    (["--gt", "x.txt", "--pred", "y.txt", "--seqmap", "m.txt"], "--seqmap selects sequences"),
    (["--gt-folder", "{split}", "--trackers-folder", "{trackers}", "--frames", "1:2"],
     "--frames and --per-frame apply to --gt/--pred"),
    (["--gt-folder", "{split}", "--trackers-folder", "{trackers}", "--metrics", "framewise"],
     "framewise metrics are not combined"),
    ([], "give --gt and --pred"),
    (["--gt", "x.txt"], "give --gt and --pred"),
], ids=["with-gt", "with-pred", "no-trackers", "seqmap-alone", "frames", "framewise", "nothing",
        "gt-only"])
def test_benchmark_options_misused_are_one_line_errors(small, capsys, args, msg):
    split, trackers = small
    code = _evaluate(*[a.format(split=split, trackers=trackers) for a in args])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert msg in err and len(err.splitlines()) == 1, err


# --------------------------------------------------------------------------------------------------
# start-up: the command loads neither scipy.optimize nor OpenCV
# --------------------------------------------------------------------------------------------------
def test_benchmark_command_imports_neither_scipy_optimize_nor_opencv(small):
    split, trackers = small
    code = ("import sys; from motiontrack.cli import main; "
            f"code = main(['evaluate', '--gt-folder', {str(split)!r}, '--trackers-folder', "
            f"{str(trackers)!r}, '-q']); "
            "print(code, sorted(m for m in sys.modules if m.startswith(('scipy', 'cv2'))), "
            "file=sys.stderr)")
    err = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                         text=True).stderr.strip()
    assert err == "0 ['scipy.optimize._lsap']"
