"""``motiontrack serve``: what viewers cost a camera, and how late pictures and events arrive.

Two runs of ``motiontrack serve`` on a free 127.0.0.1 port, one camera each (``synth:crossing``
with the scene of ``motiontrack synth-events``, looping):

1. processing rate — the camera unpaced (``fps = 1000`` in the cameras file: frames as fast as
   the pipeline takes them), so every CPU cycle the server spends on viewers could show as a
   lower rate. For each number of MJPEG viewers (0, 1, 5, 20: raw sockets reading the stream
   in this process, as a browser's ``<img>`` would) the frames the camera processed in a
   ``--seconds`` window; the windows of all viewer counts alternate ``--rounds`` times and the
   median of each count is reported with its ratio to no viewer, and the CPU the server process
   (web app and hub, not the camera's process) spent per second meanwhile — the viewers' cost
   itself, steadier than a rate on a machine shared with other work;
2. latency — the camera at the scene's own 25 fps, one MJPEG viewer and one event stream:
   frame → picture is the arrival of an MJPEG part minus its ``X-Frame-Wall`` header (when the
   camera process read that frame), frame → event the arrival of an SSE event minus its ``wall``
   field (same machine clock).

With ``--browsers`` the viewers are real browsers instead (and the latency run is left out):
headless Chromium driven by Selenium 4 (Debian ``chromium`` and ``chromedriver``), one browser
process each, showing the page (its MJPEG picture, the event feed over Server-Sent Events and
the once-a-second poll of the camera list) — 0, 1 and 5 by default. All browsers start once; in
a window with ``n`` browsers the first ``n`` show the page and the others ``about:blank``. Besides
the server's CPU the browsers' own (every process under their drivers) is reported: on a small
machine it is what competes with the camera.

Run: .venv/bin/python benchmarks/serve.py [--seconds 5] [--rounds 3] [--viewers 0,1,5,20]
     .venv/bin/python benchmarks/serve.py --browsers [--seconds 5] [--rounds 3] [--viewers 0,1,5]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import httpx


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Serve:
    """``motiontrack serve`` with one camera ``cam`` (``fps``: the cameras file's, or None)."""

    def __init__(self, root: Path, fps: float | None) -> None:
        self.port = _free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        subprocess.run([sys.executable, "-m", "motiontrack", "-q", "synth-events",
                        "synth:crossing", "-o", str(root / "gt"), "--force"], check=True)
        rate = f"fps = {fps}\n" if fps else ""
        (root / "cameras.toml").write_text(
            f'[[camera]]\nname = "cam"\nsource = "synth:crossing"\nscene = "gt/scene.toml"\n'
            f"loop = true\n{rate}")
        env = {**os.environ}
        env.pop("MOTIONTRACK_TOKEN", None)
        self.log = open(root / "serve.log", "w")
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "motiontrack", "serve", str(root / "cameras.toml"), "--port",
             str(self.port), "--out", str(root / "out")],
            cwd=root, stdout=self.log, stderr=subprocess.STDOUT, env=env)
        self.client = httpx.Client(base_url=self.url, timeout=10)
        end = time.monotonic() + 90
        while time.monotonic() < end:
            cam = self.camera()
            if cam and cam["status"] == "running" and cam["frames"] > 50:
                return
            time.sleep(0.2)
        raise SystemExit(f"serve did not start; see {root / 'serve.log'}")

    def camera(self) -> dict | None:
        try:
            return self.client.get("/api/cameras").json()[0]
        except httpx.TransportError:
            if self.proc.poll() is not None:
                raise SystemExit("serve exited") from None
            return None

    def frames(self) -> int:
        return self.camera()["frames"]

    def cpu(self) -> float:
        """CPU seconds the server process has used (Linux; 0 elsewhere)."""
        try:
            fields = Path(f"/proc/{self.proc.pid}/stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            return 0.0
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")

    def stop(self) -> None:
        self.proc.send_signal(signal.SIGTERM)
        self.proc.wait(60)
        self.client.close()
        self.log.close()


class Viewer(threading.Thread):
    """One MJPEG viewer over a raw socket: reads the stream as fast as it comes."""

    def __init__(self, port: int) -> None:
        super().__init__(daemon=True)
        self.sock = socket.create_connection(("127.0.0.1", port))
        self.sock.sendall(b"GET /api/cameras/cam/stream.mjpg HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")
        self.bytes = 0
        self.start()

    def run(self) -> None:
        try:
            while True:
                data = self.sock.recv(1 << 16)
                if not data:
                    return
                self.bytes += len(data)
        except OSError:
            return

    def close(self) -> None:
        try:
            self.sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        self.sock.close()


def processing_rates(root: Path, viewers: list[int], seconds: float, rounds: int) -> dict:
    srv = Serve(root / "rate", fps=1000)
    rates: dict[int, list[float]] = {n: [] for n in viewers}
    received: dict[int, list[float]] = {n: [] for n in viewers}
    cpu: dict[int, list[float]] = {n: [] for n in viewers}
    try:
        for _ in range(rounds):
            for n in viewers:
                vs = [Viewer(srv.port) for _ in range(n)]
                time.sleep(1.0)                       # connected and streaming
                b0 = [v.bytes for v in vs]
                f0, c0, t0 = srv.frames(), srv.cpu(), time.monotonic()
                time.sleep(seconds)
                f1, c1, t1 = srv.frames(), srv.cpu(), time.monotonic()
                rates[n].append((f1 - f0) / (t1 - t0))
                cpu[n].append((c1 - c0) / (t1 - t0))
                if vs:
                    received[n].append(min(v.bytes - b for v, b in zip(vs, b0)) / (t1 - t0))
                for v in vs:
                    v.close()
                time.sleep(0.5)
    finally:
        srv.stop()
    return {n: {"fps": statistics.median(r), "server_cpu": statistics.median(cpu[n]),
                "min_viewer_kB_s": statistics.median(received[n]) / 1e3 if received[n] else None}
            for n, r in rates.items()}


def _cpu_used(before: dict[int, float], after: dict[int, float]) -> float:
    """CPU seconds the processes of ``after`` used since ``before``; a process that ended in
    between takes its time with it (so this is a lower bound, never negative)."""
    return sum(t - before.get(p, 0.0) for p, t in after.items())


def _cpu_by_process(pids: set[int]) -> dict[int, float]:
    """CPU seconds of each of ``pids`` and all their descendants (Linux; empty elsewhere)."""
    parents: dict[int, int] = {}
    times: dict[int, float] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:     # the process has gone
            continue
        pid = int(stat.parent.name)
        parents[pid] = int(fields[1])
        times[pid] = (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    tree, grew = set(pids), True
    while grew:
        new = {p for p, pp in parents.items() if pp in tree and p not in tree}
        tree |= new
        grew = bool(new)
    return {p: times[p] for p in tree if p in times}


class Browsers:
    """``n`` headless Chromium browsers (Selenium 4, Debian's ``chromium`` + ``chromedriver``)."""

    def __init__(self, n: int, url: str) -> None:
        try:
            from selenium import webdriver
            from selenium.webdriver.chrome.service import Service
        except ImportError:
            raise SystemExit("--browsers needs selenium (pip install -e '.[dev]')") from None
        chromium = shutil.which("chromium") or shutil.which("chromium-browser")
        driver = shutil.which("chromedriver") or (
            "/usr/bin/chromedriver" if os.access("/usr/bin/chromedriver", os.X_OK) else None)
        if not chromium or not driver:
            raise SystemExit("--browsers needs chromium and chromedriver "
                             "(Debian: apt-get install chromium chromium-driver)")
        self.url = url
        self.drivers = []
        try:
            for _ in range(n):
                options = webdriver.ChromeOptions()
                options.binary_location = chromium
                for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage",
                            "--disable-gpu", "--window-size=1280,900"):
                    options.add_argument(arg)
                d = webdriver.Chrome(service=Service(driver), options=options)
                d.set_page_load_timeout(60)
                d.get("about:blank")
                self.drivers.append(d)
        except BaseException:
            self.close()
            raise

    def show(self, n: int) -> None:
        """The page in the first ``n`` browsers (each once its picture shows), the others blank."""
        for i, d in enumerate(self.drivers):
            d.get(self.url if i < n else "about:blank")
        for d in self.drivers[:n]:
            end = time.monotonic() + 30
            while not d.execute_script(
                    "const i = document.querySelector('[data-testid=\"camera-img-cam\"]');"
                    "return !!i && i.naturalWidth > 0;"):
                if time.monotonic() > end:
                    raise SystemExit("a browser did not show the camera's picture in 30 s")
                time.sleep(0.2)

    def cpu(self) -> dict[int, float]:
        """CPU seconds of each browser process (and of their drivers)."""
        return _cpu_by_process({d.service.process.pid for d in self.drivers})

    def close(self) -> None:
        for d in self.drivers:
            try:
                d.quit()
            except Exception:   # a browser already gone: nothing left to stop
                pass
        self.drivers = []


def browser_rates(root: Path, counts: list[int], seconds: float, rounds: int) -> dict:
    srv = Serve(root / "browsers", fps=1000)
    rates: dict[int, list[float]] = {n: [] for n in counts}
    cpu: dict[int, list[float]] = {n: [] for n in counts}
    bcpu: dict[int, list[float]] = {n: [] for n in counts}
    browsers = None
    try:
        browsers = Browsers(max(counts), srv.url + "/")
        for _ in range(rounds):
            for n in counts:
                browsers.show(n)
                time.sleep(1.0)                       # streams and event feed connected
                f0, c0, b0, t0 = srv.frames(), srv.cpu(), browsers.cpu(), time.monotonic()
                time.sleep(seconds)
                f1, c1, b1, t1 = srv.frames(), srv.cpu(), browsers.cpu(), time.monotonic()
                rates[n].append((f1 - f0) / (t1 - t0))
                cpu[n].append((c1 - c0) / (t1 - t0))
                bcpu[n].append(_cpu_used(b0, b1) / (t1 - t0))
    finally:
        if browsers is not None:
            browsers.close()
        srv.stop()
    return {n: {"fps": statistics.median(r), "server_cpu": statistics.median(cpu[n]),
                "browser_cpu": statistics.median(bcpu[n])} for n, r in rates.items()}


def _mjpeg_latencies(url: str, seconds: float, out: list[float]) -> None:
    buf, end = b"", time.monotonic() + seconds
    with httpx.Client(timeout=10) as c, c.stream("GET", url) as r:
        for chunk in r.iter_bytes():
            now = time.time()
            buf += chunk
            while True:
                head = buf.find(b"\r\n\r\n")
                if head < 0:
                    break
                headers = dict(h.split(b": ", 1) for h in buf[:head].split(b"\r\n")[1:])
                length = int(headers[b"Content-Length"])
                if len(buf) < head + 4 + length + 2:
                    break
                if b"X-Frame-Wall" in headers:
                    out.append(now - float(headers[b"X-Frame-Wall"]))
                buf = buf[head + 4 + length + 2:]
            if time.monotonic() > end:
                return


def _event_latencies(url: str, seconds: float, out: list[float]) -> None:
    end = time.monotonic() + seconds
    with httpx.Client(timeout=httpx.Timeout(10, read=30)) as c, c.stream("GET", url) as r:
        for line in r.iter_lines():
            if line.startswith("data: "):
                e = json.loads(line[6:])
                if "wall" in e:
                    out.append(time.time() - e["wall"])
            if time.monotonic() > end:
                return


def latencies(root: Path, seconds: float) -> dict:
    srv = Serve(root / "latency", fps=None)
    pictures: list[float] = []
    events: list[float] = []
    try:
        threads = [threading.Thread(target=_mjpeg_latencies,
                                    args=(f"{srv.url}/api/cameras/cam/stream.mjpg", seconds,
                                          pictures)),
                   threading.Thread(target=_event_latencies,
                                    args=(f"{srv.url}/api/events", seconds, events))]
        for t in threads:
            t.start()
        for t in threads:
            t.join(seconds + 40)
    finally:
        srv.stop()
    return {"picture": pictures, "event": events}


def _ms(values: list[float], q: float) -> str:
    if not values:
        return "-"
    v = sorted(values)
    return f"{1000 * v[min(len(v) - 1, int(q * len(v)))]:.0f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=5.0, help="measuring window (s)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--viewers", help="viewer counts, comma-separated (default 0,1,5,20; "
                                      "with --browsers 0,1,5)")
    ap.add_argument("--browsers", action="store_true",
                    help="viewers are headless Chromium browsers showing the page")
    args = ap.parse_args()
    viewers = [int(v) for v in (args.viewers or ("0,1,5" if args.browsers else "0,1,5,20"))
               .split(",")]
    if args.browsers:
        with tempfile.TemporaryDirectory() as tmp:
            (Path(tmp) / "browsers").mkdir()
            rates = browser_rates(Path(tmp), viewers, args.seconds, args.rounds)
        base = rates[viewers[0]]["fps"]
        print(f"processing rate of one unpaced camera (synth:crossing + scene) with headless "
              f"Chromium showing the page, median of {args.rounds} windows of {args.seconds:g} s")
        print(f"{'browsers':>8} {'fps':>7} {'ratio':>6} {'server CPU %':>13} "
              f"{'browsers CPU %':>15}")
        for n in viewers:
            r = rates[n]
            print(f"{n:>8} {r['fps']:>7.1f} {r['fps'] / base:>6.3f} "
                  f"{100 * r['server_cpu']:>13.1f} {100 * r['browser_cpu']:>15.1f}")
        return
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        (root / "rate").mkdir()
        (root / "latency").mkdir()
        rates = processing_rates(root, viewers, args.seconds, args.rounds)
        lat = latencies(root, max(20.0, 4 * args.seconds))
    base = rates[viewers[0]]["fps"]
    print(f"processing rate of one unpaced camera (synth:crossing + scene), median of "
          f"{args.rounds} windows of {args.seconds:g} s")
    print(f"{'viewers':>8} {'fps':>7} {'ratio':>6} {'server CPU %':>13} "
          f"{'slowest viewer kB/s':>20}")
    for n in viewers:
        r = rates[n]
        kb = f"{r['min_viewer_kB_s']:.0f}" if r["min_viewer_kB_s"] is not None else "-"
        print(f"{n:>8} {r['fps']:>7.1f} {r['fps'] / base:>6.3f} {100 * r['server_cpu']:>13.1f} "
              f"{kb:>20}")
    print("\nlatency at the scene's own 25 fps (ms): median, p95, n")
    for name, v in (("frame -> picture", lat["picture"]), ("frame -> event", lat["event"])):
        print(f"{name:<17} {_ms(v, 0.5):>6} {_ms(v, 0.95):>6} {len(v):>5}")


if __name__ == "__main__":
    main()
