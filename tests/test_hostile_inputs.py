"""Hostile and mistaken input to the calibration, annotation and config readers and to the
calibrate, world, gt-stats and follow commands.

Each case ends as one clear line and exit code 2 — never a crash, a traceback, an "internal
error" or a silently wrong result — and a message never quotes more of a file than a short
(at most 20 characters), escaped excerpt of the offending token.
"""

from __future__ import annotations

import logging
import os
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from helpers.cli_errors import user_error
from motiontrack.cli import main
from motiontrack.errors import (EXCERPT_CHARS, InputError, excerpt, location, printable,
                                token_at)

#: a secret in a file given by mistake: messages may show at most its first 20 characters
SECRET = "sk-live-0123456789abcdefghijklmnopqrstuvwxyz"
HIDDEN = SECRET[EXCERPT_CHARS:]

TSAI_TOML = """model = "tsai"
[geometry]
width = 768
height = 576
ncx = 1
nfx = 1
dx = 1
dy = 1
dpx = 0.01
dpy = 0.01
[intrinsic]
focal = 5
kappa1 = 0
cx = 384
cy = 288
sx = 1
[extrinsic]
tx = 0
ty = 0
tz = 5000
rx = 0
ry = 0
rz = 0
"""

YAML_3x3 = """%YAML:1.0
---
image_width: 640
image_height: 480
camera_matrix: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ {data} ]
distortion_coefficients: !!opencv-matrix
   rows: 5
   cols: 1
   dt: d
   data: [ 0., 0., 0., 0., 0. ]
"""


def run(capsys, *argv) -> tuple[int, str]:
    code = main([str(a) for a in argv])
    return code, capsys.readouterr().err


@pytest.fixture
def tracks(tmp_path) -> Path:
    p = tmp_path / "tracks.txt"
    p.write_text("1,1,10,10,5,5,1,-1,-1,-1\n")
    return p


@pytest.fixture
def ground(tmp_path) -> Path:
    """A ground-plane homography camera (1 px = 1 cm) and nothing else."""
    p = tmp_path / "ground.toml"
    p.write_text('model = "homography"\nH = [[0.01, 0, 0], [0, 0.01, 0], [0, 0, 1]]\n'
                 "width = 80\nheight = 60\n")
    return p


@pytest.fixture
def image(tmp_path) -> Path:
    p = tmp_path / "frame.png"
    cv2.imwrite(str(p), np.full((60, 80, 3), 128, np.uint8))
    return p


# ----------------------------------------------------------------------------- the helpers
@pytest.mark.parametrize("text, shown", [
    ("plain", "plain"),
    ("two\nlines", "two\\nlines"),
    ("\x1b[31mred", "\\x1b[31mred"),
    ("tab\there", "tab\\there"),
    ("bidi\u202eevil", "bidi\\u202eevil"),
    ("back\\slash", "back\\slash"),          # printable: left alone, so escaping twice is a no-op
])
def test_printable_escapes_what_could_forge_a_line(text, shown):
    assert printable(text) == shown
    assert printable(printable(text)) == shown


@pytest.mark.parametrize("token, shown", [
    ("ten", "'ten'"),
    (SECRET, "'" + SECRET[:EXCERPT_CHARS] + "...'"),
    ("a\nb", "'a\\nb'"),
    ("it's", "'it\\'s'"),
])
def test_excerpt_is_short_quoted_and_escaped(token, shown):
    assert excerpt(token) == shown


@pytest.mark.parametrize("line, start, token", [
    ("API_KEY=sk-live-abc", 0, "API_KEY"),
    ("root:x:0:0:root:/root:/bin/bash", 0, "root"),
    ("1,2,ten,4", 4, "ten"),
    ("=value", 0, "="),                    # a separator where the token should be: itself
])
def test_token_at_stops_at_a_separator(line, start, token):
    assert token_at(line, start) == token


def test_location_escapes_the_file_name():
    assert location("a\nb.txt", 3, 7) == "a\\nb.txt:3:7"
    assert location("a.txt", 3) == "a.txt:3" and location("a.txt") == "a.txt"


# ------------------------------------------------------------- crashes before OpenCV's parser
def _deep_yaml(tmp_path: Path, kind: str) -> Path:
    n = 50_000
    text = {
        "sequences": "%YAML:1.0\n---\ncamera_matrix: " + "[" * n + "]" * n + "\n",
        "mappings": "%YAML:1.0\n---\ncamera_matrix: " + "{a: " * n + "1" + "}" * n + "\n",
        # a quote the scanner might take for a string: the bracket count still bounds the depth
        "behind a quote": "%YAML:1.0\n---\nname: it's\ncamera_matrix: " + "[" * n + "]" * n + "\n",
        "xml in a .yml": "<?xml version='1.0'?>\n<opencv_storage>" + "<a>" * n + "</a>" * n
                         + "</opencv_storage>\n",
    }[kind]
    p = tmp_path / "deep.yml"
    p.write_text(text)
    return p


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["sequences", "mappings", "behind a quote", "xml in a .yml"])
@pytest.mark.parametrize("command", ["world", "track"])
def test_deeply_nested_camera_yaml_is_refused_before_opencv_parses_it(tmp_path, tracks, kind,
                                                                      command):
    """OpenCV's FileStorage recurses per nesting level: 50,000 levels were a segmentation fault
    (exit 139). A subprocess, so that a crash cannot take the test run with it."""
    cam = _deep_yaml(tmp_path, kind)
    argv = {"world": ["world", "--camera", cam, tracks, "-o", tmp_path / "w.txt"],
            "track": ["track", "synth:walker?n_frames=2", "--camera", cam, "-o", tmp_path / "t"]}
    proc = subprocess.run([sys.executable, "-m", "motiontrack", *map(str, argv[command])],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2, (proc.returncode, proc.stderr[-500:])
    line = [ln for ln in proc.stderr.splitlines() if "error" in ln]
    assert len(line) == 1 and "OpenCV camera YAML" in line[0], proc.stderr[-500:]
    assert any(w in line[0] for w in ("nested deeper", "brackets", "XML content")), line[0]


@pytest.mark.parametrize("what, argv", [
    ("config", lambda t, p: ["track", "synth:walker?n_frames=2", "--config", p, "-o", t / "o"]),
    ("camera", lambda t, p: ["world", "--camera", p, t / "tracks.txt", "-o", t / "w.txt"]),
])
def test_toml_nested_100000_deep_is_a_clear_error(tmp_path, tracks, capsys, what, argv):
    p = tmp_path / "deep.toml"
    p.write_text('model = "tsai"\nx = ' + "[" * 100_000 + "]" * 100_000 + "\n")
    user_error(*run(capsys, *argv(tmp_path, p)), "nested too deeply", str(p))


# ---------------------------------------------------------------------- bounded allocations
def test_show_refuses_a_grid_step_that_would_draw_millions_of_lines(tmp_path, ground, image,
                                                                     capsys):
    """--step 0.000001 grew past 5 GB: the number of lines is worked out and bounded first."""
    line = user_error(*run(capsys, "calibrate", "show", ground, image, "-o", tmp_path / "s.png",
                           "--step", "0.000001"), "grid lines", "1000")
    assert "--step 1e-06" in line
    assert not (tmp_path / "s.png").exists()


@pytest.mark.parametrize("argv, words", [
    (["--step", "nan"], ("--step", "nan")),
    (["--step", "inf"], ("--step", "inf")),
    (["--step", "-1"], ("--step",)),
    (["--extent", "0,nan,0,1"], ("extent", "finite")),
    (["--extent", "0,1e300,0,1"], ("extent", "1e+06")),
    (["--extent", "5,1,0,1"], ("extent", "xmin < xmax")),
])
def test_show_refuses_non_finite_and_reversed_grids(tmp_path, ground, image, capsys, argv, words):
    user_error(*run(capsys, "calibrate", "show", ground, image, "-o", tmp_path / "s.png", *argv),
               *words)


@pytest.mark.parametrize("argv, words", [
    (["calibrate", "chessboard", "{image}", "--pattern", "100000x100000", "-o", "{t}/c.yml"],
     ("at most 100", "100000")),
    (["calibrate", "chessboard", "{image}", "--square", "nan", "-o", "{t}/c.yml"],
     ("--square", "nan")),
    (["calibrate", "lines", "{image}", "--lines", "{t}/l.csv", "--half-width", "1e9",
      "-o", "{t}/c.toml"], ("--half-width", "200")),
    (["calibrate", "lines", "{image}", "--lines", "{t}/l.csv", "--pixel-mm", "inf",
      "-o", "{t}/c.toml"], ("--pixel-mm", "inf")),
    (["calibrate", "ground", "--points", "{t}/p.csv", "--size", "99999999999x5",
      "-o", "{t}/g.toml"], ("--size", "100000")),
    (["gt-stats", "{t}/tracks.txt", "--image-size", "99999999999999x5"], ("--image-size",)),
])
def test_parameters_are_bounded_before_use(tmp_path, tracks, image, capsys, argv, words):
    (tmp_path / "l.csv").write_text("line,axis,value,u,v\nL1,x,0,1,2\nL1,x,0,3,4\n")
    (tmp_path / "p.csv").write_text("0,0,0,0\n100,0,1,0\n0,100,0,1\n100,100,1,1\n")
    args = [a.format(t=tmp_path, image=image) for a in argv]
    user_error(*run(capsys, *args), *words)


def test_a_viper_framespan_cannot_expand_to_billions_of_rows():
    from motiontrack.io.viper import parse_viper

    doc = ('<viper xmlns="http://lamp.cfar.umd.edu/viper#" '
           'xmlns:data="http://lamp.cfar.umd.edu/viperdata#"><config>'
           '<descriptor name="P" type="OBJECT"><attribute name="L" '
           'type="http://lamp.cfar.umd.edu/viperdata#bbox"/></descriptor></config><data>'
           '<sourcefile><object id="1" name="P" framespan="1:1"><attribute name="L">'
           '<data:bbox framespan="1:999999999999" x="1" y="1" width="2" height="2"/>'
           "</attribute></object></sourcefile></data></viper>")
    with pytest.raises(InputError, match="more than 10000000 rows"):
        parse_viper(doc, "v.xml")


def test_sources_far_beyond_the_defaults_get_a_warning(caplog):
    from motiontrack.config import SIZED_FOR, warn_if_oversized

    with caplog.at_level(logging.WARNING, logger="motiontrack"):
        assert warn_if_oversized(8000, 6000, "big.avi")
        assert not warn_if_oversized(*SIZED_FOR, "4k.avi")
        assert not warn_if_oversized(1920, 1080, "hd.avi")
    assert len(caplog.records) == 1
    msg = caplog.records[0].getMessage()
    assert "big.avi" in msg and "8000x6000" in msg and "3840x2160" in msg and "GB" in msg


# ----------------------------------------------------------- user mistakes, not internal errors
def test_output_naming_a_file_or_a_path_under_a_file(tmp_path, tracks, capsys):
    afile = tmp_path / "afile"
    afile.write_text("keep")
    cam = tmp_path / "ground.toml"
    cam.write_text('model = "homography"\nH = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\n')
    user_error(*run(capsys, "world", "--camera", cam, tracks, "-o", afile / "w.txt"),
               "-o", "is a file, not a folder")
    user_error(*run(capsys, "world", "--camera", cam, tracks, "-o", tmp_path),
               "-o", "is a folder")
    user_error(*run(capsys, "gt-stats", tracks, "--image-size", "64x48", "--json",
                    afile / "sub" / "s.json"), "--json", "is a file, not a folder")
    user_error(*run(capsys, "follow", "synth:walker?n_frames=3", "--box", "10,10,20,40",
                    "-o", afile), "-o", "is a file, not a folder")
    user_error(*run(capsys, "follow", "synth:walker?n_frames=3", "--box", "10,10,20,40",
                    "-o", afile / "out"), "-o", "is a file, not a folder")
    assert afile.read_text() == "keep"


def test_output_in_a_read_only_folder(tmp_path, tracks, capsys, monkeypatch):
    import errno
    import tempfile

    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    if os.access(ro, os.W_OK):  # root writes anywhere: fail the way a read-only mount does
        def refuse(*args, dir=None, **kwargs):
            raise OSError(errno.EROFS, "Read-only file system", str(dir))

        monkeypatch.setattr(tempfile, "TemporaryFile", refuse)
    cam = tmp_path / "ground.toml"
    cam.write_text('model = "homography"\nH = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\n')
    try:
        line = user_error(*run(capsys, "world", "--camera", cam, tracks, "-o", ro / "w.txt"),
                          "-o", "cannot write in")
    finally:
        ro.chmod(0o755)
    assert "read-only" in line or "permission denied" in line


def test_a_failed_file_operation_at_the_edge_is_the_users_not_a_bug(monkeypatch, capsys):
    """An OSError naming a file (a disk that fills, a folder that turns read-only mid-run) is
    reported as an error about that file; one without a file name stays an internal error."""
    import errno

    import motiontrack.cli.gt_stats as gt

    def full(args):
        raise OSError(errno.ENOSPC, "No space left on device", "/data/out/stats.json")

    monkeypatch.setattr(gt, "cmd_gt_stats", full)
    code, err = run(capsys, "gt-stats", "x.txt", "--image-size", "64x48")
    user_error(code, err, "/data/out/stats.json", "no space left")

    def bug(args):
        raise OSError("something internal")

    monkeypatch.setattr(gt, "cmd_gt_stats", bug)
    code, err = run(capsys, "gt-stats", "x.txt", "--image-size", "64x48")
    assert code == 1 and "internal error" in err


@pytest.mark.parametrize("name, text, words", [
    ("units.toml", TSAI_TOML.replace('model = "tsai"\n', 'model = "tsai"\nunits = 5\n'),
     ("units must be a table", "got 5")),
    ("unit.toml", TSAI_TOML.replace('model = "tsai"\n',
                                    'model = "tsai"\nunits = {unit_per_metre = "m"}\n'),
     ("unit_per_metre",)),
    ("width.toml", TSAI_TOML.replace("width = 768", "width = inf"), ("width", "finite")),
    ("bool.toml", TSAI_TOML.replace("focal = 5", "focal = true"), ("focal", "number")),
    ("big.toml", TSAI_TOML.replace("tz = 5000", "tz = " + "9" * 400), ("tz", "400 digits")),
    ("digits.toml", TSAI_TOML.replace("tz = 5000", "tz = " + "9" * 5000), ("too many digits",)),
    ("model.toml", "model = {a = 1}\n", ("model must be",)),
    ("h.toml", 'model = "homography"\nH = "abc"\n', ("3x3",)),
    ("hsing.toml", 'model = "homography"\nH = [[0, 0, 0], [0, 0, 0], [0, 0, 1]]\n',
     ("invertible",)),
    ("hw.toml", 'model = "homography"\nH = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\nwidth = inf\n'
                "height = 2\n", ("width", "whole number")),
    ("wrong.yml", YAML_3x3.format(data="1., 0., 320."), ("camera_matrix", "9 values", "got 3")),
    ("huge.yml", YAML_3x3.replace("rows: 3", "rows: 99999").replace("cols: 3", "cols: 99999")
                         .format(data="1."), ("expected a 3x3 matrix", "99999x99999")),
    ("seq.yml", "%YAML:1.0\n---\ncamera_matrix: [1, 2]\n", ("camera_matrix", "OpenCV matrix")),
    ("json.yml", '{"camera_matrix": 5}\n', ("camera_matrix",)),
    ("nosize.yml", YAML_3x3.replace("image_width: 640\n", "").format(
        data="600., 0., 320., 0., 600., 240., 0., 0., 1."), ("image_width",)),
    ("pose.yml", YAML_3x3.format(data="600., 0., 320., 0., 600., 240., 0., 0., 1.")
                 + "ground_rvec: [1, 2, 3]\n", ("ground_rvec", "OpenCV matrix")),
    ("tsai_nan.xml", '<Camera><Geometry width="nan" height="576" ncx="1" nfx="1" dx="1" dy="1" '
                     'dpx="1" dpy="1"/><Intrinsic focal="1" kappa1="0" cx="1" cy="1" sx="1"/>'
                     '<Extrinsic tx="0" ty="0" tz="1" rx="0" ry="0" rz="0"/></Camera>',
     ("width", "finite")),
])
def test_camera_files_with_mistakes(tmp_path, tracks, capsys, name, text, words):
    p = tmp_path / name
    p.write_text(text)
    user_error(*run(capsys, "world", "--camera", p, tracks, "-o", tmp_path / "w.txt"), *words)


@pytest.mark.parametrize("pairs, words", [
    ("0,0,0,0\n1,1,1,0\n2,2,2,0\n3,3,3,0\n", ("lie on one line",)),     # both sets collinear
    ("0,0,0,0\n1,1,1,0\n2,2,0,1\n3,3,1,1\n", ("image points", "one line")),
    ("5,5,1,1\n5,5,1,1\n5,5,1,1\n5,5,1,1\n", ("one point",)),
])
def test_ground_points_that_fit_no_homography(tmp_path, capsys, pairs, words):
    (tmp_path / "p.csv").write_text(pairs)
    user_error(*run(capsys, "calibrate", "ground", "--points", tmp_path / "p.csv",
                    "-o", tmp_path / "g.toml"), *words)
    assert not (tmp_path / "g.toml").exists()


def _onnx_identity() -> bytes:
    """A valid ONNX model (one Identity node, input 1x3x8x8) that is no tracker's network."""
    def varint(n):
        out = b""
        while True:
            b, n = n & 0x7F, n >> 7
            out += bytes([b | 0x80]) if n else bytes([b])
            if not n:
                return out

    def field(f, payload):          # length-delimited field
        return varint(f << 3 | 2) + varint(len(payload)) + payload

    def num(f, n):                  # varint field
        return varint(f << 3) + varint(n)

    def text(f, s):
        return field(f, s.encode())

    shape = field(2, b"".join(field(1, num(1, d)) for d in (1, 3, 8, 8)))
    tensor = field(1, num(1, 1) + shape)
    value = lambda name: text(1, name) + field(2, tensor)  # noqa: E731
    graph = (field(1, text(1, "x") + text(2, "y") + text(4, "Identity")) + text(2, "g")
             + field(11, value("x")) + field(12, value("y")))
    return num(1, 7) + field(8, text(1, "") + num(2, 13)) + field(7, graph)


@pytest.mark.parametrize("model, words", [
    (b"\x00garbage that is no protobuf" * 50, ("backbone", "not a model OpenCV can read")),
    (_onnx_identity(), ("cannot run with the model file", "--param backbone")),
], ids=["not a model", "another network"])
def test_follow_with_a_bad_onnx_model(tmp_path, capsys, model, words):
    p = tmp_path / "model.onnx"
    p.write_bytes(model)
    user_error(*run(capsys, "follow", "synth:walker?n_frames=3", "--box", "10,10,20,40",
                    "--tracker", "nano", "--param", f"backbone={p}", "--param", f"neckhead={p}",
                    "-o", tmp_path / "f"), *words)


@pytest.mark.parametrize("param, words", [
    ("detect_thresh=nan", ("finite",)),
    ("detect_thresh=99999999999999999999", ("out of range",)),
])
def test_follow_parameters_are_checked(tmp_path, capsys, param, words):
    user_error(*run(capsys, "follow", "synth:walker?n_frames=3", "--box", "10,10,20,40",
                    "--tracker", "kcf", "--param", param, "-o", tmp_path / "f"), *words)


# ------------------------------------------------------------------ no file content in messages
def _write(tmp_path: Path, name: str, text: str | bytes) -> Path:
    p = tmp_path / name
    p.write_bytes(text if isinstance(text, bytes) else text.encode())
    return p


CONTENT_CASES = {
    "env file as ground truth": (
        "secret.env", f"API_KEY={SECRET}\n",
        lambda p, t: ["gt-stats", p, "--image-size", "64x48"], ":1:1:"),
    "passwd as point pairs": (
        "passwd", f"root:x:0:0:root:/root:/bin/bash\n{SECRET}:x:1:1::/:/bin/sh\n",
        lambda p, t: ["calibrate", "ground", "--points", p, "-o", t / "g.toml"], ":2"),
    "mot field": (
        "gt.txt", f"1,1,10,10,5,5\n2,1,{SECRET},10,5,5\n",
        lambda p, t: ["gt-stats", p, "--image-size", "64x48"], ":2:5:"),
    "point pairs field": (
        "p.csv", f"1,2,3,4\n1,{SECRET},3,4\n",
        lambda p, t: ["calibrate", "ground", "--points", p, "-o", t / "g.toml"], ":2:3:"),
    "lines csv axis": (
        "l.csv", f"L1,{SECRET},0,1,2\n",
        lambda p, t: ["calibrate", "lines", t / "img.png", "--lines", p, "-o", t / "c.toml"],
        ":1:4:"),
    "cvml attribute": (
        "a.xml", f'<dataset><frame number="{SECRET}"/></dataset>',
        lambda p, t: ["gt-stats", p, "--image-size", "64x48"], ":1:"),
    "cvat flag": (
        "b.xml", f'<annotations><track id="1" label="p"><box frame="0" outside="{SECRET}" '
                 'xtl="1" ytl="1" xbr="2" ybr="2"/></track></annotations>',
        lambda p, t: ["gt-stats", p, "--image-size", "64x48"], ":1:"),
    "viper framespan": (
        "c.xml", '<viper xmlns="http://lamp.cfar.umd.edu/viper#"><config>'
                 '<descriptor name="P" type="OBJECT"><attribute name="L" '
                 'type="http://lamp.cfar.umd.edu/viperdata#bbox"/></descriptor></config>'
                 '<data><sourcefile>'
                 f'<object id="1" name="P" framespan="{SECRET}"/></sourcefile></data></viper>',
        lambda p, t: ["gt-stats", p, "--image-size", "64x48"], "line 1"),
    "json key": (
        "d.json", f'{{"format": "motiontrack", "version": 1, "tracks": [], "{SECRET}": 1}}',
        lambda p, t: ["gt-stats", p, "--image-size", "64x48"], "top level"),
    "json format": (
        "e.json", f'{{"format": "{SECRET}", "version": 1, "tracks": []}}',
        lambda p, t: ["gt-stats", p, "--image-size", "64x48"], "format"),
    "xml entity": (
        "f.xml", f'<?xml version="1.0"?><!DOCTYPE dataset [<!ENTITY x SYSTEM "file:///{SECRET}">]>'
                 "<dataset/>",
        lambda p, t: ["gt-stats", p, "--image-size", "64x48"], "unsafe"),
    "config value": (
        "c.toml", f'[tracker]\nmin_iou = "{SECRET}"\n',
        lambda p, t: ["track", "synth:walker?n_frames=2", "--config", p, "-o", t / "o"],
        "tracker.min_iou"),
    "config key": (
        "k.toml", f'[tracker]\n"{SECRET}" = 1\n',
        lambda p, t: ["track", "synth:walker?n_frames=2", "--config", p, "-o", t / "o"],
        "unknown config key"),
    "camera model": (
        "m.toml", f'model = "{SECRET}"\n',
        lambda p, t: ["world", "--camera", p, t / "tracks.txt", "-o", t / "w.txt"], "model"),
    "tsai attribute": (
        "t.xml", f'<Camera><Geometry width="{SECRET}"/></Camera>',
        lambda p, t: ["world", "--camera", p, t / "tracks.txt", "-o", t / "w.txt"], "width"),
}


@pytest.mark.parametrize("case", list(CONTENT_CASES))
def test_messages_quote_at_most_a_short_excerpt(tmp_path, tracks, image, capsys, case):
    name, text, argv, where = CONTENT_CASES[case]
    (tmp_path / "img.png").write_bytes(image.read_bytes())
    p = _write(tmp_path, name, text)
    line = user_error(*run(capsys, *argv(p, tmp_path)), where)
    assert HIDDEN not in line and "sk-live-0123456789abc" not in line, line
    assert "/bin/bash" not in line and "API_KEY=" not in line


def test_control_characters_in_names_and_content_are_escaped(tmp_path, capsys):
    """A file name or a token with a newline or an escape sequence cannot forge a second
    message line or colour the terminal."""
    evil = tmp_path / "gt\nmotiontrack: error: forged\x1b[2J.txt"
    evil.write_text("1,1,10,10,5,5\n2,1,a\x1b[31m\x07b,10,5,5\n")
    code, err = run(capsys, "gt-stats", evil, "--image-size", "64x48")
    line = user_error(code, err, "\\nmotiontrack: error: forged\\x1b[2J.txt:2:5:",
                      "'a\\x1b[31m\\x07b'")
    assert "\x1b" not in err and err.count("\n") == 1
    assert line.count("motiontrack: error:") == 2   # the forged text stays inside the one line


def test_log_messages_are_one_line_each(capsys):
    from motiontrack.cli import _configure_logging

    _configure_logging(debug=False, quiet=False)
    logging.getLogger("motiontrack.test").warning("read %s", "a\nmotiontrack: error: forged")
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "a\\nmotiontrack: error: forged" in err
