"""ViPER XML reading/writing: sample files, round trips, safe parsing, clear errors."""

from __future__ import annotations

import logging

import numpy as np
import pytest

from motiontrack.errors import InputError
from motiontrack.io.viper import format_viper, parse_viper, read_viper, write_viper
from motiontrack.types import Annotations

HEAD = """<?xml version="1.0" encoding="UTF-8"?>
<viper xmlns="http://lamp.cfar.umd.edu/viper#" xmlns:data="http://lamp.cfar.umd.edu/viperdata#">
  <config>
    <descriptor name="Information" type="FILE">
      <attribute dynamic="false" name="NUMFRAMES" type="http://lamp.cfar.umd.edu/viperdata#dvalue"/>
    </descriptor>
    <descriptor name="Person" type="OBJECT">
      <attribute dynamic="true" name="Location" type="http://lamp.cfar.umd.edu/viperdata#bbox"/>
      <attribute dynamic="false" name="Name" type="http://lamp.cfar.umd.edu/viperdata#svalue"/>
    </descriptor>
  </config>
  <data>
    <sourcefile filename="clip.mpg">
      <file id="0" name="Information">
        <attribute name="NUMFRAMES"><data:dvalue value="10"/></attribute>
      </file>
"""
TAIL = """    </sourcefile>
  </data>
</viper>
"""


def doc(objects: str) -> str:
    return HEAD + objects + TAIL


SMALL = doc("""\
      <object framespan="2:4" id="3" name="Person">
        <attribute name="Location">
          <data:bbox framespan="2:3" x="10" y="20" width="5" height="6"/>
          <data:bbox framespan="4:4" x="11" y="20" width="5" height="6"/>
        </attribute>
        <attribute name="Name"><data:svalue value="anna"/></attribute>
      </object>
      <object framespan="1:1 3:3" id="7" name="Person">
        <attribute name="Location">
          <data:bbox framespan="1:1 3:3" x="0" y="0" width="1" height="2"/>
        </attribute>
      </object>
""")


def test_parse_small_document():
    a = parse_viper(SMALL)
    # sorted by (frame, id); span "2:3" expands to frames 2 and 3 (inclusive); frames unchanged
    assert a.frames.tolist() == [1, 2, 3, 3, 4]
    assert a.ids.tolist() == [7, 3, 3, 7, 3]
    assert a.boxes.tolist() == [
        [0, 0, 1, 2], [10, 20, 5, 6], [10, 20, 5, 6], [0, 0, 1, 2], [11, 20, 5, 6]]
    assert a.meta["names"] == {3: "anna"}
    assert a.meta["num_frames"] == 10
    assert a.meta["descriptor"] == "Person" and a.meta["attribute"] == "Location"


@pytest.mark.data
def test_read_sample_truth(data):
    a = read_viper(data("viper-sample-001", "test-truth.xml"))
    assert len(a) == 74 + 92
    assert sorted(set(a.ids.tolist())) == [0, 1]
    assert a.meta["frame_size"] == (352, 240)
    assert a.meta["names"] == {0: "eins", 1: "zwei"}
    # object 0, framespan 1:74, first box x=215 y=76 width=59 height=113
    first = a.select((a.ids == 0) & (a.frames == 1))
    assert first.boxes.tolist() == [[215, 76, 59, 113]]
    # object 1's first bbox covers "1:46" with one box
    one = a.select((a.ids == 1) & (a.frames <= 46))
    assert one.frames.tolist() == list(range(1, 47))
    assert (one.boxes == [116, 68, 54, 143]).all()
    assert a.select(a.ids == 0).frames.tolist() == list(range(1, 75))


@pytest.mark.data
@pytest.mark.parametrize("name", ["test-truth.xml", "test-candidate.xml"])
def test_sample_round_trip(data, tmp_path, name):
    a = read_viper(data("viper-sample-001", name))
    out = tmp_path / "again.xgtf"
    write_viper(a, out)
    b = read_viper(out)
    assert np.array_equal(a.frames, b.frames)
    assert np.array_equal(a.ids, b.ids)
    assert np.array_equal(a.boxes, b.boxes)
    assert b.meta["frame_size"] == (352, 240)


def test_write_merges_runs_and_reads_back(tmp_path):
    # id 1: frames 1-3 same box, frame 4 moved, gap, frames 8-9; id 5: frame 2 only
    a = Annotations.from_columns(
        [1, 2, 3, 4, 8, 9, 2],
        [1, 1, 1, 1, 1, 1, 5],
        [[1, 2, 3, 4]] * 3 + [[2, 2, 3, 4]] + [[0, 0, 5, 5]] * 2 + [[9, 9, 1, 1]],
    )
    text = format_viper(a, frame_size=(64, 48))
    assert 'framespan="1:4 8:9" id="1"' in text
    assert 'framespan="1:3"' in text and 'framespan="4:4"' in text and 'framespan="8:9"' in text
    path = tmp_path / "tracks.xgtf"
    write_viper(a, path, frame_size=(64, 48))
    b = read_viper(path)
    order = np.lexsort((a.ids, a.frames))
    assert np.array_equal(b.frames, a.frames[order])
    assert np.array_equal(b.ids, a.ids[order])
    assert np.array_equal(b.boxes, a.boxes[order])
    assert b.meta["frame_size"] == (64, 48) and b.meta["num_frames"] == 9
    assert not list(tmp_path.glob("*.part"))  # atomic write leaves no temporary file


def test_write_empty(tmp_path):
    path = tmp_path / "empty.xgtf"
    write_viper(Annotations.empty(), path)
    assert len(read_viper(path)) == 0


def test_write_rounds_non_integer_boxes(tmp_path, caplog):
    a = Annotations.from_columns([1], [1], [[1.4, 2.6, 3.0, 4.0]])
    with caplog.at_level(logging.WARNING, logger="motiontrack.io.viper"):
        write_viper(a, tmp_path / "r.xgtf")
    assert "rounding" in caplog.text
    assert read_viper(tmp_path / "r.xgtf").boxes.tolist() == [[1, 3, 3, 4]]


def test_write_refuses_two_boxes_per_id_and_frame(tmp_path):
    a = Annotations.from_columns([1, 1], [2, 2], [[0, 0, 1, 1], [5, 5, 1, 1]])
    with pytest.raises(InputError, match="two boxes"):
        write_viper(a, tmp_path / "x.xgtf")


BILLION_LAUGHS = """<?xml version="1.0"?>
<!DOCTYPE viper [
  <!ENTITY lol "lol">
  <!ENTITY lol2 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">
]>
<viper xmlns="http://lamp.cfar.umd.edu/viper#">&lol2;</viper>
"""
EXTERNAL_ENTITY = """<?xml version="1.0"?>
<!DOCTYPE viper [ <!ENTITY xxe SYSTEM "file:///etc/passwd"> ]>
<viper xmlns="http://lamp.cfar.umd.edu/viper#">&xxe;</viper>
"""


@pytest.mark.parametrize("text", [BILLION_LAUGHS, EXTERNAL_ENTITY], ids=["entities", "external"])
def test_unsafe_xml_is_refused(tmp_path, text):
    path = tmp_path / "evil.xml"
    path.write_text(text)
    with pytest.raises(InputError, match="unsafe XML"):
        read_viper(path)


BAD_DOCS = {
    "not well-formed": (HEAD + "      <object id='1' name='Person'>\n" + TAIL, r"line \d+, column"),
    "bad bbox": (doc("""\
      <object framespan="1:1" id="1" name="Person">
        <attribute name="Location">
          <data:bbox framespan="1:1" x="a" y="0" width="1" height="1"/>
        </attribute>
      </object>
"""), r"line 19: <bbox>: bbox needs integer x, y, width, height"),
    "bad framespan": (doc("""\
      <object framespan="1:1" id="1" name="Person">
        <attribute name="Location">
          <data:bbox framespan="3-4" x="0" y="0" width="1" height="1"/>
        </attribute>
      </object>
"""), r"line 19: <bbox>: framespan must look like 'a:b'"),
    "reversed framespan": (doc("""\
      <object framespan="5:1" id="1" name="Person">
      </object>
"""), r"line 17: <object>: framespan end < start"),
    "bad id": (doc("""\
      <object framespan="1:1" id="x" name="Person">
      </object>
"""), r"line 17: <object>: object id must be an integer"),
    "negative size": (doc("""\
      <object framespan="1:1" id="1" name="Person">
        <attribute name="Location">
          <data:bbox framespan="1:1" x="0" y="0" width="-1" height="1"/>
        </attribute>
      </object>
"""), r"width/height must be >= 0"),
    "overlapping spans": (doc("""\
      <object framespan="1:3" id="1" name="Person">
        <attribute name="Location">
          <data:bbox framespan="1:2" x="0" y="0" width="1" height="1"/>
          <data:bbox framespan="2:3" x="0" y="0" width="1" height="1"/>
        </attribute>
      </object>
"""), r"object 1 has two boxes at frame 2"),
    "wrong root": ("<foo/>", r"root element must be <viper>"),
}


@pytest.mark.parametrize("name", list(BAD_DOCS))
def test_malformed_input_names_line_and_element(name):
    text, pattern = BAD_DOCS[name]
    with pytest.raises(InputError, match=pattern):
        parse_viper(text, name="bad.xgtf")


def test_missing_file(tmp_path):
    with pytest.raises(InputError, match="not found"):
        read_viper(tmp_path / "nope.xgtf")


def test_unknown_descriptor():
    with pytest.raises(InputError, match="no OBJECT descriptor 'Car'"):
        parse_viper(SMALL, descriptor="Car")
