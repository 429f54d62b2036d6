"""What a command loads before it does its work: ``motiontrack --help`` and ``track --help`` load
neither NumPy, OpenCV, PyAV nor any stage; a plain ``track`` run loads none of what only some
runs use (scene analytics, camera models, synthetic scenes, metrics, event sinks, the other
commands' trackers, a hidden progress bar). How long start-up takes is measured by
``benchmarks/startup.py``, never here."""

from __future__ import annotations

import json
import os
import subprocess
import sys

from motiontrack.io import codec_cache

#: runs the command line on its arguments, then prints the exit code and every loaded module
_PROBE = """\
import json, sys
from motiontrack.cli import main
try:
    code = main(sys.argv[1:])
except SystemExit as exc:
    code = exc.code
print(json.dumps([code, sorted(sys.modules)]), file=sys.stderr)
"""

#: loaded by no help text
NOT_FOR_HELP = ("numpy", "cv2", "av", "scipy", "tqdm", "motiontrack.types", "motiontrack.config",
                "motiontrack.pipeline", "motiontrack.run", "motiontrack.analytics",
                "motiontrack.calibrate", "motiontrack.synth", "motiontrack.io.video",
                "motiontrack.io.sources")


def _loaded(argv: list[str], cache: os.PathLike | None = None) -> tuple[int, set[str], str]:
    """Exit code, loaded modules and standard output of ``motiontrack ARGV`` in a new process
    (standard error a pipe, as in a script); ``cache`` is its ``XDG_CACHE_HOME``."""
    env = dict(os.environ, COLUMNS="100")
    if cache is not None:
        env["XDG_CACHE_HOME"] = str(cache)
    proc = subprocess.run([sys.executable, "-c", _PROBE, *argv], capture_output=True, text=True,
                          env=env, timeout=300)
    code, modules = json.loads(proc.stderr.strip().splitlines()[-1])
    return code, set(modules), proc.stdout


def _among(modules: set[str], packages: tuple[str, ...]) -> list[str]:
    """The modules that are one of ``packages`` or inside one."""
    return sorted(m for m in modules if any(m == p or m.startswith(p + ".") for p in packages))


def test_help_loads_neither_numpy_nor_opencv_nor_any_stage(tmp_path):
    code, modules, out = _loaded(["--help"], tmp_path)
    assert code == 0 and "track" in out
    assert _among(modules, NOT_FOR_HELP) == []
    # the one evaluate module is the light list of --scoring conventions
    assert _among(modules, ("motiontrack.evaluate",)) == ["motiontrack.evaluate",
                                                          "motiontrack.evaluate.scoring"]


def test_track_help_lists_the_codecs_of_the_installation_from_its_cached_probe(tmp_path):
    from motiontrack.io.video import encodable_codecs

    # the first help probes the codecs (OpenCV and PyAV) and keeps the answer
    code, first_modules, first = _loaded(["track", "--help"], tmp_path)
    assert code == 0 and "cv2" in first_modules
    assert list((tmp_path / "motiontrack").glob("codecs-*.json"))
    # the next one reads it: the same text without loading OpenCV, PyAV or the pipeline
    code, modules, again = _loaded(["track", "--help"], tmp_path)
    assert code == 0 and again == first
    assert _among(modules, NOT_FOR_HELP) == []
    # the parser of the command named alone: no other command's module
    commands = [m for m in modules if m.startswith("motiontrack.cli.")
                and not m.startswith("motiontrack.cli._")]
    assert commands == ["motiontrack.cli.track"]
    listed = " ".join(first.split())
    assert f"can encode: {', '.join(encodable_codecs())} (default vp80" in listed


def test_the_codec_help_trusts_only_the_cache_of_this_installation(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    key = codec_cache.installation_key()
    path = codec_cache.cache_file(key)
    path.parent.mkdir(parents=True)

    def codecs_in_help() -> str:
        out = " ".join(_loaded(["track", "--help"], tmp_path)[2].split())
        return out[out.index("can encode: ") + 12:out.index(" (default vp80")]

    # a cache file of this installation is what the help shows (nothing probed)
    path.write_text(json.dumps({"key": key, "codecs": ["vp80", "mjpg"]}))
    assert codecs_in_help() == "vp80, mjpg"
    # one of another installation (here: another PyAV build), or a damaged one, is probed anew
    # and replaced
    path.write_text(json.dumps({"key": {**key, "av": None}, "codecs": ["vp80", "mjpg"]}))
    real = codecs_in_help()
    assert real != "vp80, mjpg" and real.startswith("vp80, vp90")
    assert json.loads(path.read_text()) == {"key": json.loads(json.dumps(key)),
                                            "codecs": real.split(", ")}
    path.write_text('{"key": ')
    assert codecs_in_help() == real


def test_the_codec_help_without_a_writable_cache_folder_probes(tmp_path):
    blocked = tmp_path / "file"
    blocked.write_text("")   # the cache folder would be inside a regular file
    code, modules, out = _loaded(["track", "--help"], blocked)
    assert code == 0 and "can encode: vp80" in " ".join(out.split())


def test_a_plain_track_run_loads_only_what_it_uses(data, tmp_path):
    video = data("pets09-s2l1", "video.avi")
    code, modules, _ = _loaded(["track", str(video), "-o", str(tmp_path / "run"), "-q",
                                "--no-video", "--max-frames", "20"], tmp_path)
    assert code == 0 and (tmp_path / "run" / "tracks.txt").stat().st_size > 0
    assert "motiontrack.pipeline" in modules
    unused = ("motiontrack.analytics", "motiontrack.calibrate", "motiontrack.synth.scenes",
              "motiontrack.synth.render", "motiontrack.synth.events", "motiontrack.io.sinks",
              "motiontrack.io.xmlsafe", "motiontrack.tracking.flow", "motiontrack.run.heatmaps",
              "motiontrack.run.analytics_writers", "motiontrack.run.event_sinks",
              "motiontrack.render.scene", "motiontrack.render.flow", "motiontrack.render.overlay",
              "motiontrack.motion.dense_flow", "tqdm", "multiprocessing",
              "defusedxml", "http", "email", "av")
    assert _among(modules, unused) == []
    # the synth: scheme is registered (its source class), and no metric beyond the names of
    # the --scoring conventions is loaded
    assert _among(modules, ("motiontrack.synth",)) == ["motiontrack.synth",
                                                       "motiontrack.synth.source"]
    assert _among(modules, ("motiontrack.evaluate",)) == ["motiontrack.evaluate",
                                                          "motiontrack.evaluate.scoring"]
