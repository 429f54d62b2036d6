"""Annotation formats: PETS CVML, CVAT for video 1.1, motiontrack JSON, auto-detection, safe XML."""

from __future__ import annotations

import json

import numpy as np
import pytest

from motiontrack.errors import ConfigError, InputError
from motiontrack.io.annotations import detect_format, read_annotations, write_annotations
from motiontrack.io.cvat import format_cvat, parse_cvat, read_cvat, write_cvat
from motiontrack.io.cvml import format_cvml, parse_cvml, read_cvml, write_cvml
from motiontrack.io.jsonfmt import format_json, parse_json, read_json, write_json
from motiontrack.io.mot import read_mot
from motiontrack.types import Annotations

COLS = ("frames", "ids", "boxes", "scores", "consider", "classes", "visibility", "world")


def sorted_rows(a: Annotations) -> Annotations:
    return a.select(np.lexsort((a.ids, a.frames)))


def assert_same(a: Annotations, b: Annotations, cols=COLS, atol: float = 0.0) -> None:
    a, b = sorted_rows(a), sorted_rows(b)
    assert len(a) == len(b)
    for c in cols:
        x, y = getattr(a, c), getattr(b, c)
        if atol and x.dtype.kind == "f":
            np.testing.assert_allclose(x, y, rtol=0, atol=atol, err_msg=c)
        else:
            np.testing.assert_array_equal(x, y, err_msg=c)


def sample() -> Annotations:
    """Three ids over frames 1..5 with a gap (id 2 absent in frame 3) and an anonymous row."""
    return Annotations.from_columns(
        frames=[1, 1, 2, 2, 3, 4, 4, 5, 5],
        ids=[1, 2, 1, 2, 1, 1, 2, 1, -1],
        boxes=[[10, 20, 30, 40], [100.5, 50.25, 20, 60], [12, 21, 30, 40], [101, 51, 20, 60],
               [14, 22, 30.125, 40], [16, 23, 30, 40], [103, 53, 21, 61], [18, 24, 30, 40],
               [300, 200, 10, 10]],
        scores=[1, 1, 0.9, 1, 1, 0.5, 1, 1, 0.25],
        consider=[True, True, True, False, True, True, True, True, True],
        classes=[1, 3, 1, 3, 1, 1, 3, 1, -1],
        visibility=[1.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0, 1.0],
        world=[[1, 2, 0]] + [[-1, -1, -1]] * 8,
    )


# --------------------------------------------------------------------------------------------- CVML

CVML_TINY = b"""<?xml version='1.0' encoding='utf-8'?>
<dataset name="tiny">
  <frame number="0">
    <objectlist>
      <object id="9"><box h="20" w="10" xc="15" yc="30" /></object>
      <object id="4"><box h="4" w="2" xc="1" yc="2" /><orientation>90</orientation></object>
    </objectlist>
  </frame>
  <frame number="1"><objectlist /></frame>
  <frame number="7">
    <objectlist><object id="9"><box h="21" w="11" xc="16.5" yc="31.5" /></object></objectlist>
  </frame>
</dataset>
"""


def test_cvml_tiny_maps_frames_and_centres():
    a = parse_cvml(CVML_TINY, "tiny.xml")
    np.testing.assert_array_equal(a.frames, [0 + 1, 0 + 1, 7 + 1])  # number + 1
    np.testing.assert_array_equal(a.ids, [9, 4, 9])
    np.testing.assert_array_equal(a.boxes, [[15 - 10 / 2, 30 - 20 / 2, 10, 20],
                                            [1 - 2 / 2, 2 - 4 / 2, 2, 4],
                                            [16.5 - 11 / 2, 31.5 - 21 / 2, 11, 21]])
    assert a.meta["format"] == "cvml" and a.meta["name"] == "tiny"
    assert (a.scores == 1).all() and a.consider.all() and (a.classes == -1).all()


@pytest.mark.data
def test_cvml_pets_equals_mot15(data):
    """The PETS CVML and the MOT15 CSV are the same annotation: frames/ids exactly, left/top within
    the MOT15 rounding to whole pixels, width/height within MOT15's 5 significant digits."""
    cv = sorted_rows(read_annotations(data("pets09-s2l1", "gt_cvml.xml")))
    mot = sorted_rows(read_mot(data("pets09-s2l1", "gt_mot15.txt"), kind="gt"))
    assert cv.meta["format"] == "cvml"
    assert len(cv) == len(mot) == 1874
    np.testing.assert_array_equal(cv.frames, mot.frames)
    np.testing.assert_array_equal(cv.ids, mot.ids)
    assert cv.frames.min() == 1 and cv.frames.max() == 300
    assert np.abs(cv.boxes[:, :2] - mot.boxes[:, :2]).max() <= 0.51
    assert np.mean(np.round(cv.boxes[:, :2]) == mot.boxes[:, :2]) > 0.99
    np.testing.assert_allclose(cv.boxes[:, 2:], mot.boxes[:, 2:], rtol=5e-5)


@pytest.mark.data
def test_cvml_pets_round_trip(data, tmp_path):
    a = read_cvml(data("pets09-s2l1", "gt_cvml.xml"))
    write_cvml(a, tmp_path / "out.xml")
    assert_same(read_annotations(tmp_path / "out.xml"), a, cols=("frames", "ids", "boxes"),
                atol=1e-9)


def test_cvml_round_trip_and_empty(tmp_path):
    a = sample()
    write_annotations(a, tmp_path / "a.xml", fmt="cvml")
    back = read_cvml(tmp_path / "a.xml")
    assert_same(back, a, cols=("frames", "ids", "boxes"), atol=1e-9)
    write_cvml(Annotations.empty(), tmp_path / "e.xml")
    assert len(read_cvml(tmp_path / "e.xml")) == 0
    # frames 1..5 all present, frame 3 has only id 1
    assert format_cvml(a).count("<frame ") == 5


@pytest.mark.parametrize("body, where", [
    (b'<dataset>\n<frame number="x"/>\n</dataset>', ":2: <frame>: attribute number='x'"),
    (b'<dataset>\n<frame number="-1"/>\n</dataset>', ":2: <frame>: attribute number=-1 out of"),
    (b'<dataset><frame number="0"><objectlist>\n<object id="1"/>\n</objectlist></frame></dataset>',
     ":2: <object>: object without a <box>"),
    (b'<dataset><frame number="0"><objectlist><object id="1">\n<box xc="1" yc="1" w="0" h="2"/>'
     b'</object></objectlist></frame></dataset>', ":2: <box>: box width and height must be > 0"),
    (b'<dataset><frame number="0"><objectlist><object id="1">\n<box xc="nan" yc="1" w="1" h="2"/>'
     b'</object></objectlist></frame></dataset>', ":2: <box>: attribute xc='nan' is not finite"),
    (b'<dataset><frame number="0"><objectlist>\n<object id="1"><box xc="1" yc="1" w="1" h="2"/>'
     b'</object>\n<object id="1"><box xc="1" yc="1" w="1" h="2"/></object></objectlist></frame>'
     b'</dataset>', ":3: <object>: object id=1 appears twice"),
    (b'<dataset>\n<frame number="0">\n</dataset>', "f.xml:3:2: malformed XML: mismatched tag"),
    (b'<annotations/>', ":1: <annotations>: not a PETS CVML file"),
])
def test_cvml_errors_name_line_and_element(body, where):
    with pytest.raises(InputError) as err:
        parse_cvml(body, "f.xml")
    assert "f.xml" in str(err.value) and where in str(err.value)


# --------------------------------------------------------------------------------------------- CVAT

CVAT_TINY = b"""<?xml version="1.0" encoding="utf-8"?>
<annotations>
  <version>1.1</version>
  <meta><task><labels>
    <label><name>person</name></label>
    <label><name>Forklift</name></label>
  </labels></task></meta>
  <track id="0" label="person" source="manual">
    <box frame="0" outside="0" occluded="0" keyframe="1" xtl="10" ytl="20" xbr="40" ybr="80"/>
    <box frame="1" outside="0" occluded="1" keyframe="0" xtl="11" ytl="20" xbr="41" ybr="80"/>
    <box frame="2" outside="1" occluded="0" keyframe="1" xtl="11" ytl="20" xbr="41" ybr="80"/>
    <box frame="5" outside="0" occluded="0" keyframe="1" xtl="20" ytl="20" xbr="50" ybr="80"/>
    <polygon frame="5" outside="0" occluded="0" keyframe="1" points="1,2;3,4;5,6"/>
  </track>
  <track id="3" label="Forklift" source="manual">
    <box frame="1" outside="0" occluded="0" keyframe="1" xtl="0.5" ytl="0.25" xbr="100.5" ybr="50.25">
      <attribute name="loaded">true</attribute>
    </box>
    <box frame="2" outside="1" occluded="0" keyframe="1" xtl="0.5" ytl="0.25" xbr="100.5" ybr="50.25"/>
  </track>
</annotations>
"""


def test_cvat_tiny_outside_rows_are_not_boxes():
    a = parse_cvat(CVAT_TINY, "t.xml")
    # track 0: frames 0, 1 then outside at 2 (a gap), back at 5; track 3: frame 1 only
    np.testing.assert_array_equal(a.frames, [0 + 1, 1 + 1, 5 + 1, 1 + 1])
    np.testing.assert_array_equal(a.ids, [0, 0, 0, 3])
    np.testing.assert_array_equal(a.boxes, [[10, 20, 40 - 10, 80 - 20], [11, 20, 41 - 11, 80 - 20],
                                            [20, 20, 50 - 20, 80 - 20],
                                            [0.5, 0.25, 100.5 - 0.5, 50.25 - 0.25]])
    np.testing.assert_array_equal(a.visibility, [1.0, 0.0, 1.0, 1.0])  # occluded → 0
    np.testing.assert_array_equal(a.classes, [1, 1, 1, 1000])  # person = MOT pedestrian 1
    assert a.meta["labels"] == {1: "person", 1000: "Forklift"}


def test_cvat_round_trip_with_gaps_and_anonymous_rows(tmp_path):
    a = sample()
    write_cvat(a, tmp_path / "a.xml")
    text = (tmp_path / "a.xml").read_text()
    # id 2 has a gap (frames 2 → 4, CVAT 1 → 3): closed by an outside box at CVAT frame 2;
    # id 2 ends at frame 4 < last frame 5: one more outside box at CVAT frame 4
    assert text.count('outside="1"') == 2
    back = read_annotations(tmp_path / "a.xml")
    assert back.meta["format"] == "cvat"
    named = back.select(back.ids != 3)  # the anonymous row got the fresh id max + 1 = 3
    assert_same(named, a.select(a.ids >= 0), cols=("frames", "ids", "boxes", "classes",
                                                   "visibility"), atol=1e-9)
    anon = back.select(back.ids == 3)
    np.testing.assert_array_equal(anon.frames, [5])
    assert "<name>car</name>" in text and "<name>pedestrian</name>" in text


def test_cvat_custom_labels_survive_round_trip(tmp_path):
    a = parse_cvat(CVAT_TINY, "t.xml")
    write_cvat(a, tmp_path / "b.xml")
    back = read_cvat(tmp_path / "b.xml")
    assert_same(back, a, cols=("frames", "ids", "boxes", "classes", "visibility"), atol=1e-9)
    assert back.meta["labels"][1000] == "Forklift"


def test_cvat_images_export_reads_anonymous_boxes():
    body = (b'<annotations><version>1.1</version>\n<image id="4" name="f4.jpg" width="9" height="9">'
            b'\n<box label="car" occluded="0" xtl="1" ytl="2" xbr="3" ybr="5"/></image>'
            b'</annotations>')
    a = parse_cvat(body, "i.xml")
    np.testing.assert_array_equal(a.frames, [4 + 1])
    np.testing.assert_array_equal(a.ids, [-1])
    np.testing.assert_array_equal(a.classes, [3])
    np.testing.assert_array_equal(a.boxes, [[1, 2, 3 - 1, 5 - 2]])


@pytest.mark.parametrize("body, where", [
    (b'<annotations>\n<track id="0">\n</track></annotations>', ":2: <track>: track without a"),
    (b'<annotations><track id="0" label="a">\n<box frame="0" xtl="5" ytl="1" xbr="5" ybr="3"/>'
     b'</track></annotations>', ":2: <box>: box needs xbr > xtl"),
    (b'<annotations><track id="0" label="a">\n<box frame="0" outside="2" xtl="1" ytl="1" '
     b'xbr="5" ybr="3"/></track></annotations>', ":2: <box>: attribute outside='2'"),
    (b'<annotations><track id="0" label="a"><box frame="0" xtl="1" ytl="1" xbr="5" ybr="3"/>\n'
     b'<box frame="0" xtl="1" ytl="1" xbr="5" ybr="3"/></track></annotations>',
     ":2: <box>: track id=0 has two boxes in frame 0"),
    (b'<annotations><track id="0" label="a">\n<box xtl="1" ytl="1" xbr="5" ybr="3"/></track>'
     b'</annotations>', ":2: <box>: missing attribute 'frame'"),
    (b'<dataset/>', ":1: <dataset>: not a CVAT file"),
])
def test_cvat_errors_name_line_and_element(body, where):
    with pytest.raises(InputError) as err:
        parse_cvat(body, "c.xml")
    assert "c.xml" in str(err.value) and where in str(err.value)


def test_cvat_writer_refuses_duplicate_id_in_a_frame():
    a = Annotations.from_columns([1, 1], [5, 5], [[0, 0, 1, 1], [2, 2, 1, 1]])
    with pytest.raises(InputError, match="id 5 has two boxes in frame 1"):
        format_cvat(a)


@pytest.mark.data
def test_cvat_pets_round_trip(data, tmp_path):
    a = read_cvml(data("pets09-s2l1", "gt_cvml.xml"))
    write_annotations(a, tmp_path / "p.xml", fmt="cvat")
    assert_same(read_annotations(tmp_path / "p.xml"), a, cols=("frames", "ids", "boxes"),
                atol=1e-9)


# --------------------------------------------------------------------------------------------- JSON


def test_json_round_trip_is_exact(tmp_path):
    a = sample()
    write_json(a, tmp_path / "a.json", meta={"sequence": "tiny"})
    back = read_json(tmp_path / "a.json")
    assert_same(back, a)
    assert back.meta["json_meta"] == {"sequence": "tiny"}
    write_annotations(back, tmp_path / "again.json")  # the file's meta survives a re-write
    assert read_json(tmp_path / "again.json").meta["json_meta"] == {"sequence": "tiny"}
    doc = json.loads((tmp_path / "a.json").read_text())
    assert doc["format"] == "motiontrack" and doc["version"] == 1
    assert [t["id"] for t in doc["tracks"]] == [-1, 1, 2]
    # defaults are omitted: the first box of id 1 has only frame, box, class, visibility, world
    assert doc["tracks"][1]["boxes"][0] == {"frame": 1, "box": [10.0, 20.0, 30.0, 40.0],
                                            "class": 1, "visibility": 1.0, "world": [1.0, 2.0, 0.0]}


def test_json_minimal_document_and_empty():
    a = parse_json('{"format": "motiontrack", "version": 1, "tracks": '
                   '[{"id": 3, "boxes": [{"frame": 2, "box": [1, 2, 3, 4]}]}]}')
    np.testing.assert_array_equal(a.frames, [2])
    np.testing.assert_array_equal(a.boxes, [[1, 2, 3, 4]])
    assert a.scores[0] == 1.0 and a.consider[0] and a.classes[0] == -1
    assert len(parse_json(format_json(Annotations.empty()))) == 0


GOOD_BOX = '{"frame": 1, "box": [0, 0, 1, 1]}'


@pytest.mark.parametrize("text, where", [
    ("", "j.json:1:1: malformed JSON"),
    ('{"format": "motiontrack",\n "version": 1,\n "tracks": [}', "j.json:3:13: malformed JSON"),
    ("[]", "top level: expected an object"),
    ('{"format": "viper", "version": 1, "tracks": []}', '"format" must be'),
    ('{"format": "motiontrack", "version": 2, "tracks": []}', "unsupported version 2"),
    ('{"format": "motiontrack", "version": 1}', "missing required key 'tracks'"),
    ('{"format": "motiontrack", "version": 1, "tracks": [], "trakcs": []}', "unknown key(s) 'trakcs'"),
    ('{"format": "motiontrack", "version": 1, "tracks": [{"id": 1.5, "boxes": []}]}',
     "tracks[0].id: expected an integer"),
    ('{"format": "motiontrack", "version": 1, "tracks": [{"id": 1, "boxes": [' + GOOD_BOX +
     ', {"frame": 0, "box": [0, 0, 1, 1]}]}]}', "tracks[0].boxes[1].frame: 0 out of range"),
    ('{"format": "motiontrack", "version": 1, "tracks": [{"id": 1, "boxes": ['
     '{"frame": 1, "box": [0, 0, 1]}]}]}', "tracks[0].boxes[0].box: expected a list of 4"),
    ('{"format": "motiontrack", "version": 1, "tracks": [{"id": 1, "boxes": ['
     '{"frame": 1, "box": [0, 0, -1, 1]}]}]}', "width and height must be > 0"),
    ('{"format": "motiontrack", "version": 1, "tracks": [{"id": 1, "boxes": ['
     '{"frame": 1, "box": [0, 0, 1, 1], "score": NaN}]}]}', "non-finite number NaN"),
    ('{"format": "motiontrack", "version": 1, "tracks": [{"id": 1, "boxes": ['
     '{"frame": 1, "box": [0, 0, 1, 1], "consider": 1}]}]}', "consider: expected true or false"),
    ('{"format": "motiontrack", "version": 1, "tracks": [{"id": 1, "boxes": ['
     '{"frame": 1, "box": [0, 0, 1, 1], "score": 1e999}]}]}', "expected a finite number"),
    ("[" * 100000, "j.json"),
])
def test_json_errors_name_the_place(text, where):
    with pytest.raises(InputError) as err:
        parse_json(text, "j.json")
    assert where in str(err.value)


# ------------------------------------------------------------------------------ detection, dispatch

MOT_TEXT = "1,1,10,20,30,40,1,-1,-1,-1\n2,1,11,20,30,40,1,-1,-1,-1\n"


@pytest.mark.parametrize("name, content, fmt", [
    ("a.txt", MOT_TEXT, "mot"),
    ("a.csv", "# comment\n\n1 1 10 20 30 40 1 -1 -1 -1\n", "mot"),
    ("noext", "\ufeff1,2,3,4,5,6\n", "mot"),
    ("a.xml", CVML_TINY.decode(), "cvml"),
    ("b.xml", CVAT_TINY.decode(), "cvat"),
    ("c.xml", '<?xml version="1.0"?>\n<!-- c -->\n<viper xmlns="http://lamp.cfar.umd.edu/viper#">'
              "</viper>", "viper"),
    ("d.dat", format_json(sample()), "json"),
    ("e.txt", '  \n{"format": "motiontrack"}', "json"),
])
def test_detect_format_by_content(tmp_path, name, content, fmt):
    p = tmp_path / name
    p.write_text(content, encoding="utf-8")
    assert detect_format(p) == fmt


@pytest.mark.parametrize("content, message", [
    ("", "empty annotation file"),
    ("frame,id,x\n", ":1: unknown annotation format"),
    ("<html><body/></html>", "unknown XML annotation format with root element <html>"),
    ("# only a comment\n", "no annotation rows found"),
])
def test_detect_format_refuses_unknown(tmp_path, content, message):
    p = tmp_path / "x.txt"
    p.write_text(content)
    with pytest.raises(InputError, match=message):
        read_annotations(p)


def test_detect_format_binary_and_missing(tmp_path):
    p = tmp_path / "x.bin"
    p.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR" + bytes(range(256)))
    with pytest.raises(InputError, match="not a text annotation file"):
        read_annotations(p)
    with pytest.raises(InputError, match="annotation file not found"):
        read_annotations(tmp_path / "missing.txt")


@pytest.mark.parametrize("fmt, name", [
    ("mot", "r.txt"), ("mot-gt", "gt.txt"), ("cvml", "a.xml"), ("cvat", "b.xml"), ("json", "c.json"),
])
def test_write_then_read_any_format(tmp_path, fmt, name):
    a = sample().select(sample().ids >= 0)
    assert write_annotations(a, tmp_path / name, fmt=fmt) == fmt
    back = read_annotations(tmp_path / name)
    assert back.meta["format"] == {"mot-gt": "mot"}.get(fmt, fmt)
    # MOT writes boxes with 2 decimals; the XML formats with 12 significant digits
    assert_same(back, a, cols=("frames", "ids", "boxes"), atol=0.005 if "mot" in fmt else 1e-9)


@pytest.mark.parametrize("name, fmt", [("r.txt", "mot"), ("r.csv", "mot"), ("r.json", "json")])
def test_write_format_from_extension(tmp_path, name, fmt):
    assert write_annotations(sample(), tmp_path / name) == fmt
    assert detect_format(tmp_path / name) == fmt


def test_write_gt_kind_from_meta(tmp_path):
    a = sample()
    gt = Annotations(**{c: getattr(a, c) for c in COLS}, meta={"kind": "gt"})
    assert write_annotations(gt, tmp_path / "gt.txt") == "mot-gt"


@pytest.mark.parametrize("name, fmt, message", [
    ("a.xml", None, "could be ViPER, PETS CVML or CVAT"),
    ("a.dat", None, "cannot tell the annotation format"),
    ("a.txt", "yaml", "unknown annotation format 'yaml'"),
])
def test_write_format_errors(tmp_path, name, fmt, message):
    with pytest.raises(ConfigError, match=message):
        write_annotations(sample(), tmp_path / name, fmt=fmt)


@pytest.mark.parametrize("fmt", ["cvml", "cvat"])
def test_xml_writes_back_in_the_format_read(tmp_path, fmt):
    write_annotations(sample(), tmp_path / "in.xml", fmt=fmt)
    a = read_annotations(tmp_path / "in.xml")
    assert write_annotations(a, tmp_path / "out.xml") == fmt
    assert detect_format(tmp_path / "out.xml") == fmt


def test_read_unknown_kind_is_config_error(tmp_path):
    with pytest.raises(ConfigError, match="unknown annotation format 'xls'"):
        read_annotations(tmp_path / "x.txt", kind="xls")


def test_forced_kind_overrides_detection(tmp_path):
    p = tmp_path / "a.txt"
    p.write_text(MOT_TEXT)
    with pytest.raises(InputError, match="malformed JSON"):
        read_annotations(p, kind="json")
    assert len(read_annotations(p, kind="mot")) == 2


@pytest.mark.data
def test_auto_reads_mot17_gt(data):
    seqs = sorted(data("mot17-mini", "train").glob("*/gt/gt.txt"))
    assert seqs
    a = read_annotations(seqs[0])
    assert a.meta["format"] == "mot" and a.meta["kind"] == "gt" and len(a) > 0


@pytest.mark.data
def test_auto_reads_viper_through_its_reader(data):
    from motiontrack.io import viper

    p = data("viper-sample-001", "test-truth.xml")
    assert detect_format(p) == "viper"
    a = read_annotations(p)
    b = viper.read_viper(p)
    assert_same(a, b, cols=("frames", "ids", "boxes"))


def test_inputs_are_not_mutated(tmp_path):
    a = sample()
    before = {c: getattr(a, c).copy() for c in COLS}
    for fmt, name in (("cvml", "a.xml"), ("cvat", "b.xml"), ("json", "c.json")):
        write_annotations(a, tmp_path / name, fmt=fmt)
    for c in COLS:
        np.testing.assert_array_equal(getattr(a, c), before[c])


# ------------------------------------------------------------------------------------------ safety

BILLION_LAUGHS = b"""<?xml version="1.0"?>
<!DOCTYPE lolz [
 <!ENTITY lol "lol">
 <!ENTITY lol1 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">
 <!ENTITY lol2 "&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;">
 <!ENTITY lol3 "&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;">
 <!ENTITY lol9 "&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;">
]>
<ROOT><frame number="&lol9;"/></ROOT>
"""
EXTERNAL_ENTITY = b"""<?xml version="1.0"?>
<!DOCTYPE ROOT [<!ENTITY xxe SYSTEM "file:///etc/passwd">]>
<ROOT><frame number="0"><objectlist><object id="1">&xxe;</object></objectlist></frame></ROOT>
"""
EXTERNAL_DTD = b"""<?xml version="1.0"?>
<!DOCTYPE ROOT SYSTEM "http://127.0.0.1:9/evil.dtd">
<ROOT/>
"""
PARAMETER_ENTITY = b"""<?xml version="1.0"?>
<!DOCTYPE ROOT [<!ENTITY % p SYSTEM "file:///etc/passwd"> %p;]>
<ROOT/>
"""


@pytest.mark.parametrize("attack", [BILLION_LAUGHS, EXTERNAL_ENTITY, EXTERNAL_DTD, PARAMETER_ENTITY],
                         ids=["billion-laughs", "external-entity", "external-dtd", "parameter-entity"])
@pytest.mark.parametrize("root", ["dataset", "annotations"])
def test_unsafe_xml_is_refused(tmp_path, attack, root):
    p = tmp_path / "attack.xml"
    p.write_bytes(attack.replace(b"ROOT", root.encode()))
    with pytest.raises(InputError, match="refused unsafe XML"):
        read_annotations(p)
    reader = read_cvml if root == "dataset" else read_cvat
    with pytest.raises(InputError, match="refused unsafe XML"):
        reader(p)


@pytest.mark.parametrize("kind, text", [
    ("gt", "1,1,10,20,5,6,1,1,0.5\n2,1,11,20,5,6,0,7,1\n"),                 # MOT17 gt, 9 columns
    ("results", "1,3,10.5,20,5,6,0.9,-1,-1,-1\n1,4,30,20,5,6,0.8,-1,-1,-1\n"),  # 10 columns
    ("det", "1,-1,10,20,5,6\n2,-1,11, 21, 5, 6\n"),                        # 6 columns, spaces
    ("gt", "1,9,499,158,31.03,75.17,1,-4.15,-7.35,0\n"),                   # MOT15 gt with world
])
def test_mot_fast_and_line_by_line_parsers_agree(kind, text):
    from motiontrack.io.mot import parse_mot

    fast = parse_mot(text, kind)
    slow = parse_mot("# forces the line-by-line parser\n" + text, kind)
    for col in ("frames", "ids", "boxes", "scores", "consider", "classes", "visibility", "world"):
        assert np.array_equal(getattr(fast, col), getattr(slow, col)), col
