"""An image's size from its header, before any decoding, and the pixel bound on images and frames.

OpenCV has no header-only reader: ``cv2.imread`` allocates the whole picture (about 1.9 GB for
25,000 × 25,000 pixels) and its own bound, ``OPENCV_IO_MAX_IMAGE_PIXELS`` (2**30 pixels), is read
once when the library loads. :func:`header_size` reads the first bytes of PNG, JPEG, BMP, WebP and
PNM (PPM/PGM) files, whatever their name; :func:`check_image` refuses a file whose header claims
more than ``max_pixels`` (``source.max_pixels``, :data:`DEFAULT_MAX_PIXELS` by default);
:func:`check_frame_size` does the same for a video's frame size as its container states it.
Formats not read here (TIFF) are decoded under OpenCV's own bound and checked after.
"""

from __future__ import annotations

import re
import struct
from pathlib import Path

from ..errors import InputError, printable

__all__ = ["DEFAULT_MAX_PIXELS", "header_size", "check_image", "check_frame_size",
           "too_many_pixels"]

#: most pixels of a frame or picture by default (``source.max_pixels``): 8000 x 6000 fits; a run
#: takes about 80 bytes per pixel (:func:`motiontrack.config.warn_if_oversized`), so about 4 GB
DEFAULT_MAX_PIXELS = 50_000_000

#: bytes read for the header: a JPEG's frame header follows its EXIF and ICC segments
_HEAD = 1 << 16
_PNM = re.compile(rb"^P[1-6](?:\s+|#[^\n]*\n)+(\d+)(?:\s+|#[^\n]*\n)+(\d+)")
#: JPEG start-of-frame markers (not DHT C4, JPG C8, DAC CC)
_SOF = frozenset(range(0xC0, 0xD0)) - {0xC4, 0xC8, 0xCC}


def _png(b: bytes) -> tuple[int, int] | None:
    if b[:8] == b"\x89PNG\r\n\x1a\n" and b[12:16] == b"IHDR" and len(b) >= 24:
        return struct.unpack(">II", b[16:24])
    return None


def _jpeg(b: bytes, path: Path) -> tuple[int, int] | None:
    if b[:2] != b"\xff\xd8":
        return None
    i = 2
    with open(path, "rb") as f:   # segments may run past the first bytes read
        while True:
            f.seek(i)
            head = f.read(9)
            if len(head) < 4 or head[0] != 0xFF:
                return None
            marker = head[1]
            if marker == 0xFF:          # fill byte
                i += 1
                continue
            if marker in (0x01, *range(0xD0, 0xD8)):   # no length
                i += 2
                continue
            length = struct.unpack(">H", head[2:4])[0]
            if marker in _SOF:
                if len(head) < 9:
                    return None
                h, w = struct.unpack(">HH", head[5:9])
                return w, h
            if length < 2:
                return None
            i += 2 + length


def _bmp(b: bytes) -> tuple[int, int] | None:
    if b[:2] != b"BM" or len(b) < 26:
        return None
    if struct.unpack("<I", b[14:18])[0] == 12:   # OS/2 core header: 16-bit sizes
        return struct.unpack("<HH", b[18:22])
    w, h = struct.unpack("<ii", b[18:26])
    return abs(w), abs(h)   # a negative height is a top-down picture


def _webp(b: bytes) -> tuple[int, int] | None:
    if b[:4] != b"RIFF" or b[8:12] != b"WEBP" or len(b) < 30:
        return None
    chunk = b[12:16]
    if chunk == b"VP8X":
        return (int.from_bytes(b[24:27], "little") + 1, int.from_bytes(b[27:30], "little") + 1)
    if chunk == b"VP8L" and b[20] == 0x2F:
        bits = int.from_bytes(b[21:25], "little")
        return (bits & 0x3FFF) + 1, ((bits >> 14) & 0x3FFF) + 1
    if chunk == b"VP8 " and b[23:26] == b"\x9d\x01\x2a":
        w, h = struct.unpack("<HH", b[26:30])
        return w & 0x3FFF, h & 0x3FFF
    return None


def header_size(path: str | Path) -> tuple[int, int] | None:
    """``(width, height)`` an image file's header states, or None when the file is not a PNG,
    JPEG, BMP, WebP or PNM picture (or its header is cut short). Reads the first 64 KiB (a
    JPEG's segments up to its frame header); never decodes."""
    p = Path(path)
    try:
        with open(p, "rb") as f:
            b = f.read(_HEAD)
    except (IsADirectoryError, FileNotFoundError, PermissionError):
        return None
    pnm = _PNM.match(b)
    if pnm:
        return int(pnm.group(1)), int(pnm.group(2))
    return _png(b) or _bmp(b) or _webp(b) or _jpeg(b, p)


def too_many_pixels(what: str, width: int, height: int, max_pixels: int,
                    option: str = "--set source.max_pixels=N") -> InputError:
    """The one-line error of a picture or frame over the bound; ``option`` raises it."""
    return InputError(f"{printable(what)} is {width}x{height} pixels ({width * height:,}), more "
                      f"than the bound of {max_pixels:,}; raise it ({option}, at most "
                      f"{2**30:,}) to read it")


def check_image(path: str | Path, max_pixels: int = DEFAULT_MAX_PIXELS,
                option: str = "--set source.max_pixels=N") -> tuple[int, int] | None:
    """The header size of image ``path`` (None for a format not read here), refused as an
    :class:`~motiontrack.errors.InputError` when it has more than ``max_pixels`` pixels."""
    size = header_size(path)
    if size is not None:
        check_frame_size(str(path), *size, max_pixels=max_pixels, option=option)
    return size


def check_frame_size(what: str, width: int, height: int, max_pixels: int = DEFAULT_MAX_PIXELS,
                     option: str = "--set source.max_pixels=N") -> None:
    """Refuse frames of ``width`` x ``height`` over ``max_pixels`` (``what`` names the source)."""
    if int(width) * int(height) > max_pixels:
        raise too_many_pixels(what, int(width), int(height), max_pixels, option)
