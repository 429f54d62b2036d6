"""The HTML report's layout: key metrics first, the best run marked, only the parameters of
stages that ran."""

from __future__ import annotations

import json
import re

from motiontrack.config import load_config
from motiontrack.studies.report import build_report
from motiontrack.studies.sweep import study_from_args, versions
from motiontrack.studies.table import summarise_runs, write_table

WALKER = "synth:walker?n_frames=10"


def make_study(folder, params, overrides=(), metrics=None):
    """A study folder as a sweep leaves it (study.json, results.csv, summary.csv), with the
    metrics given per run instead of measured."""
    st = study_from_args([WALKER], None, params, load_config(None, list(overrides)))
    folder.mkdir(parents=True)
    (folder / "study.json").write_text(json.dumps({**st.as_dict(), "versions": versions(),
                                                   "runs": len(metrics)}))
    key = st.keys[0]
    rows = [{"run": run, "sequence": "walker", "group": "", key: value, "HOTA": h, "MOTA": m,
             "IDF1": i} for run, (value, h, m, i) in enumerate(metrics, start=1)]
    write_table(rows, folder / "results.csv")
    write_table(summarise_runs(rows, st.keys), folder / "summary.csv")
    return folder


THRESHOLDS = [  # value, HOTA, MOTA, IDF1: run 2 has the best HOTA, run 3 the best MOTA
    (0.1, 0.41, 0.50, 0.61),
    (0.2, 0.57, 0.62, 0.79),
    (0.3, 0.52, 0.71, 0.70),
]


def _rows_of(html: str, section: str) -> list[str]:
    start = html.index(section)
    end = html.index("</table>", start)
    return re.findall(r"<tr[^>]*>.*?</tr>", html[start:end])


def test_key_metrics_come_before_figures_and_big_tables(tmp_path):
    html = build_report(make_study(tmp_path / "s", ["motion.median.threshold=0.1,0.2,0.3"],
                                   ["motion.method=median"], THRESHOLDS))
    key = html.index('id="key-metrics"')
    for later in ("<h2>Sequences", "<h2>Figures", "<h2>Summary", "<h2>All runs",
                  "<h2>Base tracker parameters"):
        assert key < html.index(later), later
    block = html[key:html.index("</section>", key)]
    best, best_hota, best_mota, best_idf1 = _rows_of(block, "<tbody>")
    # the best run by HOTA with its setting and its three key metrics
    assert re.findall(r"<td>([^<]*)</td>", best) == ["\u2605 2", "0.2", "0.57", "0.62", "0.79"]
    assert "best HOTA" in best_hota and "\u2605 2" in best_hota
    assert "best MOTA" in best_mota and ">3<" in best_mota and "0.71" in best_mota
    assert "best IDF1" in best_idf1 and "\u2605 2" in best_idf1


def test_best_run_is_marked_in_both_tables(tmp_path):
    html = build_report(make_study(tmp_path / "s", ["motion.median.threshold=0.1,0.2,0.3"],
                                   ["motion.method=median"], THRESHOLDS))
    for section in ("<h2>Summary", "<h2>All runs"):
        rows = _rows_of(html, section)[1:]                     # the header row left out
        marked = [r for r in rows if 'class="best"' in r]
        assert len(marked) == 1 and "\u2605 2</td>" in marked[0], section
        assert all("\u2605" not in r for r in rows if r not in marked)


def _parameters(html: str) -> set[str]:
    start = html.index("<h2>Base tracker parameters")
    return set(re.findall(r"<tr[^>]*><th>([^<]+)</th>", html[start:html.index("<h2>Software", start)]))


def test_parameter_dump_shows_only_stages_and_methods_that_ran(tmp_path):
    html = build_report(make_study(tmp_path / "s", ["motion.knn.dist2_threshold=200,400"],
                                   ["motion.method=knn"], [(200, .5, .5, .5), (400, .6, .6, .6)]))
    shown = _parameters(html)
    assert "motion.method" in shown and "motion.knn.dist2_threshold" in shown
    assert "regions.min_area" in shown and "tracker.method" in shown
    assert not any(k.startswith(("motion.mog2.", "motion.median.", "motion.gsoc.")) for k in shown)
    assert "people.enabled" in shown                          # the switch itself is shown
    assert "people.hog_every" not in shown                    # the people stage is off
    assert "left out" in html


def test_parameter_dump_keeps_every_method_the_grid_runs(tmp_path):
    html = build_report(make_study(tmp_path / "s", ["motion.method=knn,mog2"], (),
                                   [("knn", .5, .5, .5), ("mog2", .6, .6, .6)]))
    shown = _parameters(html)
    assert any(k.startswith("motion.knn.") for k in shown)
    assert any(k.startswith("motion.mog2.") for k in shown)
    assert not any(k.startswith("motion.median.") for k in shown)


def test_study_without_tracking_metrics_says_so(tmp_path):
    folder = make_study(tmp_path / "s", ["motion.median.threshold=0.1,0.2"],
                        ["motion.method=median"], [(0.1, .5, .5, .5), (0.2, .6, .6, .6)])
    write_table([{"run": 1, "sequence": "walker", "group": "", "motion.median.threshold": 0.1}],
                folder / "results.csv")
    (folder / "summary.csv").unlink()
    html = build_report(folder)
    assert "No tracking metrics" in html and 'class="best"' not in html


def test_base_parameters_mark_the_swept_key_and_write_whole_numbers_as_integers(tmp_path):
    html = build_report(make_study(tmp_path / "s", ["motion.knn.dist2_threshold=200,400"],
                                   ["motion.method=knn"], [(200, .5, .5, .5), (400, .6, .6, .6)]))
    start = html.index("<h2>Base tracker parameters")
    block = html[start:html.index("<h2>Software", start)]
    swept = re.findall(r'<tr class="swept"><th>([^<]+)</th><td class="t">(.*?)</td></tr>', block)
    assert [(k, re.sub(r"<[^>]+>", "", v)) for k, v in swept] == [
        ("motion.knn.dist2_threshold", "swept: 200, 400 (base 300, used by no run)")]
    # a float field with a whole value reads as the integer; others keep their digits
    assert '<th>regions.min_area</th><td class="t">100</td>' in block
    assert '<th>regions.min_size</th><td class="t">0.001</td>' in block
    assert "300.0" not in block and "100.0" not in block
