"""Property tests: any input to the annotation readers gives Annotations or our InputError, never
another exception (no crash, no traceback at the CLI edge)."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from motiontrack.errors import InputError, MotionTrackError
from motiontrack.io.annotations import read_annotations
from motiontrack.io.cvat import format_cvat, parse_cvat
from motiontrack.io.cvml import format_cvml, parse_cvml
from motiontrack.io.jsonfmt import format_json, parse_json
from motiontrack.io.mot import format_mot_rows, parse_mot
from motiontrack.types import Annotations

SETTINGS = settings(max_examples=150, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.too_slow])

VALID = Annotations.from_columns(
    frames=[1, 1, 2, 4], ids=[1, 2, 1, 2],
    boxes=[[10, 20, 30, 40], [100.5, 50.25, 20, 60], [12, 21, 30, 40], [103, 53, 21, 61]],
    scores=[1, 0.5, 1, 1], classes=[1, 3, 1, 3], visibility=[1, 0, 1, 0.5],
)
SEEDS = {
    "mot": format_mot_rows(VALID.frames, VALID.ids, VALID.boxes, VALID.scores).encode(),
    "cvml": format_cvml(VALID).encode(),
    "cvat": format_cvat(VALID).encode(),
    "json": format_json(VALID).encode(),
}
# tokens that tend to reach the interesting branches of the parsers
TOKENS = [b"<", b">", b"/>", b'"', b"=", b",", b"\n", b"-1", b"0", b"1e999", b"nan", b"-0",
          b"99999999999999999999999", b"{", b"}", b"[", b"]", b":", b"null", b"true", b"&amp;",
          b"<!DOCTYPE x [<!ENTITY a 'b'>]>", b"&a;", b"\xff\xfe", b"\x00", b"\xef\xbb\xbf",
          b'outside="1"', b'frame="', b'number="', b'"box": [', b"<box ", b"<object id=\"",
          b"<track id=\"3\" label=\"x\">", b"</track>", b"]]>", b"<![CDATA["]


def _check(fn, *args):
    try:
        out = fn(*args)
    except InputError:
        return None
    assert isinstance(out, Annotations)
    n = len(out)
    assert out.boxes.shape == (n, 4) and out.frames.dtype == np.int64
    if n:
        assert out.frames.min() >= 1
        assert np.isfinite(out.boxes).all()
    return out


PARSERS = {
    "mot": lambda b: parse_mot(b.decode("utf-8", "replace"), "results", "fuzz.txt"),
    "cvml": lambda b: parse_cvml(b, "fuzz.xml"),
    "cvat": lambda b: parse_cvat(b, "fuzz.xml"),
    "json": lambda b: parse_json(b, "fuzz.json"),
}
try:  # the ViPER reader lives in another module; fuzz it too when it is there
    from motiontrack.io.viper import format_viper, parse_viper
except ImportError:  # pragma: no cover
    pass
else:
    _INT_VALID = Annotations.from_columns(VALID.frames, VALID.ids, np.round(VALID.boxes))
    SEEDS["viper"] = format_viper(_INT_VALID).encode()
    PARSERS["viper"] = lambda b: parse_viper(b, "fuzz.xml")


@st.composite
def mutated(draw, seed: bytes) -> bytes:
    """A valid file with 1-4 random edits: delete, duplicate, insert token/bytes, replace byte."""
    data = bytearray(seed)
    for _ in range(draw(st.integers(1, 4))):
        op = draw(st.sampled_from(["delete", "duplicate", "token", "bytes", "replace"]))
        i = draw(st.integers(0, len(data)))
        j = min(len(data), i + draw(st.integers(0, 40)))
        if op == "delete":
            del data[i:j]
        elif op == "duplicate":
            data[i:i] = data[i:j]
        elif op == "token":
            data[i:i] = draw(st.sampled_from(TOKENS))
        elif op == "bytes":
            data[i:i] = draw(st.binary(max_size=8))
        elif data:
            data[min(i, len(data) - 1)] = draw(st.integers(0, 255))
    return bytes(data)


@pytest.mark.parametrize("fmt", sorted(PARSERS))
@SETTINGS
@given(raw=st.binary(max_size=300))
def test_random_bytes(fmt, raw):
    _check(PARSERS[fmt], raw)


@pytest.mark.parametrize("fmt", sorted(PARSERS))
@SETTINGS
@given(text=st.text(alphabet=st.characters(codec="utf-8"), max_size=200))
def test_random_text(fmt, text):
    _check(PARSERS[fmt], text.encode("utf-8"))


@pytest.mark.parametrize("fmt", sorted(PARSERS))
@SETTINGS
@given(data=st.data())
def test_mutated_valid_file(fmt, data):
    _check(PARSERS[fmt], data.draw(mutated(SEEDS[fmt])))


def test_seeds_are_valid():
    for fmt, seed in SEEDS.items():
        out = PARSERS[fmt](seed)
        assert len(out) == len(VALID), fmt


@pytest.fixture(scope="module")
def scratch():
    with tempfile.TemporaryDirectory() as d:
        yield Path(d)


@SETTINGS
@given(data=st.data())
def test_auto_detection_on_mutated_files(scratch, data):
    """read_annotations: detection + dispatch on a mutated file of any format."""
    fmt = data.draw(st.sampled_from(sorted(SEEDS)))
    p = scratch / "fuzz.dat"
    p.write_bytes(data.draw(mutated(SEEDS[fmt])))
    _check(read_annotations, p)


@pytest.mark.parametrize("line", ["1e300,1,1,1,1,1", "1,1e300,1,1,1,1", "1,1,1,1,1,1,1,1e300,1"])
def test_mot_out_of_range_integers(line):
    _check(lambda b: parse_mot(b.decode(), "gt", "fuzz.txt"), line.encode())


_ENCODING_CASES = [fmt for fmt in sorted(PARSERS) if fmt in ("cvml", "cvat", "viper")]


@pytest.mark.parametrize("fmt", _ENCODING_CASES)
def test_unknown_xml_encoding_declaration(fmt):
    """Found by a longer fuzz run: an XML declaration naming an unknown encoding."""
    seed = SEEDS[fmt].replace(b"utf-8", b"TF-8").replace(b"UTF-8", b"TF-8")
    assert b'encoding="TF-8"' in seed or b"encoding='TF-8'" in seed
    with pytest.raises(InputError):
        PARSERS[fmt](seed)


# ------------------------------------------------------------ camera and calibration readers
def _camera_seeds() -> dict[str, bytes]:
    """A valid file of each camera kind, as bytes (written once through the writers)."""
    from motiontrack.calibrate.chessboard import OpenCVCamera, write_opencv_yaml
    from motiontrack.calibrate.ground import GroundHomography, write_ground_toml
    from motiontrack.calibrate.tsai import TsaiCamera, write_tsai_toml, write_tsai_xml

    tsai = TsaiCamera(width=768, height=576, ncx=768, nfx=768, dx=0.01, dy=0.01, dpx=0.01,
                      dpy=0.01, focal=6.0, kappa1=1e-4, cx=384, cy=288, sx=1.0, tx=0, ty=1000,
                      tz=8000, rx=2.2, ry=0.0, rz=0.0)
    cv = OpenCVCamera(K=np.array([[600.0, 0, 320], [0, 600, 240], [0, 0, 1]]), dist=np.zeros(5),
                      size=(640, 480), rvec=np.array([2.2, 0, 0]), tvec=np.array([0, 1.0, 6]))
    with tempfile.TemporaryDirectory() as d:
        out = {}
        for name, write in (("cam.xml", lambda p: write_tsai_xml(tsai, p)),
                            ("cam.toml", lambda p: write_tsai_toml(tsai, p)),
                            ("ground.toml", lambda p: write_ground_toml(
                                GroundHomography(H=np.diag([0.01, 0.01, 1.0])), p)),
                            ("cam.yml", lambda p: write_opencv_yaml(p, cv))):
            write(Path(d) / name)
            out[name] = (Path(d) / name).read_bytes()
    return out


CAMERA_SEEDS = _camera_seeds()


def _check_camera(path: Path) -> None:
    """A camera file gives a camera that maps pixels to the ground, or our InputError."""
    from motiontrack.calibrate.camera import load_camera

    try:
        cam = load_camera(path)
    except InputError:
        return
    try:
        xy = cam.image_to_world(np.array([[10.0, 20.0], [300.0, 400.0]]))
    except MotionTrackError:  # e.g. an OpenCV camera without a ground pose
        return
    assert xy.shape == (2, 2)


@SETTINGS
@given(data=st.data())
def test_camera_readers_on_mutated_files(scratch, data):
    name = data.draw(st.sampled_from(sorted(CAMERA_SEEDS)))
    p = scratch / name
    p.write_bytes(data.draw(mutated(CAMERA_SEEDS[name])))
    _check_camera(p)


def test_camera_seeds_are_valid(scratch):
    from motiontrack.calibrate.camera import load_camera

    for name, seed in CAMERA_SEEDS.items():
        (scratch / name).write_bytes(seed)
        assert load_camera(scratch / name).image_to_world(np.array([[10.0, 20.0]])).shape == (1, 2)


_TOML_VALUES = st.recursive(
    st.one_of(st.integers(min_value=-(10**30), max_value=10**30), st.floats(),
              st.booleans(), st.text(max_size=30)),
    lambda inner: st.one_of(st.lists(inner, max_size=4),
                            st.dictionaries(st.text(max_size=8), inner, max_size=4)),
    max_leaves=12)


@SETTINGS
@given(data=st.data(), value=_TOML_VALUES)
def test_camera_toml_with_any_value_anywhere(data, value):
    """Any TOML value in place of any entry of a valid camera TOML: a camera or InputError."""
    from motiontrack.calibrate.ground import ground_from_toml_doc
    from motiontrack.calibrate.tsai import tsai_from_toml_doc
    from motiontrack.io.tomlfile import parse_toml

    name = data.draw(st.sampled_from(["cam.toml", "ground.toml"]))
    doc = parse_toml(CAMERA_SEEDS[name].decode(), name)
    tables = [doc] + [v for v in doc.values() if isinstance(v, dict)]
    table = data.draw(st.sampled_from(tables))
    table[data.draw(st.sampled_from(sorted(table)))] = value
    read = tsai_from_toml_doc if name == "cam.toml" else ground_from_toml_doc
    try:
        cam = read(doc, name)
    except InputError:
        return
    assert cam.image_to_world(np.array([[384.0, 500.0]])).shape == (1, 2)


@pytest.mark.parametrize("reader", ["toml", "points", "lines", "seqinfo"])
@SETTINGS
@given(raw=st.binary(max_size=300))
def test_text_readers_on_random_bytes(scratch, reader, raw):
    """TOML, point pairs, grid lines and seqinfo.ini: their value or InputError, nothing else."""
    from motiontrack.calibrate.ground import read_point_pairs
    from motiontrack.cli.calibrate import read_lines_csv
    from motiontrack.io.mot import read_seqinfo
    from motiontrack.io.tomlfile import read_toml

    p = scratch / f"fuzz.{reader}"
    p.write_bytes(raw)
    read = {"toml": read_toml, "points": read_point_pairs, "lines": read_lines_csv,
            "seqinfo": read_seqinfo}[reader]
    try:
        out = read(p)
    except InputError:
        return
    if reader == "points":
        assert all(np.isfinite(a).all() for a in out)
    if reader == "lines":
        assert all(np.isfinite(pts).all() for _, _, _, pts in out)
