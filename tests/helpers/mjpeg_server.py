"""Servers on 127.0.0.1 for the tests of live sources: an MJPEG stream (multipart/x-mixed-replace
of JPEG pictures) that can drop, stall, stop and start again, and a folder over HTTP."""

from __future__ import annotations

import functools
import http.server
import threading
import time

import cv2
import numpy as np


class HTTPServer(http.server.ThreadingHTTPServer):
    """Shutting down does not wait for open connections (a stalled stream holds one)."""

    block_on_close = False


def serve_http(handler, port: int = 0) -> HTTPServer:
    """``handler``'s server on 127.0.0.1:``port`` (0: a free port), serving from a daemon thread
    until its ``shutdown()``."""
    httpd = HTTPServer(("127.0.0.1", port), handler)
    threading.Thread(target=httpd.serve_forever, daemon=True).start()
    return httpd


class _Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


def serve_folder(root) -> HTTPServer:
    """The files under ``root`` over HTTP."""
    return serve_http(functools.partial(_Quiet, directory=str(root)))


def moving_box(i: int, size: tuple[int, int], box: tuple[int, int, int, int], step: int,
               period: int) -> np.ndarray:
    """Picture ``i`` of a scene ``size`` (width, height): on grey, a white ``box`` (left, top,
    right, bottom at picture 0) moving right ``step`` pixels a picture, back every ``period``."""
    img = np.full((size[1], size[0], 3), 90, np.uint8)
    dx = step * (i % period)
    cv2.rectangle(img, (box[0] + dx, box[1]), (box[2] + dx, box[3]), (255, 255, 255), -1)
    return img


class MjpegServer:
    """An MJPEG stream of ``pictures`` (in turn) at ``fps``. Each connection gets ``frames``
    pictures, or pictures until :meth:`stop` when ``frames`` is None; then the server closes it
    (``then="close"``) or keeps it open and silent until :meth:`stop` (``then="stall"``).

    ``connections`` counts the connections; ``served`` is set once the first connection has had
    its pictures. :meth:`stop` ends listening and the open connections; :meth:`start` listens
    again on the same port.
    """

    def __init__(self, pictures, frames: int | None = None, then: str = "close",
                 fps: float = 25.0) -> None:
        self.parts = [cv2.imencode(".jpg", p)[1].tobytes() for p in pictures]
        self.frames, self.then, self.fps = frames, then, fps
        self.connections = 0
        self.served = threading.Event()
        stream = self

        class Handler(http.server.BaseHTTPRequestHandler):
            def log_message(self, *args):
                pass

            def do_GET(self):
                stream.connections += 1
                try:
                    stream._send(self, stream.stopped)
                except (BrokenPipeError, ConnectionResetError):
                    pass                    # the client went away
                self.close_connection = True

        self._handler = Handler
        self.port = 0
        self.start()
        self.url = f"http://127.0.0.1:{self.port}/s.mjpg"

    def start(self) -> None:
        self.stopped = threading.Event()
        self.httpd = serve_http(self._handler, self.port)
        self.port = self.httpd.server_address[1]

    def _send(self, handler, stopped: threading.Event) -> None:
        handler.send_response(200)
        handler.send_header("Content-Type", "multipart/x-mixed-replace; boundary=frame")
        handler.end_headers()
        i = 0
        while (self.frames is None or i < self.frames) and not stopped.is_set():
            jpeg = self.parts[i % len(self.parts)]
            handler.wfile.write(b"--frame\r\nContent-Type: image/jpeg\r\nContent-Length: %d\r\n\r\n"
                                % len(jpeg) + jpeg + b"\r\n")
            handler.wfile.flush()
            i += 1
            time.sleep(1 / self.fps)
        self.served.set()
        if self.then == "stall":
            stopped.wait(30)                # connection open, nothing sent

    def stop(self) -> None:
        """Stop listening (new connections are refused) and end the open ones."""
        self.stopped.set()
        self.httpd.shutdown()
        self.httpd.server_close()
