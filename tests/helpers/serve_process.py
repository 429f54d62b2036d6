"""``motiontrack serve`` in a subprocess, for the tests that talk to a live server.

:class:`ServeProcess` writes ``ROOT/cameras.toml``, starts ``motiontrack serve`` on a free
127.0.0.1 port with its outputs under ``ROOT/out`` and its output in ``ROOT/serve.log``, waits
for its cameras, and stops it with SIGTERM (killing it when it does not end in time).
:func:`synth_cameras` gives looping synthetic cameras with the scene files of
``motiontrack synth-events``.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

from helpers import free_port


def synth_cameras(root: Path, sources: dict[str, str]) -> dict[str, dict]:
    """Cameras ``name -> synthetic source`` that loop, each with the scene file that
    ``motiontrack synth-events`` writes for its source (``root/NAME/scene.toml``)."""
    cameras = {}
    for name, source in sources.items():
        subprocess.run([sys.executable, "-m", "motiontrack", "synth-events", source, "-o",
                        str(root / name), "-q"], check=True, timeout=120)
        cameras[name] = {"source": source, "scene": f"{name}/scene.toml", "loop": True}
    return cameras


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    return json.dumps(value)   # a JSON string or number is a TOML one too


class ServeProcess:
    """``motiontrack serve ROOT/cameras.toml --port P --out ROOT/out ARGS...``.

    ``cameras``: name -> the camera's keys in the cameras file. ``token``: given with
    ``--token`` and sent with every request of :meth:`get` and :attr:`client`; without it the
    server runs without a token, whatever the environment's ``MOTIONTRACK_TOKEN``. A context
    manager: leaving it stops the server, so that no test leaves one running.
    """

    def __init__(self, root: Path, cameras: dict[str, dict], *args: str,
                 token: str | None = None) -> None:
        self.root, self.names, self.token = root, list(cameras), token
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.out = root / "out"
        (root / "cameras.toml").write_text("\n".join(
            f'[[camera]]\nname = "{name}"\n'
            + "".join(f"{key} = {_toml_value(v)}\n" for key, v in keys.items())
            for name, keys in cameras.items()))
        if token:
            args = (*args, "--token", token)
        env = {**os.environ, "PYTHONUNBUFFERED": "1"}
        env.pop("MOTIONTRACK_TOKEN", None)
        self._client = None
        self._log = open(root / "serve.log", "wb")
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "motiontrack", "serve", str(root / "cameras.toml"),
             "--port", str(self.port), "--out", str(self.out), *args],
            cwd=root, stdout=self._log, stderr=subprocess.STDOUT, env=env)

    def __enter__(self) -> ServeProcess:
        return self

    def __exit__(self, *exc) -> None:
        self.stop()

    @property
    def headers(self) -> dict[str, str]:
        return {"Authorization": f"Bearer {self.token}"} if self.token else {}

    @property
    def client(self):
        """An ``httpx.Client`` on the server (10 s timeout), closed by :meth:`stop`."""
        if self._client is None:
            import httpx

            self._client = httpx.Client(base_url=self.url, headers=self.headers, timeout=10)
        return self._client

    def get(self, path: str, timeout: float = 5.0):
        """``GET path`` (``/api/...``): what it answers, decoded when it is JSON."""
        req = urllib.request.Request(self.url + path, headers=self.headers)
        with urllib.request.urlopen(req, timeout=timeout) as r:
            body = r.read()
            return json.loads(body) if "json" in r.headers.get("Content-Type", "") else body

    def cameras(self) -> dict[str, dict]:
        """``/api/cameras``, by camera name."""
        return {c["name"]: c for c in self.get("/api/cameras")}

    def camera(self, name: str) -> dict:
        return self.cameras()[name]

    def wait(self, what: str, check, timeout: float, interval: float = 0.2):
        """Poll ``check()`` until it returns something truthy, and return that. Fail naming
        ``what`` (with the server's last output) after ``timeout`` seconds, or at once when the
        server has exited. Meanwhile ``check`` may raise OSError or ValueError: the server not
        answering yet, an answer cut short."""
        end = time.monotonic() + timeout
        while True:
            try:
                last = check()
            except (OSError, ValueError) as e:
                last = e
            if last and not isinstance(last, Exception):
                return last
            if self.proc.poll() is not None:
                raise AssertionError(f"motiontrack serve exited with {self.proc.returncode} "
                                     f"before {what}{self.logs()}")
            if time.monotonic() > end:
                raise AssertionError(f"not within {timeout:g} s: {what} (last: {last!r})"
                                     f"{self.logs()}")
            time.sleep(interval)

    def wait_running(self, frames: int = 0, timeout: float = 90) -> dict[str, dict]:
        """Wait until every camera of the cameras file runs and has processed more than
        ``frames`` frames; return :meth:`cameras`."""
        def running():
            cams = self.cameras()
            return cams if set(cams) == set(self.names) and all(
                c["status"] == "running" and c["frames"] > frames for c in cams.values()) else None

        return self.wait(f"every camera running past frame {frames}", running, timeout)

    def logs(self, lines: int = 40) -> str:
        """The server's last lines of output, to end a failure message with."""
        text = (self.root / "serve.log").read_text(errors="replace")
        return "\nmotiontrack serve's last output:\n" + "\n".join(text.splitlines()[-lines:])

    def stop(self, timeout: float = 30) -> int:
        """SIGTERM and the exit code; killed (a negative code) when it has not ended after
        ``timeout`` seconds. Stopping a stopped server only gives its code again."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(10)
        if self._client is not None:
            self._client.close()
        self._log.close()
        return self.proc.returncode
