"""The ROS log's history without ROS (cell_nodes.inspect.log_history): bounded by count and age whatever the
storm, filtered by level, node and text as the page asks, the newest kept when a query is capped."""
from __future__ import annotations

import pytest

from cell_nodes.inspect.log_history import (MAX_TEXT, Entry, InspectConfigError, LogHistory, Query,
                                            parse_inspect)

DEBUG, INFO, WARN, ERROR, FATAL = 1, 2, 4, 8, 16


def entry(i: int, level: int = INFO, node: str = "/a", msg: str = "") -> Entry:
    return Entry(1000.0 + i, level, node, msg or f"message {i}", "a.py", "f", i)


def test_a_storm_keeps_the_newest_entries_and_counts_the_rest() -> None:
    h = LogHistory(max_entries=100, max_age_s=3600)
    for i in range(10_000):
        h.add(entry(i / 1000), now=1000 + i / 1000)            # 1 kHz for 10 s
    got, matched, dropped, kept = h.query(Query(), now=1010)
    assert matched == len(got) == 100 and dropped == 9900
    assert got[0].msg == "message 9.9" and got[-1].msg == "message 9.999"


def test_entries_older_than_the_age_leave_even_when_nothing_new_comes() -> None:
    h = LogHistory(max_entries=1000, max_age_s=60)
    for i in range(0, 120, 10):
        h.add(entry(i), now=1000 + i)
    got, _, dropped, kept = h.query(Query(), now=1110)
    assert [e.line for e in got] == [50, 60, 70, 80, 90, 100, 110] and dropped == 5 and kept == 60
    got, _, dropped, kept = h.query(Query(), now=2000)          # a quiet hour later
    assert got == [] and dropped == 12 and kept == 0


def test_filters_by_level_node_and_text_like_the_page() -> None:
    h = LogHistory(max_entries=1000, max_age_s=3600)
    h.add(entry(0, DEBUG, "/driver", "tick"))
    h.add(entry(1, WARN, "/driver", "RTDE rate low: 98 Hz"))
    h.add(entry(2, ERROR, "/process_node", "Move failed: protective stop"))
    h.add(entry(3, INFO, "/process_node", "started"))
    h.add(entry(4, FATAL, "/alarms", "cannot read the cell file"))

    def msgs(**kw) -> list[str]:
        return [e.msg for e in h.query(Query(**kw), now=1010)[0]]

    assert msgs(min_level=WARN) == ["RTDE rate low: 98 Hz", "Move failed: protective stop", "cannot read the cell file"]
    assert msgs(node="/process_node") == ["Move failed: protective stop", "started"]
    assert msgs(text="PROTECTIVE") == ["Move failed: protective stop"]
    assert msgs(text="driver", min_level=INFO) == ["RTDE rate low: 98 Hz"]              # the node's name matches too
    got, matched, _, _ = h.query(Query(max_entries=2), now=1010)
    assert [e.line for e in got] == [3, 4] and matched == 5                             # the newest two


def test_a_huge_message_is_cut() -> None:
    h = LogHistory(max_entries=10, max_age_s=60)
    h.add(entry(0, msg="x" * (MAX_TEXT * 3)), now=1000)
    [e] = h.query(Query(), now=1000)[0]
    assert len(e.msg) == MAX_TEXT + len(" [cut]") and e.msg.endswith(" [cut]")


@pytest.mark.parametrize("section, message", [
    ("all", "inspect: expected a mapping"),
    ({"log_keep_entries": 0}, "inspect.log_keep_entries: expected an integer from 1 to 1000000, got 0"),
    ({"log_keep_entries": 1.5}, "inspect.log_keep_entries"),
    ({"log_keep_s": "10 min"}, "inspect.log_keep_s: expected a number from 1 to 86400, got '10 min'"),
])
def test_a_section_the_node_cannot_use_names_the_field(section, message) -> None:
    with pytest.raises(InspectConfigError, match=message):
        parse_inspect({"inspect": section})


def test_the_defaults() -> None:
    assert parse_inspect({"inspect": {}}) == (5000, 600.0)
    assert parse_inspect({"inspect": {"log_keep_entries": 20, "log_keep_s": 30}}) == (20, 30.0)
    with pytest.raises(ValueError):
        LogHistory(0, 10)
