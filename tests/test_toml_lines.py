"""The one TOML line locator: keys, tables and arrays of tables by dotted path, and the nearest
written line for a key left to its default."""

from __future__ import annotations

from particlebot.toml_lines import key_lines, line_of

TEXT = """\
name = "trial run"   # line 1

[[trial]]
method = "D"
set = { CYCLE_STEPS = 75 }

[[trial]]
method = "B"

[trial.set]
WAVE_SIZE = 3
"""


def test_each_key_and_table_is_found_at_its_line() -> None:
    lines = key_lines(TEXT)
    assert lines["name"] == 1
    assert lines["trial[1]"] == 3 and lines["trial[1].method"] == 4
    assert lines["trial[1].set"] == 5
    assert lines["trial[2]"] == 7 and lines["trial[2].method"] == 8
    # [trial.set] after the second [[trial]] belongs to it
    assert lines["trial[2].set"] == 10 and lines["trial[2].set.WAVE_SIZE"] == 11


def test_a_key_not_written_points_at_the_nearest_table_above_it() -> None:
    lines = key_lines(TEXT)
    assert line_of(lines, "trial[2].set.WAVE_SIZE") == 11
    assert line_of(lines, "trial[1].set.CYCLE_STEPS") == 5  # inside an inline table
    assert line_of(lines, "trial[2].repetitions") == 7
    assert line_of(lines, "seed") == 1  # nothing above: the first line
