"""CLEAR-MOT, Identity and HOTA: hand-built scenarios, TrackEval goldens, py-motmetrics values, CLI."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest

from helpers import ann, require
from motiontrack.cli import main
from motiontrack.errors import InputError
from motiontrack.evaluate import clear, hota, mot, pairs, sequence
from motiontrack.io.mot import read_mot
from motiontrack.types import Annotations

GOLDEN = Path(__file__).resolve().parents[1] / "golden"
NA = len(hota.ALPHAS)


def flat(gt_rows, pred_rows, **kw):
    return mot.evaluate_tracking(ann(gt_rows, gt=True), ann(pred_rows), **kw)


# --------------------------------------------------------------------------------------------------
# hand-built scenarios, 10 x 10 boxes: IoU of a box shifted by dx is (10 - dx) * 10 / (200 - (10 - dx) * 10)
# --------------------------------------------------------------------------------------------------
PERFECT = (
    [(1, 1, 0, 0, 10, 10), (1, 2, 20, 0, 10, 10), (2, 1, 1, 0, 10, 10), (2, 2, 21, 0, 10, 10)],
    [(1, 7, 0, 0, 10, 10), (1, 8, 20, 0, 10, 10), (2, 7, 1, 0, 10, 10), (2, 8, 21, 0, 10, 10)],
    {"MOTA": 1.0, "MOTP": 1.0, "IDF1": 1.0, "HOTA": 1.0, "DetA": 1.0, "AssA": 1.0, "LocA": 1.0,
     "TP": 4, "FP": 0, "FN": 0, "IDSW": 0, "Frag": 0, "MT": 2, "PT": 0, "ML": 0},
)

IDSWITCH = (
    [(f, 1, 0, 0, 10, 10) for f in (1, 2, 3, 4)],
    [(1, 1, 0, 0, 10, 10),   # frame 1: track 1 on the object
     (2, 1, 0, 0, 10, 10),   # frame 2: track 1 again
     (3, 2, 0, 0, 10, 10),   # frame 3: track 2 takes over -> one ID switch
     (4, 2, 0, 0, 10, 10)],  # frame 4: track 2 continues
    {"TP": 4, "FP": 0, "FN": 0, "IDSW": 1, "MOTA": (4 - 0 - 1) / 4, "MODA": 1.0,
     "IDTP": 2, "IDFP": 2, "IDFN": 2, "IDF1": 2 / (2 + 0.5 * 2 + 0.5 * 2), "IDP": 2 / 4, "IDR": 2 / 4,
     # each (gt, track) pair: 2 matches, |gt| = 4, |track| = 2 -> A = 2 / (4 + 2 - 2)
     "DetA": 1.0, "AssA": 2 / 4, "HOTA": math.sqrt(1.0 * 2 / 4), "LocA": 1.0},
)

FRAG = (
    [(f, 1, 0, 0, 10, 10) for f in (1, 2, 3, 4, 5)],
    [(1, 1, 0, 0, 10, 10),      # frame 1: tracked
     (2, 1, 0, 0, 10, 10),      # frame 2: tracked
     (3, 1, 50, 50, 10, 10),    # frame 3: box far away -> FN + FP, tracking interrupted
     (4, 1, 0, 0, 10, 10),      # frame 4: tracked again (same id: no switch) -> Frag 1
     (5, 1, 0, 0, 10, 10)],     # frame 5: tracked
    {"TP": 4, "FP": 1, "FN": 1, "IDSW": 0, "Frag": 1, "MOTA": (4 - 1 - 0) / 5,
     "MT": 0, "PT": 1, "ML": 0,  # tracked 4/5 = 0.8 is not > 0.8
     "IDTP": 4, "IDF1": 4 / (4 + 0.5 + 0.5)},
)

FRAG_EMPTY_FRAME = (
    FRAG[0],
    [r for r in FRAG[1] if r[0] != 3],  # frame 3 has no tracker box at all
    # TrackEval skips frames without tracker boxes when tracking continuity is judged: no Frag
    {"TP": 4, "FP": 0, "FN": 1, "IDSW": 0, "Frag": 0, "MOTA": 4 / 5},
)

CONTINUE = (
    [(1, 1, 0, 0, 10, 10), (2, 1, 0, 0, 10, 10)],
    [(1, 1, 0, 0, 10, 10),   # frame 1: track 1 exact (IoU 1)
     (2, 1, 2, 0, 10, 10),   # frame 2: track 1 shifted by 2 -> IoU 80/120 = 2/3
     (2, 2, 0, 0, 10, 10)],  # frame 2: track 2 exact, but CLEAR keeps the continuing track 1
    {"TP": 2, "FP": 1, "FN": 0, "IDSW": 0, "MOTP": (1 + 2 / 3) / 2, "MOTA": (2 - 1) / 2,
     "IDTP": 2, "IDFP": 1, "IDF1": 2 / (2 + 0.5),
     # HOTA matches track 1 too; alpha <= 0.65: 2 TP, 1 FP, AssA 1; alpha >= 0.70: 1 TP, 1 FN, 2 FP,
     # AssA 1 / (2 + 2 - 1); 13 and 6 of the 19 alphas
     "HOTA": (13 * math.sqrt(2 / 3 * 1) + 6 * math.sqrt(1 / 4 * 1 / 3)) / 19,
     "LocA": (13 * (1 + 2 / 3) / 2 + 6 * 1.0) / 19},
)

PREPROC = (
    [(1, 1, 0, 0, 10, 10, 1, 1),     # pedestrian
     (1, 2, 20, 0, 10, 10, 0, 7),    # static person (distractor): the box on it is removed
     (1, 3, 40, 0, 10, 10, 0, 1),    # zero-marked pedestrian: dropped, its box stays an FP
     (1, 4, 60, 0, 10, 10, 0, 3)],   # car: dropped, its box stays an FP
    [(1, 1, 0, 0, 10, 10), (1, 2, 20, 0, 10, 10), (1, 3, 40, 0, 10, 10), (1, 4, 60, 0, 10, 10)],
    {"TP": 1, "FP": 2, "FN": 0, "MOTA": (1 - 2) / 1, "IDF1": 1 / (1 + 0.5 * 2),
     "DetA": 1 / 3, "AssA": 1.0, "HOTA": math.sqrt(1 / 3)},
)

CLASSLESS = (
    [(1, 1, 0, 0, 10, 10, 1, -1), (1, 2, 20, 0, 10, 10, 0, -1)],  # unknown classes: consider only
    [(1, 1, 0, 0, 10, 10), (1, 2, 20, 0, 10, 10)],
    {"TP": 1, "FP": 1, "FN": 0, "MOTA": 0.0},
)


@pytest.mark.parametrize("gt,pred,expected", [PERFECT, IDSWITCH, FRAG, FRAG_EMPTY_FRAME, CONTINUE,
                                              PREPROC, CLASSLESS],
                         ids=["perfect", "idswitch", "frag", "frag-empty-frame", "continue",
                              "preproc", "classless"])
def test_scenarios(gt, pred, expected):
    res = flat(gt, pred)
    for k, v in expected.items():
        assert res[k] == pytest.approx(v, abs=1e-12), k


# --------------------------------------------------------------------------------------------------
# N = 0 (TrackEval's conventions: empty side -> all counts on the other side)
# --------------------------------------------------------------------------------------------------
GT2 = [(1, 1, 0, 0, 10, 10), (2, 1, 0, 0, 10, 10), (2, 2, 30, 0, 10, 10)]


@pytest.mark.parametrize("gt,pred,expected", [
    ([], [], {"TP": 0, "FP": 0, "FN": 0, "MOTA": 0.0, "IDF1": 0.0, "HOTA": 0.0, "LocA": 1.0,
              "MT": 0, "ML": 0}),
    (GT2, [], {"TP": 0, "FP": 0, "FN": 3, "ML": 2, "MOTA": 0.0, "IDFN": 3, "IDF1": 0.0,
               "HOTA": 0.0, "DetA": 0.0, "LocA": 1.0}),
    ([], GT2, {"TP": 0, "FP": 3, "FN": 0, "ML": 0, "MOTA": 0.0, "IDFP": 3, "HOTA": 0.0}),
], ids=["both-empty", "no-predictions", "no-gt"])
def test_empty(gt, pred, expected):
    res = flat(gt, pred)
    for k, v in expected.items():
        assert res[k] == pytest.approx(v, abs=1e-12), k


def test_empty_combined_with_nonempty_recomputes_ratios():
    a = mot.evaluate_sequence(ann(GT2), ann(GT2))       # perfect: TP 3
    b = mot.evaluate_sequence(ann([]), ann(GT2))        # no gt: FP 3
    c = mot.flatten(mot.combine_sequences([a, b]))
    assert c["MOTA"] == pytest.approx((3 - 3) / 3)
    assert c["IDF1"] == pytest.approx(3 / (3 + 0.5 * 3))
    assert c["DetA"] == pytest.approx(3 / (3 + 3))
    assert c["LocA"] == pytest.approx(1.0)


def test_inputs_not_mutated_and_order_irrelevant():
    rng = np.random.default_rng(3)
    gt = ann([(f, i, 15 * i, 0, 10, 10) for f in range(1, 9) for i in range(1, 4)])
    boxes = gt.boxes + rng.uniform(-2, 2, gt.boxes.shape)
    pred = Annotations.from_columns(gt.frames, gt.ids + 10, boxes)
    before = pred.boxes.copy()
    r1 = mot.evaluate_tracking(gt, pred)
    assert np.array_equal(pred.boxes, before)
    # frames in reverse order (rows within a frame keep their order: they break Hungarian ties)
    perm = np.concatenate([np.flatnonzero(pred.frames == f) for f in range(8, 0, -1)])
    r2 = mot.evaluate_tracking(gt, pred.select(perm))
    assert r1 == r2


def test_duplicate_id_in_frame_is_input_error():
    with pytest.raises(InputError, match="id 5 more than once in frame 2"):
        flat(GT2, [(2, 5, 0, 0, 10, 10), (2, 5, 30, 0, 10, 10)])


def test_iou_matches_trackeval_conventions():
    a = np.array([[0, 0, 10, 10], [0, 0, 10, 10], [0, 0, 10, 10]], float)
    b = np.array([[5, 0, 10, 10], [20, 20, 5, 5], [0, 0, 10, 10]], float)
    assert pairs.box_iou_xywh(a, b).tolist() == [50 / 150, 0.0, 1.0]
    assert pairs.box_iou_xywh(np.zeros((0, 4)), np.zeros((0, 4))).shape == (0,)


# --------------------------------------------------------------------------------------------------
# TrackEval goldens (tools/trackeval_golden.py, TrackEval 1.3.0 in its own venv)
# --------------------------------------------------------------------------------------------------
def _golden_cases():
    out = []
    for p in sorted(GOLDEN.glob("*.json")):
        g = json.loads(p.read_text())
        for seq in list(g["sequences"]) + ["combined"]:
            needs_data = any(v.startswith("data:") for i in g["inputs"] for v in (i["gt"], i["pred"]))
            out.append(pytest.param(p.name, seq, id=f"{g['name']}-{seq}",
                                    marks=[pytest.mark.data] if needs_data else []))
    return out


def _resolve(v: str) -> Path:
    return require(*v[5:].split("/")) if v.startswith("data:") else GOLDEN / v


def _ours(g: dict) -> dict[str, dict]:
    per = {}
    for inp in g["inputs"]:
        gt = read_mot(_resolve(inp["gt"]), kind="gt")
        pred = read_mot(_resolve(inp["pred"]), kind="results")
        per[inp["seq"]] = mot.evaluate_sequence(gt, pred,
                                                num_timesteps=g["seq_lengths"][inp["seq"]])
    return per


@pytest.mark.parametrize("name,seq", _golden_cases())
def test_trackeval_golden(name, seq):
    g = json.loads((GOLDEN / name).read_text())
    per = _ours(g)
    res = mot.combine_sequences(per.values()) if seq == "combined" else per[seq]
    ref = g["combined"] if seq == "combined" else g["sequences"][seq]
    ours = {k: v for fam in res.values() for k, v in fam.items()}
    checked = 0
    for k, v in ref.items():
        assert k in ours, f"missing field {k}"
        np.testing.assert_allclose(np.asarray(ours[k], float), np.asarray(v, float),
                                   rtol=0, atol=1e-6, err_msg=f"{seq} {k}")
        checked += 1
    assert checked >= 40


def test_golden_cases_cover_the_tricky_parts():
    g = json.loads((GOLDEN / "tricky-mot17.json").read_text())["combined"]
    assert g["IDSW"] >= 2 and g["Frag"] >= 1 and g["CLR_FP"] >= 3
    gaps = json.loads((GOLDEN / "gaps-mot15.json").read_text())["sequences"]
    assert gaps["EMPTY"]["CLR_TP"] == 0 and gaps["NOGT"]["CLR_FP"] > 0


# --------------------------------------------------------------------------------------------------
# published py-motmetrics values on TUD-Campus
# --------------------------------------------------------------------------------------------------
# py-motmetrics name -> (our flat key, transform). MOTP: py-motmetrics reports the mean distance
# 1 - IoU of the matches; ours (TrackEval, MOTChallenge) the mean IoU. The JSON holds 6 decimals.
MOTMETRICS = {
    "idf1": ("IDF1", None), "idp": ("IDP", None), "idr": ("IDR", None),
    "recall": ("recall", None), "precision": ("precision", None),
    "mostly_tracked": ("MT", None), "partially_tracked": ("PT", None), "mostly_lost": ("ML", None),
    "num_false_positives": ("FP", None), "num_misses": ("FN", None),
    "num_switches": ("IDSW", None), "num_fragmentations": ("Frag", None), "mota": ("MOTA", None),
    "motp_1_minus_iou": ("MOTP", lambda v: 1 - v),
}


@pytest.mark.data
def test_tud_campus_matches_py_motmetrics(data):
    exp = json.loads(data("tud-campus", "expected_motmetrics.json").read_text())
    res = mot.evaluate_tracking(read_mot(data("tud-campus", "gt.txt"), kind="gt"),
                                read_mot(data("tud-campus", "test.txt"), kind="results"))
    for name, (key, tf) in MOTMETRICS.items():
        v = res[key] if tf is None else tf(res[key])
        assert v == pytest.approx(exp[name], abs=1e-6), name
    assert res["MT"] + res["PT"] + res["ML"] == exp["num_unique_objects"]


# --------------------------------------------------------------------------------------------------
# the command
# --------------------------------------------------------------------------------------------------
@pytest.mark.data
def test_cli_json_and_table(data, tmp_path, capsys):
    out = tmp_path / "m.json"
    pf = tmp_path / "pf.csv"
    code = main(["evaluate", "--gt", str(data("tud-campus", "gt.txt")),
                 "--pred", str(data("tud-campus", "test.txt")), "--metrics", "clear,identity,hota",
                 "--json", str(out), "--per-frame", str(pf)])
    assert code == 0
    table = capsys.readouterr().out
    assert "HOTA" in table and "MOTA" in table and "test" in table
    res = json.loads(out.read_text())
    for k in ("HOTA", "DetA", "AssA", "LocA", "MOTA", "MOTP", "IDF1", "IDP", "IDR", "IDSW", "Frag",
              "MT", "PT", "ML", "TP", "FP", "FN"):
        assert k in res, k
    assert res["IDSW"] == 7 and res["FP"] == 13 and res["FN"] == 150
    rows = list(csv.DictReader(pf.read_text().splitlines()))
    assert sum(int(r["TP"]) for r in rows) == res["TP"]
    assert sum(int(r["IDSW"]) for r in rows) == res["IDSW"]


def test_cli_folder_of_trackers_and_frames(tmp_path, capsys):
    gt = tmp_path / "gt.txt"
    gt.write_text("".join(f"{f},1,0,0,10,10,1,-1,-1,-1\n" for f in range(1, 6)))
    folder = tmp_path / "trackers"
    folder.mkdir()
    (folder / "good.txt").write_text("".join(f"{f},3,0,0,10,10,1,-1,-1,-1\n" for f in range(1, 6)))
    (folder / "bad.txt").write_text("".join(f"{f},3,50,0,10,10,1,-1,-1,-1\n" for f in range(1, 6)))
    (folder / "none.txt").write_text("")
    out = tmp_path / "all.json"
    code = main(["evaluate", "--gt", str(gt), "--pred", str(folder), "--frames", "2:4",
                 "--metrics", "clear,identity,hota", "--json", str(out)])
    assert code == 0
    table = capsys.readouterr().out
    assert all(n in table for n in ("good", "bad", "none"))
    res = json.loads(out.read_text())
    assert res["good"]["MOTA"] == 1.0 and res["good"]["TP"] == 3  # frames 2..4 only
    assert res["bad"]["MOTA"] == (0 - 3) / 3 and res["bad"]["FN"] == 3
    assert res["none"]["FN"] == 3 and res["none"]["FP"] == 0


def test_cli_scores_every_pred_and_names_runs_by_their_folder(tmp_path, capsys):
    gt = tmp_path / "gt.txt"
    gt.write_text("".join(f"{f},1,0,0,10,10,1,-1,-1,-1\n" for f in range(1, 6)))
    for run, x in (("run1", 0), ("run2", 50)):         # run2's boxes miss the object
        (tmp_path / run).mkdir()
        (tmp_path / run / "tracks.txt").write_text(
            "".join(f"{f},3,{x},0,10,10,1,-1,-1,-1\n" for f in range(1, 6)))
    other = tmp_path / "other.txt"
    other.write_text("".join(f"{f},4,0,0,10,10,1,-1,-1,-1\n" for f in range(1, 4)))
    out = tmp_path / "all.json"
    code = main(["evaluate", "--gt", str(gt), "--pred", str(tmp_path / "run1" / "tracks.txt"),
                 "--pred", str(tmp_path / "run2" / "tracks.txt"), "--pred", str(other),
                 "--metrics", "clear", "--json", str(out)])
    assert code == 0
    table = capsys.readouterr().out
    assert all(n in table for n in ("run1/tracks", "run2/tracks", "other"))
    res = json.loads(out.read_text())
    assert sorted(res) == ["other", "run1/tracks", "run2/tracks"]
    assert res["run1/tracks"]["MOTA"] == 1.0 and res["run2/tracks"]["FN"] == 5
    assert res["other"]["TP"] == 3 and res["other"]["FN"] == 2
    # the same file twice is a mistake, not two rows
    assert main(["evaluate", "--gt", str(gt), "--pred", str(other), "--pred", str(other)]) == 2
    assert "more than once" in capsys.readouterr().err


@pytest.mark.parametrize("args,msg", [
    (["--gt", "missing.txt", "--pred", "x.txt"], "not found"),
    (["--gt", "{gt}", "--pred", "{gt}", "--metrics", "clear,nope"], "unknown metric"),
    (["--gt", "{bad}", "--pred", "{gt}"], "bad.txt"),
], ids=["missing", "unknown-metric", "malformed"])
def test_cli_bad_input_one_line(tmp_path, capsys, args, msg):
    gt = tmp_path / "gt.txt"
    gt.write_text("1,1,0,0,10,10,1,-1,-1,-1\n")
    bad = tmp_path / "bad.txt"
    bad.write_text("1,1,0,zero,10,10,1\n")
    args = [a.format(gt=gt, bad=bad) for a in args]
    code = main(["evaluate", *args])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert msg in err and len(err.splitlines()) == 1


def test_pair_table_chunking_does_not_change_results(monkeypatch):
    rng = np.random.default_rng(11)
    rows_g, rows_p = [], []
    for f in range(1, 41):
        for i in range(1, 7):
            x = 12 * i + rng.uniform(-3, 3)
            rows_g.append((f, i, x, 0, 10, 10))
            if rng.random() < 0.85:
                rows_p.append((f, (i + (f > 20)) % 7 + 1, x + rng.uniform(-4, 4), rng.uniform(-3, 3),
                               10, 10))
    ref = flat(rows_g, rows_p)
    monkeypatch.setattr(pairs, "_CHUNK", 7)  # many tiny blocks, split mid-sequence
    assert flat(rows_g, rows_p) == ref


def test_evaluate_tracking_with_framewise_and_unknown_metric():
    from motiontrack.errors import ConfigError

    res = flat(PERFECT[0], PERFECT[1], metrics=("clear", "framewise"))
    assert res["MOTA"] == 1.0 and res["pixel_precision"] == pytest.approx(1.0)
    assert "HOTA" not in res
    with pytest.raises(ConfigError, match="unknown metric 'mota'"):
        flat(PERFECT[0], PERFECT[1], metrics=("mota",))


@pytest.mark.parametrize("ignore, expected", [
    # TrackEval (MOTChallenge): the zero-marked gt row is dropped, the box on it stays a false positive
    (False, {"TP": 1, "FP": 1, "FN": 0, "MOTA": (1 - 0 - 1) / 1}),
    # ignore regions (PETS "consider = 0"): the box on the zero-marked row is removed as well
    (True, {"TP": 1, "FP": 0, "FN": 0, "MOTA": 1.0}),
])
def test_zero_marked_rows_as_ignore_regions(ignore, expected):
    gt = [(1, 1, 0, 0, 10, 10, 1, -1),     # frame 1: a person that counts
          (1, 2, 50, 0, 10, 10, 0, -1)]    # frame 1: a person outside the tracking area
    pred = [(1, 5, 0, 0, 10, 10),          # on person 1: a hit
            (1, 6, 51, 0, 10, 10)]         # on the zero-marked person (IoU 90 / 110 >= 0.5)
    res = flat(gt, pred, ignore_zero_marked=ignore)
    for key, value in expected.items():
        assert res[key] == pytest.approx(value), key


def _crowd(seed: int) -> tuple[Annotations, Annotations]:
    """A crowded MOT17-style sequence: people overlapping each other, distractor classes and
    zero-marked rows, a tracker with jitter, misses, identity swaps, false positives, exact
    duplicate boxes (ties for the assignment solver) and a box over two people."""
    rng = np.random.default_rng(seed)
    g_rows, p_rows = [], []
    for f in range(1, 61):
        for i in range(1, 13):
            x, y = 15 * i + 3 * np.sin(f / 5 + i), 5 * (i % 3)
            klass = 7 if i % 5 == 0 else 1
            g_rows.append((f, i, x, y, 24, 60, int(i % 7 != 0), klass))
            if rng.random() < 0.85:
                tid = ((i - 1) ^ 1) + 1 if f > 30 and i <= 6 else i  # three swaps
                box = (x + rng.normal(0, 3), y + rng.normal(0, 3), 24, 60)
                p_rows.append((f, tid, *box))
                if rng.random() < 0.1:
                    p_rows.append((f, 100 + tid, *box))
        for k in range(rng.poisson(2)):
            p_rows.append((f, 500 + 10 * f + k, rng.uniform(0, 200), rng.uniform(0, 20), 24, 60))
        if f % 2:  # apart from the crowd: one wide box over two people (IoU 0.5 with each)
            g_rows += [(f, 50, 400, 0, 20, 60, 1, 1), (f, 51, 420, 0, 20, 60, 1, 1)]
            p_rows.append((f, 60, 400, 0, 40, 60))
    return ann(g_rows, gt=True), ann(p_rows)


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("zero", [False, True])
def test_direct_matches_equal_the_solver_in_every_frame(monkeypatch, seed, zero):
    # where the candidate pairs of a frame share no row they are taken without the solver;
    # forcing the solver into every frame must give the very same numbers, bit for bit
    gt, pred = _crowd(seed)
    seen = []
    shared = pairs.shared_rows
    users = (sequence, clear, hota)  # distractor removal, CLEAR's and HOTA's matching
    for m in users:
        monkeypatch.setattr(m, "shared_rows", lambda *a: seen.append(shared(*a)) or seen[-1])
    fast = mot.evaluate_sequence(gt, pred, ignore_zero_marked=zero)
    hard = np.concatenate(seen)
    assert hard.any() and not hard.all()  # both kinds of frame occur
    for m in users:
        monkeypatch.setattr(m, "shared_rows", lambda t, *a: np.ones(len(t.frames), dtype=bool))
    solver = mot.evaluate_sequence(gt, pred, ignore_zero_marked=zero)
    for fam in solver:
        for k, v in solver[fam].items():
            assert np.array_equal(fast[fam][k], v), (fam, k)


def test_restricted_pair_table_equals_one_computed_on_the_kept_rows():
    gt, pred = _crowd(3)
    rng = np.random.default_rng(3)
    keep_g, keep_p = rng.random(len(gt)) < 0.7, rng.random(len(pred)) < 0.6
    full = pairs.pair_table(gt.frames, gt.boxes, pred.frames, pred.boxes)
    got = pairs.restrict(full, gt.frames, pred.frames, keep_g, keep_p)
    ref = pairs.pair_table(gt.frames[keep_g], gt.boxes[keep_g], pred.frames[keep_p],
                         pred.boxes[keep_p])
    assert len(ref.sim) > 100
    for k in ("frames", "g0", "ng", "p0", "np_", "offsets", "gi", "pi", "sim"):
        assert np.array_equal(getattr(got, k), getattr(ref, k)), k


def test_frame_sums_add_left_to_right():
    rng = np.random.default_rng(5)
    values = rng.random(500) * 10.0 ** rng.integers(-8, 8, 500)
    frames = np.sort(rng.integers(0, 40, 500))
    expected = []
    for f in np.unique(frames):
        s = 0.0
        for v in values[frames == f]:
            s += v
        expected.append(s)
    assert clear._frame_sums(values, frames).tolist() == expected
