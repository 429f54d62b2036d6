"""The one error line of a command refused for bad input."""

from __future__ import annotations


def user_error(code: int, err: str, *words: str) -> str:
    """The one error line of a refused command (exit 2, no traceback); checks ``words`` are in
    it as written."""
    lines = [ln for ln in err.splitlines() if "error" in ln]
    assert code == 2, err
    assert "Traceback" not in err and "internal error" not in err, err
    assert len(lines) == 1 and lines[0].startswith("motiontrack: error: "), err
    for w in words:
        assert w in lines[0], (w, lines[0])
    return lines[0]
