"""The user's ONNX detector: decoding of both YOLO layouts, letterboxing back to frame pixels,
class names, NMS, fusion with the motion regions, and clear messages for bad models. The models
are built here with the ``onnx`` package: each ignores its image and emits a constant tensor."""

from __future__ import annotations

import numpy as np
import pytest

from motiontrack.detect import detector_regions, matches
from motiontrack.detect.onnx_yolo import (Detections, OnnxDetector, decode, letterbox,
                                          model_metadata)
from motiontrack.errors import InputError
from motiontrack.types import Box, Region

onnx = pytest.importorskip("onnx")
from onnx import TensorProto, helper, numpy_helper  # noqa: E402


def constant_model(path, out: np.ndarray, size: int = 64, names: str | None = None):
    """An ONNX model with a ``[1, 3, size, size]`` input whose output is ``out`` (plus 0 times
    the image's mean, so that the graph reads its input)."""
    x = helper.make_tensor_value_info("images", TensorProto.FLOAT, [1, 3, size, size])
    y = helper.make_tensor_value_info("output0", TensorProto.FLOAT, list(out.shape))
    nodes = [helper.make_node("ReduceMean", ["images"], ["mean"], keepdims=0),
             helper.make_node("Mul", ["mean", "zero"], ["nothing"]),
             helper.make_node("Add", ["out", "nothing"], ["output0"])]
    graph = helper.make_graph(nodes, "constant", [x], [y], initializer=[
        numpy_helper.from_array(out.astype(np.float32), "out"),
        numpy_helper.from_array(np.zeros(1, np.float32), "zero")])
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 12)])
    model.ir_version = 7
    if names is not None:
        entry = model.metadata_props.add()
        entry.key, entry.value = "names", names
    onnx.save(model, str(path))
    return path


# YOLOv8 layout [1, 4 + C, N], C = 2 (person, car), N = 3 boxes, in the 64x64 input's pixels
V8 = np.array([[[32, 33, 10],      # cx
                [32, 32, 10],      # cy
                [10, 10, 4],       # w
                [20, 20, 4],       # h
                [0.9, 0.8, 0.1],   # person
                [0.1, 0.1, 0.05]]], np.float32)  # car


def test_yolov8_output_letterboxed_back_with_names_from_the_metadata(tmp_path) -> None:
    model = constant_model(tmp_path / "v8.onnx", V8, names="{0: 'person', 1: 'car'}")
    det = OnnxDetector(model, input_size=64)
    assert det.names == ("person", "car")
    found = det.detect(np.zeros((48, 64, 3), np.uint8))
    # a 64x48 frame fills the 64 square at scale 1 with 8 px of padding above and below:
    # box 0 (cx 32, cy 32, 10x20) is x = 32 - 5, y = 32 - 10 - 8; box 1 overlaps it at IoU
    # 0.82 and is suppressed; box 2 scores 0.1 < 0.25
    assert found.boxes.tolist() == [[27.0, 14.0, 10.0, 20.0]]
    assert found.scores.tolist() == pytest.approx([0.9])
    assert [found.name(i) for i in range(len(found))] == ["person"]


def test_yolov5_output_with_objectness_and_names_from_a_file(tmp_path) -> None:
    # [1, N, 5 + C]: cx, cy, w, h, objectness, person, car
    out = np.array([[[28, 14, 8, 8, 0.5, 0.2, 0.9],     # car 0.45
                     [10, 16, 6, 12, 0.9, 0.9, 0.1],    # person 0.81
                     [28, 14, 8, 8, 0.2, 0.1, 0.9]]],   # car 0.18: below 0.25
                   np.float32)
    names = tmp_path / "names.txt"
    names.write_text("# classes\nperson\ncar\n")
    det = OnnxDetector(constant_model(tmp_path / "v5.onnx", out, size=32), names=names,
                       input_size=32)
    found = det.detect(np.zeros((64, 128, 3), np.uint8))
    # a 128x64 frame at scale 0.25 is 32x16, padded by 8 above: x = (cx - w/2) / 0.25,
    # y = (cy - h/2 - 8) / 0.25, w / 0.25, h / 0.25
    assert found.boxes.tolist() == [[96.0, 8.0, 32.0, 32.0], [28.0, 8.0, 24.0, 48.0]]
    assert found.scores.tolist() == pytest.approx([0.45, 0.81])
    assert [found.name(i) for i in range(len(found))] == ["car", "person"]


def test_decode_clips_to_the_frame_and_suppresses_per_class() -> None:
    # two overlapping boxes of different classes both stay; one past the border is clipped
    out = np.array([[[10, 10, 20, 20, 1, 0.9, 0.0],
                     [11, 10, 20, 20, 1, 0.0, 0.8],
                     [95, 50, 20, 20, 1, 0.7, 0.0]]], np.float32)
    boxes, scores, classes = decode(out, 1.0, (0.0, 0.0), (100, 100), 0.25, 0.45, 2)
    assert boxes.tolist() == [[0.0, 0.0, 20.0, 20.0], [1.0, 0.0, 20.0, 20.0],
                              [85.0, 40.0, 15.0, 20.0]]
    assert classes.tolist() == [0, 1, 0]


def test_letterbox_scales_and_pads_evenly() -> None:
    square, r, pad = letterbox(np.full((50, 100, 3), 7, np.uint8), 64)
    assert square.shape == (64, 64, 3) and r == 0.64 and pad == (0.0, 16.0)
    assert square[0, 0].tolist() == [114] * 3 and square[32, 32].tolist() == [7] * 3


@pytest.mark.parametrize("shape", [(1, 7), (2, 6, 3), (1, 3, 4)])
def test_an_unknown_output_layout_is_one_clear_message(tmp_path, shape) -> None:
    det = OnnxDetector(constant_model(tmp_path / "odd.onnx", np.zeros(shape, np.float32)),
                       input_size=64)
    with pytest.raises(InputError, match=r"unknown layout.*expected YOLOv5 \[1, N, 5\+C\]"):
        det.detect(np.zeros((64, 64, 3), np.uint8))


def test_a_model_that_cannot_load_is_one_clear_message(tmp_path) -> None:
    bad = tmp_path / "bad.onnx"
    bad.write_bytes(b"not a model")
    with pytest.raises(InputError, match="bad.onnx: not an ONNX model OpenCV can load"):
        OnnxDetector(bad)
    with pytest.raises(InputError, match="cannot read the detector model"):
        OnnxDetector(tmp_path / "missing.onnx")


def test_the_metadata_reader_finds_ultralytics_names(tmp_path) -> None:
    model = constant_model(tmp_path / "m.onnx", V8, names="{0: 'person', 1: 'car'}")
    assert model_metadata(model.read_bytes()) == {"names": "{0: 'person', 1: 'car'}"}
    assert model_metadata(b"\xff\xff") == {}


def _region(x, y, w, h) -> Region:
    return Region(box=Box(x, y, w, h), centroid=(x + w / 2, y + h / 2), area=w * h)


def test_fusion_keeps_motion_regions_and_adds_unmatched_detections_when_asked() -> None:
    dets = Detections(np.array([[0, 0, 10, 10], [50, 50, 10, 10.]]), np.array([0.9, 0.8]),
                      np.array([0, 1]), ("person", "car"))
    motion = [_region(1, 1, 10, 10)]           # IoU 0.68 with the first detection
    assert detector_regions(motion, dets, "fuse", False, 0.3) == motion
    fused = detector_regions(motion, dets, "fuse", True, 0.3)
    assert [r.box.as_array().tolist() for r in fused] == [[1, 1, 10, 10], [50, 50, 10, 10]]
    assert [r.score for r in detector_regions(motion, dets, "replace", False, 0.3)] == [0.9, 0.8]
    assert matches(np.array([[1, 1, 10, 10.]]), dets.boxes, 0.3) == [(0, 0)]


def test_a_replacing_detector_gives_its_tracks_its_class(tmp_path) -> None:
    from motiontrack.config import load_config
    from motiontrack.pipeline import run

    # one "car" box at the same place in every frame, in a 64x64 input: the walker's 640x480
    # frame is letterboxed at scale 0.1, 8 px of padding above: x = (32 - 5) / 0.1,
    # y = (32 - 5 - 8) / 0.1
    out = np.zeros((1, 6, 1), np.float32)
    out[0, :, 0] = [32, 32, 10, 10, 0.1, 0.9]
    model = constant_model(tmp_path / "car.onnx", out, names="{0: 'person', 1: 'car'}")
    cfg = load_config(None, [f"detector.model='onnx:{model}'", "detector.input_size=64",
                             "detector.mode='replace'", "source.max_frames=12"])
    last = [r.tracks for r in run("synth:walker", cfg)][-1]
    assert [(t.label, t.box.as_array().round(1).tolist()) for t in last] == [
        ("vehicle", [270.0, 190.0, 100.0, 100.0])]


@pytest.mark.parametrize("spec, message", [
    ("onnx:{bad}", "bad.onnx: not an ONNX model OpenCV can load"),
    ("{bad}", "expected onnx:PATH"),
])
def test_track_refuses_a_bad_detector_with_one_line_and_exit_2(tmp_path, capsys, spec,
                                                                message) -> None:
    from motiontrack.cli import main

    bad = tmp_path / "bad.onnx"
    bad.write_bytes(b"not a model")
    code = main(["track", "synth:walker?n_frames=5", "--detector", spec.format(bad=bad),
                 "--no-video", "-o", str(tmp_path / "run")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and message in err[0] and "Traceback" not in err[0]
    assert not (tmp_path / "run").exists()


def test_a_names_file_without_names_or_unreadable_is_one_clear_message(tmp_path) -> None:
    from motiontrack.detect.onnx_yolo import read_names

    empty = tmp_path / "empty.names"
    empty.write_text("# nothing\n\n")
    with pytest.raises(InputError, match="empty.names: no class names"):
        read_names(empty)
    binary = tmp_path / "bin.names"
    binary.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(InputError, match="bin.names: the class names are not UTF-8 text"):
        read_names(binary)
    with pytest.raises(InputError, match="missing.names: cannot read the class names"):
        read_names(tmp_path / "missing.names")
