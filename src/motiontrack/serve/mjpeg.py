"""The MJPEG stream format the page's ``<img>`` elements play: a live camera's pictures and an
event's clip replayed (``multipart/x-mixed-replace``, one JPEG a part)."""

from __future__ import annotations

__all__ = ["BOUNDARY", "MJPEG_TYPE", "WALL_HEADER", "part"]

BOUNDARY = "frame"
MJPEG_TYPE = f"multipart/x-mixed-replace; boundary={BOUNDARY}"
#: header of a picture (snapshot, MJPEG part) with its frame's read time, epoch seconds
WALL_HEADER = "X-Frame-Wall"


def part(jpeg: bytes, wall: float | None = None) -> bytes:
    """One MJPEG part; ``wall`` (when its frame was read) goes in :data:`WALL_HEADER`, for
    latency measurements."""
    stamp = f"{WALL_HEADER}: {wall:.4f}\r\n" if wall is not None else ""
    return (f"--{BOUNDARY}\r\nContent-Type: image/jpeg\r\nContent-Length: {len(jpeg)}\r\n"
            f"{stamp}\r\n".encode() + jpeg + b"\r\n")
