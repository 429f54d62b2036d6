"""`motiontrack config`, and the warnings and refusals of commands given config keys that have no
effect with the other settings."""

from __future__ import annotations

import subprocess
import sys

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

import pytest

from motiontrack.cli import main
from motiontrack.config import load_config, to_dict
from motiontrack.config_keys import key_docs

WALKER = "synth:walker?n_frames=3"


def _rows(out: str) -> dict[str, str]:
    """Printed table rows by key (the key is the second column, after the marks)."""
    rows = {}
    for line in out.splitlines()[1:-1]:
        rows[line[4:].split()[0]] = line
    return rows


def test_config_prints_every_key_with_value_default_type_range_and_meaning(capsys):
    assert main(["config"]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    assert lines[0].split() == ["key", "value", "default", "type", "allowed", "meaning"]
    assert lines[-1] == "* differs from the default   - has no effect with these settings"
    rows = _rows(out)
    assert list(rows) == [d.key for d in key_docs()]
    knn = rows["motion.knn.n_samples"]
    assert knn.split()[:5] == ["motion.knn.n_samples", "7", "7", "int", "[1,"]
    assert "samples kept per pixel" in knn
    # defaults only: no value is marked as changed; the other detectors' keys are marked inactive
    assert not any(r.startswith("*") for r in rows.values())
    assert rows["motion.mog2.var_threshold"].startswith(" -")
    assert "[needs motion.method=mog2]" in rows["motion.mog2.var_threshold"]
    assert rows["motion.knn.dist2_threshold"].startswith("  ")


def test_config_marks_changed_values_and_follows_preset_file_and_set(tmp_path, capsys):
    cfg = tmp_path / "c.toml"
    cfg.write_text('[motion]\nmethod = "mog2"\n')
    assert main(["config", "--preset", "people", "--config", str(cfg), "--set",
                 "motion.mog2.var_threshold=8", "motion", "people.enabled"]) == 0
    captured = capsys.readouterr()
    assert captured.err == ""                          # the --set key takes effect: no warning
    rows = _rows(captured.out)
    assert set(rows) == {d.key for d in key_docs()
                         if d.key.startswith("motion.") or d.key == "people.enabled"}
    assert rows["motion.method"].startswith("* ") and '"mog2"' in rows["motion.method"]
    assert rows["motion.mog2.var_threshold"].split()[1:4] == ["motion.mog2.var_threshold", "8.0",
                                                              "16.0"]
    assert rows["people.enabled"].startswith("* ")       # the people preset
    assert rows["motion.knn.history"].startswith(" -")


def test_config_warns_of_a_set_key_without_effect(capsys):
    assert main(["config", "--set", "motion.knn.history=300", "--set", "motion.method=mog2",
                 "motion.knn.history"]) == 0
    captured = capsys.readouterr()
    assert captured.err.strip() == (
        "motiontrack: WARNING: --set motion.knn.history has no effect while motion.method = mog2; "
        "add --set motion.method=knn")
    assert _rows(captured.out)["motion.knn.history"].startswith("*-")


def test_config_toml_is_the_resolved_config_as_a_file(tmp_path, capsys):
    assert main(["config", "--preset", "fast", "--set", "tracker.max_lost_s=3", "--toml"]) == 0
    text = capsys.readouterr().out
    expected = load_config(None, ["tracker.max_lost_s=3"], preset="fast")
    assert tomllib.loads(text) == to_dict(expected)
    (tmp_path / "c.toml").write_text(text)
    assert load_config(tmp_path / "c.toml") == expected


@pytest.mark.parametrize("argv, message", [
    (["config", "motion.nope"], "no config key or section 'motion.nope'; sections: classes, cleanup, detector,"),
    (["config", "--toml", "motion"], "--toml prints the whole config; give no KEY with it"),
    (["config", "--set", "motion.knn.history=0"], "motion.knn.history must be in [1, 2147483647]"),
    (["config", "--preset", "nope"], "unknown preset 'nope'"),
])
def test_config_bad_input_is_one_line(capsys, argv, message):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("motiontrack: error: ") and message in err[0], err


def test_help_does_not_import_the_config_descriptions():
    code = ("import sys; from motiontrack.cli import build_parser; build_parser(); "
            "print(sorted(m for m in ('motiontrack.config', 'motiontrack.config_keys', "
            "'motiontrack.config_activity') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "config_keys" not in out.stdout and "config_activity" not in out.stdout, out.stdout


# ----------------------------------------------------------------- warnings and refusals elsewhere
def test_track_warns_of_a_set_key_of_a_detector_that_does_not_run(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["track", WALKER, "--no-video", "-o", str(out),
                 "--set", "motion.mog2.var_threshold=8"]) == 0
    warned = [ln for ln in capsys.readouterr().err.splitlines() if "WARNING" in ln]
    assert warned == ["motiontrack: WARNING: --set motion.mog2.var_threshold has no effect while "
                      "motion.method = knn; add --set motion.method=mog2"]
    assert main(["track", WALKER, "--no-video", "-o", str(out), "--force",
                 "--set", "motion.mog2.var_threshold=8", "--set", "motion.method=mog2"]) == 0
    assert "WARNING" not in capsys.readouterr().err


def test_dense_flow_takes_the_farneback_keys_whatever_motion_method_says(tmp_path, capsys):
    assert main(["flow", WALKER, "--mode", "dense", "-o", str(tmp_path / "f"),
                 "--set", "motion.farneback.threshold=1.0", "--set", "motion.knn.history=5",
                 "--set", "tracker.max_lost_s=3"]) == 0
    warned = [ln for ln in capsys.readouterr().err.splitlines() if "WARNING" in ln]
    reads = "which reads only source.*, motion.farneback.*, output.*"
    assert warned == [f"motiontrack: WARNING: --set motion.knn.history has no effect on dense flow, "
                      f"{reads}",
                      f"motiontrack: WARNING: --set tracker.max_lost_s has no effect on dense flow, "
                      f"{reads}"]


def test_sparse_flow_warns_of_tracker_and_inactive_motion_keys(tmp_path, capsys):
    assert main(["flow", WALKER, "--mode", "sparse", "--no-video", "-o", str(tmp_path / "f"),
                 "--set", "tracker.max_lost_s=3", "--set", "motion.mog2.history=5",
                 "--set", "regions.min_area=50"]) == 0
    warned = [ln for ln in capsys.readouterr().err.splitlines() if "WARNING" in ln]
    assert warned == [
        "motiontrack: WARNING: --set tracker.max_lost_s has no effect on sparse flow, which reads "
        "only source.*, preprocess.*, motion.*, cleanup.*, regions.*, output.*",
        "motiontrack: WARNING: --set motion.mog2.history has no effect while motion.method = knn; "
        "add --set motion.method=mog2"]


def test_sweep_refuses_a_param_no_grid_point_activates_before_writing(tmp_path, capsys):
    out = tmp_path / "study"
    assert main(["sweep", WALKER, "--param", "motion.mog2.var_threshold=8,40",
                 "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["motiontrack: error: --param motion.mog2.var_threshold has no effect while "
                   "motion.method = knn; add --set motion.method=mog2 (or sweep motion.method)"]
    assert not out.exists()


def test_sweep_over_the_method_and_its_keys_is_accepted_and_warns_of_dead_set_keys(
        tmp_path, capsys, monkeypatch):
    from types import SimpleNamespace

    import motiontrack.studies.sweep as sw

    ran = []
    monkeypatch.setattr(sw, "run_sweep", lambda study, *a, **k: ran.append(study)
                        or SimpleNamespace(rows=[], outputs={}))    # the study, not its runs
    assert main(["sweep", WALKER, "--param", "motion.method=knn,mog2",
                 "--param", "motion.mog2.var_threshold=8,40", "--set", "motion.mog2.history=50",
                 "--set", "people.hog_every=3", "-o", str(tmp_path / "s")]) == 0
    assert [k for k, _ in ran[0].grid] == ["motion.method", "motion.mog2.var_threshold"]
    warned = [ln for ln in capsys.readouterr().err.splitlines() if "WARNING" in ln]
    assert warned == ["motiontrack: WARNING: --set people.hog_every has no effect while "
                      "people.enabled = false and people.hog = off; add --set people.enabled=true "
                      "--set people.hog=regions"]


def test_tune_refuses_a_param_no_point_of_the_space_activates(tmp_path, capsys, monkeypatch):
    pytest.importorskip("optuna", reason="optuna not installed")
    import motiontrack.studies.tune as tu

    monkeypatch.setattr(tu, "execute", lambda *a, **k: pytest.fail("a trial ran"))
    out = tmp_path / "t"
    assert main(["tune", "--train", WALKER, "--param", "motion.mog2.var_threshold=8:40",
                 "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["motiontrack: error: --param motion.mog2.var_threshold has no effect while "
                   "motion.method = knn; add --set motion.method=mog2 (or search motion.method)"]
    assert not out.exists()


def test_a_tune_space_over_the_method_activates_its_keys():
    from motiontrack.config_activity import inactive_in_study
    from motiontrack.studies.tune import parse_space

    space = [parse_space("motion.method=knn,mog2"), parse_space("motion.mog2.var_threshold=8:40")]
    assert space[1].domain == (8.0, 40.0)
    assert inactive_in_study(load_config(None), [p.key for p in space],
                             {p.key: p.domain for p in space}) == []
