"""Optuna tuning (optional extra): search space parsing, determinism, best config usable by track."""

from __future__ import annotations

import pytest

from motiontrack.config import load_config
from motiontrack.errors import ConfigError
from motiontrack.io.manifest import SequenceSpec
from motiontrack.studies.tune import SearchParam, parse_space

optuna = pytest.importorskip("optuna", reason="optuna not installed (pip install optuna)")


@pytest.mark.parametrize("text, expected", [
    ("motion.median.threshold=0.02:0.4", SearchParam("motion.median.threshold", "float", 0.02, 0.4)),
    ("regions.min_area=50:2000:log", SearchParam("regions.min_area", "int", 50, 2000, log=True)),
    ("regions.min_size=0.001:0.01:log", SearchParam("regions.min_size", "float", 0.001, 0.01, log=True)),
    ("cleanup.dilate_iterations=0:4", SearchParam("cleanup.dilate_iterations", "int", 0, 4)),
    ("motion.method=median,mog2", SearchParam("motion.method", "categorical", choices=("median", "mog2"))),
    # a stepped range: the values of the sweep grid with the same text, the last one as high
    ("motion.median.threshold=0.02:0.2:0.02",
     SearchParam("motion.median.threshold", "float", 0.02, 0.2, step=0.02)),
    ("regions.min_area=1:6:2", SearchParam("regions.min_area", "int", 1, 5, step=2)),
])
def test_parse_space(text, expected):
    assert parse_space(text) == expected


@pytest.mark.parametrize("text", ["a.b", "a.b=", "a.b=1:x", "a.b=2:1", "a.b=0:1:log", "a.b=1:2:3:4",
                                  "a.b=0:1:0", "a.b=0:1:x", "a.b=2:1:1"])
def test_parse_space_rejects(text):
    with pytest.raises(ConfigError):
        parse_space(text)


@pytest.mark.parametrize("text", ["motion.median.threshold=0.02:0.2:0.02", "regions.min_area=1:6:2"])
def test_stepped_search_range_proposes_only_the_sweep_grid_values(text):
    from motiontrack.studies.params import parse_param

    grid = set(parse_param(text)[1])
    dim = parse_space(text)
    study = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=0))
    proposed = []
    study.optimize(lambda trial: proposed.append(dim.suggest(trial)) or 0.0, n_trials=30)
    assert set(proposed) <= grid and len(set(proposed)) > 1


TRAIN = (SequenceSpec("walker", "synth:walker?n_frames=40"),)
VAL = (SequenceSpec("crossing", "synth:crossing?n_frames=40"),)
SPACE = (parse_space("motion.median.threshold=0.02:0.45"),)


@pytest.fixture(scope="module")
def tuned():
    from motiontrack.studies.tune import tune

    base = load_config(None, ["motion.method=median"])
    return [tune(TRAIN, VAL, SPACE, base, metric="det_object_f1", n_trials=4, seed=3)
            for _ in range(2)]


@pytest.mark.slow
def test_tune_is_deterministic_and_scores_validation(tuned):
    a, b = tuned
    assert a.best_params == b.best_params and a.train_score == b.train_score
    assert len(a.trials) == 4
    best = max(t["det_object_f1"] for t in a.trials)
    assert a.train_score == best                            # the best trial is reported
    assert 0.0 <= a.validation_score <= 1.0                 # scored on the held-apart sequence
    assert a.best_config.motion.median.threshold == a.best_params["motion.median.threshold"]


@pytest.mark.slow
def test_best_config_loads_with_track_config(tuned, tmp_path):
    from motiontrack.studies.tune import write_tune_outputs

    paths = write_tune_outputs(tuned[0], tmp_path)
    cfg = load_config(paths["config"])
    assert cfg == tuned[0].best_config
    assert (tmp_path / "trials.csv").read_text().count("\n") == 1 + 4


def test_unknown_metric_is_a_config_error():
    from motiontrack.studies.tune import tune

    with pytest.raises(ConfigError, match="unknown metric"):
        tune(TRAIN, (), SPACE, load_config(None, ["motion.method=median"]), metric="nope", n_trials=1)


@pytest.mark.slow
def test_cli_tune(tmp_path, capsys):
    from motiontrack.cli import main

    code = main(["-q", "tune", "--train", "synth:walker?n_frames=30", "--val", "synth:crossing?n_frames=30",
                 "--set", "motion.method=median", "--param", "motion.median.threshold=0.05:0.3",
                 "--trials", "2", "-o", str(tmp_path)])
    assert code == 0
    out = capsys.readouterr().out
    assert "validate  det_object_f1" in out
    assert (tmp_path / "best_config.toml").is_file()


def test_an_interrupted_tuning_writes_the_best_of_its_finished_trials(tmp_path, monkeypatch,
                                                                       capsys):
    import json

    import motiontrack.studies.tune as tune_module
    from motiontrack.cli import main

    calls = []

    def execute(specs, jobs=1):   # trial k scores k / 10; Ctrl-C during the third trial
        calls.append(len(specs))
        if len(calls) == 3:
            raise KeyboardInterrupt
        return [{"row": {"det_object_f1": len(calls) / 10}} for _ in specs]

    monkeypatch.setattr(tune_module, "execute", execute)
    code = main(["-q", "tune", "--train", "synth:walker", "--val", "synth:crossing",
                 "--param", "motion.knn.history=100:900", "--trials", "10", "-o", str(tmp_path)])
    assert code == 130
    assert len(calls) == 3                      # no validation run after the interrupt
    doc = json.loads((tmp_path / "tune.json").read_text())
    assert doc["interrupted"] is True and doc["n_trials"] == 2
    assert doc["train_score"] == 0.2 and doc["validation_score"] is None
    assert (tmp_path / "trials.csv").read_text().count("\n") == 1 + 2
    assert (tmp_path / "best_config.toml").is_file()
    assert "train     det_object_f1 0.2000" in capsys.readouterr().out


def test_a_tuning_interrupted_before_any_trial_finished_writes_nothing(tmp_path, monkeypatch):
    import motiontrack.studies.tune as tune_module
    from motiontrack.cli import main

    def execute(specs, jobs=1):
        raise KeyboardInterrupt

    monkeypatch.setattr(tune_module, "execute", execute)
    code = main(["-q", "tune", "--train", "synth:walker", "--param", "motion.knn.history=100:900",
                 "--trials", "10", "-o", str(tmp_path / "t")])
    assert code == 130 and not (tmp_path / "t" / "tune.json").exists()
