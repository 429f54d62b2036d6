"""The numbers the docs show next to a command are what the command prints: every transcript
marked ``<!-- checked -->`` in README.md and docs/*.md is re-run (tools/doc_numbers.py)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from helpers import require

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tools"))

import doc_numbers  # noqa: E402

TRANSCRIPTS = doc_numbers.transcripts()


def test_docs_hold_checked_transcripts():
    where = {t.path.name for t in TRANSCRIPTS}
    assert {"studies.md", "pipeline.md", "flow_and_single.md"} <= where
    assert any(not t.slow for t in TRANSCRIPTS) and any(t.slow for t in TRANSCRIPTS)
    assert all(t.command.startswith("motiontrack ") and t.expected for t in TRANSCRIPTS)


def test_a_transcript_is_read_with_its_continued_command(tmp_path):
    doc = tmp_path / "doc.md"
    doc.write_text("text\n<!-- checked: slow -->\n```\n$ motiontrack gt-stats a.txt \\\n"
                   "      --image-size 8x8\nn_boxes  3\n```\n```\nmotiontrack list\n```\n")
    (t,) = doc_numbers.transcripts([doc])     # the unmarked block is not a transcript
    assert t.command == "motiontrack gt-stats a.txt --image-size 8x8"
    assert t.expected == ("n_boxes  3",) and t.slow and t.line == 4


PRINTED = """frames    250 in 4.58 s (54.5 fps)
tracks    2
accuracy  HOTA 0.832  MOTA 0.986  IDF1 0.993  IDSW 0  (scoring trackeval)
recommended_overrides   --set regions.min_size=0.000757802 --set regions.max_size=0.0358388 --set x=1
"""


@pytest.mark.parametrize("shown, problem", [
    (("accuracy  HOTA 0.832  MOTA 0.986  IDF1 0.993  IDSW 0  (scoring trackeval)",), None),
    (("tracks    2",), None),                                   # a selection of the lines
    (("accuracy  HOTA 0.83  MOTA 0.99  IDF1 0.99  IDSW 0  (scoring trackeval)",), None),  # fewer digits
    (("recommended_overrides --set regions.min_size=0.000757802 --set regions.max_size=0.0358388 ...",),
     None),                                                  # the rest of the line left out
    (("accuracy  HOTA 0.496  MOTA 0.986  IDF1 0.993  IDSW 0  (scoring trackeval)",), "shown"),
    (("accuracy  HOTA 0.831  MOTA 0.986  IDF1 0.993  IDSW 0  (scoring trackeval)",), "shown"),
    (("tracks    3",), "shown"),
    (("n_groups   113",), "not printed"),
    (("accuracy  HOTA 0.832  MOTA 0.986  IDF1 0.993  IDSW 0  (scoring ignore-regions)",),
     "not printed"),
])
def test_shown_numbers_must_match_the_printed_ones_to_the_digits_shown(shown, problem):
    found = doc_numbers.compare(shown, PRINTED)
    assert (found == []) if problem is None else (len(found) == 1 and found[0].startswith(problem))


def _check(t):
    if "../shared/data" in t.command:
        require()
    assert doc_numbers.check(t) == [], t.where


@pytest.mark.parametrize("t", [t for t in TRANSCRIPTS if not t.slow], ids=lambda t: t.where)
def test_fast_transcripts_print_what_the_docs_show(t):
    _check(t)


@pytest.mark.slow
@pytest.mark.parametrize("t", [t for t in TRANSCRIPTS if t.slow], ids=lambda t: t.where)
def test_slow_transcripts_print_what_the_docs_show(t):
    _check(t)
