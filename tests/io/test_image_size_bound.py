"""Pictures and video frames over ``source.max_pixels`` (calibrate: ``--max-pixels``) are refused
from their header or container before anything is decoded: one line, exit 2."""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import cv2
import numpy as np
import pytest

from motiontrack.cli import main
from motiontrack.config import DEFAULT_MAX_PIXELS
from motiontrack.errors import InputError
from motiontrack.io.imagesize import check_image, header_size
from motiontrack.io.sources import ImageSequenceSource, VideoFileSource, open_source

def png_claiming(path: Path, width: int, height: int) -> Path:
    """A PNG of a few dozen bytes whose header claims ``width`` x ``height`` pixels."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data)))

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr)
                     + chunk(b"IDAT", zlib.compress(b"\0" * 16)) + chunk(b"IEND", b""))
    return path


def jpeg_claiming(path: Path, width: int, height: int) -> Path:
    """SOI, an APP0 segment, then a baseline frame header claiming the size."""
    app0 = b"\xff\xe0" + struct.pack(">H", 16) + b"JFIF\0\x01\x01\0\0\x01\0\x01\0\0"
    sof = b"\xff\xc0" + struct.pack(">HBHHB", 11, 8, height, width, 1) + b"\x01\x11\x00"
    path.write_bytes(b"\xff\xd8" + app0 + sof + b"\xff\xd9")
    return path


def bmp_claiming(path: Path, width: int, height: int) -> Path:
    info = struct.pack("<IiiHHIIiiII", 40, width, -height, 1, 24, 0, 0, 0, 0, 0, 0)
    path.write_bytes(b"BM" + struct.pack("<IHHI", 54, 0, 0, 54) + info)
    return path


@pytest.mark.parametrize("make", [png_claiming, jpeg_claiming, bmp_claiming])
def test_the_header_states_the_claimed_size(tmp_path, make):
    p = make(tmp_path / "x.img", 25_000, 24_000)
    assert header_size(p) == (25_000, 24_000)
    with pytest.raises(InputError, match=r"x.img is 25000x24000 pixels \(600,000,000\), more "
                                         r"than the bound of 50,000,000; raise it \(--set "
                                         r"source.max_pixels=N"):
        check_image(p)


@pytest.mark.parametrize("ext", [".png", ".jpg", ".bmp", ".webp", ".ppm", ".pgm"])
def test_header_sizes_of_real_pictures(tmp_path, ext):
    p = tmp_path / f"x{ext}"
    img = np.random.default_rng(1).integers(0, 255, (37, 53, 3), np.uint8)
    assert cv2.imwrite(str(p), img if ext != ".pgm" else img[:, :, 0])
    assert header_size(p) == (53, 37)


def test_a_file_that_is_no_picture_has_no_header_size(tmp_path):
    (tmp_path / "t.txt").write_text("1,2,3\n")
    assert header_size(tmp_path / "t.txt") is None
    assert header_size(tmp_path) is None


def test_a_picture_claiming_a_million_squared_pixels_as_source(tmp_path, capsys):
    p = png_claiming(tmp_path / "huge.png", 10**6, 10**6)
    assert main(["track", str(p), "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "internal error" not in err
    assert "huge.png is 1000000x1000000 pixels (1,000,000,000,000), more than the bound" in err
    assert not (tmp_path / "out").exists()


def test_an_image_folder_and_glob_of_huge_pictures(tmp_path, capsys):
    folder = tmp_path / "imgs"
    folder.mkdir()
    for name in ("a.png", "b.png"):
        png_claiming(folder / name, 25_000, 25_000)
    for spec in (str(folder), str(folder / "*.png")):
        assert main(["track", spec, "-o", str(tmp_path / "out")]) == 2
        err = capsys.readouterr().err
        assert "a.png is 25000x25000 pixels" in err and err.count("\n") == 1


def test_a_later_image_of_the_folder_is_checked_before_it_is_decoded(tmp_path):
    folder = tmp_path / "imgs"
    folder.mkdir()
    cv2.imwrite(str(folder / "1.png"), np.zeros((8, 8, 3), np.uint8))
    png_claiming(folder / "2.png", 30_000, 30_000)
    src = ImageSequenceSource(folder)
    with pytest.raises(InputError, match="2.png is 30000x30000"):
        list(src)


def test_the_bound_is_the_config_key(tmp_path, capsys):
    folder = tmp_path / "imgs"
    folder.mkdir()
    for i in range(2):
        cv2.imwrite(str(folder / f"{i}.png"), np.zeros((40, 50, 3), np.uint8))
    with pytest.raises(InputError, match=r"50x40 pixels \(2,000\), more than the bound of 1,999"):
        open_source(str(folder), max_pixels=1999)
    assert open_source(str(folder), max_pixels=2000).info.width == 50
    assert main(["track", str(folder), "--set", "source.max_pixels=1000", "--no-video",
                 "-o", str(tmp_path / "out")]) == 2
    assert "more than the bound of 1,000" in capsys.readouterr().err
    assert DEFAULT_MAX_PIXELS == 50_000_000


def test_a_video_is_checked_by_its_containers_frame_size(tmp_path):
    p = tmp_path / "v.avi"
    w = cv2.VideoWriter(str(p), cv2.VideoWriter_fourcc(*"MJPG"), 10, (64, 48))
    for _ in range(3):
        w.write(np.zeros((48, 64, 3), np.uint8))
    w.release()
    with pytest.raises(InputError, match=r"v.avi is 64x48 pixels \(3,072\), more than the bound "
                                         r"of 3,000"):
        VideoFileSource(p, max_pixels=3000)
    assert VideoFileSource(p, max_pixels=3072).info.height == 48


def _refused_by_calibrate(capsys, args: list[str]) -> None:
    assert main(["calibrate", *args]) == 2
    err = capsys.readouterr().err
    assert "big.png is 25000x25000 pixels" in err and "--max-pixels N" in err
    assert err.count("\n") == 1 and "internal error" not in err
    assert main(["calibrate", *args, "--max-pixels", "0"]) == 2
    assert "--max-pixels must be in [1, 1073741824], got 0" in capsys.readouterr().err


def test_calibrate_chessboard_refuses_huge_pictures_before_decoding(tmp_path, capsys):
    img = png_claiming(tmp_path / "big.png", 25_000, 25_000)
    _refused_by_calibrate(capsys, ["chessboard", str(img), str(img), "-o", str(tmp_path / "c.yml")])


@pytest.mark.data
def test_calibrate_show_refuses_a_huge_picture_before_decoding(data, tmp_path, capsys):
    img = png_claiming(tmp_path / "big.png", 25_000, 25_000)
    _refused_by_calibrate(capsys, ["show", str(data("pets09-s2l1", "View_001.xml")), str(img),
                                   "-o", str(tmp_path / "s.png")])


def _exif_turned_jpeg(path: Path, img: np.ndarray) -> Path:
    """A JPEG of ``img`` whose EXIF orientation (6) tells readers to turn it a quarter."""
    ok, enc = cv2.imencode(".jpg", img)
    assert ok
    tiff = b"MM\0*" + struct.pack(">I", 8) + struct.pack(">H", 1)
    tiff += struct.pack(">HHII", 0x0112, 3, 1, 6 << 16) + struct.pack(">I", 0)
    app1 = b"Exif\0\0" + tiff
    data = enc.tobytes()
    path.write_bytes(data[:2] + b"\xff\xe1" + struct.pack(">H", len(app1) + 2) + app1 + data[2:])
    return path


def test_a_folder_of_exif_turned_photos_reads_every_frame(tmp_path):
    folder = tmp_path / "imgs"
    folder.mkdir()
    for i in range(3):
        _exif_turned_jpeg(folder / f"{i}.jpg", np.full((20, 30, 3), 60 * i, np.uint8))
    assert header_size(folder / "0.jpg") == (30, 20)
    src = ImageSequenceSource(folder)
    shapes = [f.image.shape[:2] for f in src]
    assert len(shapes) == 3 and len(set(shapes)) == 1
    assert (src.info.width, src.info.height) in ((30, 20), (20, 30))


def test_a_roi_mask_over_the_bound_is_refused_before_decoding(tmp_path, capsys):
    roi = png_claiming(tmp_path / "roi.png", 25_000, 25_000)
    folder = tmp_path / "imgs"
    folder.mkdir()
    for i in range(2):
        cv2.imwrite(str(folder / f"{i}.png"), np.zeros((40, 50, 3), np.uint8))
    assert main(["track", str(folder), "--set", f"preprocess.roi={roi}", "--no-video",
                 "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "roi.png is 25000x25000 pixels" in err and "source.max_pixels=N" in err
    assert err.count("\n") == 1 and "internal error" not in err


def test_evaluate_masks_refuses_a_mask_over_its_bound(tmp_path, capsys):
    gt, pred = tmp_path / "groundtruth", tmp_path / "pred"
    gt.mkdir()
    pred.mkdir()
    cv2.imwrite(str(gt / "gt000001.png"), np.zeros((40, 50), np.uint8))
    png_claiming(pred / "bin000001.png", 25_000, 25_000)
    assert main(["evaluate-masks", "--gt", str(gt), "--pred", str(pred)]) == 2
    err = capsys.readouterr().err
    assert "bin000001.png is 25000x25000 pixels" in err and "--max-pixels N" in err
    assert err.count("\n") == 1
    cv2.imwrite(str(pred / "bin000001.png"), np.zeros((40, 50), np.uint8))
    assert main(["evaluate-masks", "--gt", str(gt), "--pred", str(pred),
                 "--max-pixels", "1999"]) == 2
    assert "more than the bound of 1,999" in capsys.readouterr().err
    assert main(["evaluate-masks", "--gt", str(gt), "--pred", str(pred),
                 "--max-pixels", "2000"]) == 0
