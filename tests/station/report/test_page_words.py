"""The words a page builds from stored English (where a report's limits come from) and
the place of a time axis' label: properties over the wordings and positions they take."""

import re

from hypothesis import given
from hypothesis import strategies as st

from station.domain.i18n import speaker
from station.report.svg import CHAR_WIDTH, _tick_label
from station.report.tables import NOT_ROLLED_UP, source_words

#: A limits profile as the report names it: ``name vN (sha256[:12])``.
PROFILES = st.builds(
    lambda name, version, sha: f"{name} v{version} ({sha})",
    st.from_regex(r"[a-z][a-z0-9-]{0,30}", fullmatch=True),
    st.integers(1, 999),
    st.from_regex(r"[0-9a-f]{12}", fullmatch=True),
)
MISSING = st.sampled_from(["no run in range", "no profile of the runs in range stored"])
#: Every wording of :func:`db.report.reports.report_bounds` and :mod:`db.report.split`,
#: as they build it.
SOURCES = st.one_of(
    PROFILES.map(lambda p: f"limits profile {p} (every run in range)"),
    st.tuples(PROFILES, st.integers(2, 50)).map(
        lambda pc: f"limits profile {pc[0]} (the latest run's, of {pc[1]} profiles in range)"
    ),
    PROFILES.map(lambda p: f"limits profile {p} (the latest run's whose profile is stored)"),
    MISSING.map(lambda m: f"the bounds the roll-ups were counted with ({m})"),
    MISSING.map(lambda m: f"no limits ({m}): no capability"),
    st.integers(2, 9).map(lambda n: f"each product against its own limits profile ({n} products)"),
    st.integers(2, 9).map(
        lambda n: f"each product against its own limits profile ({n} products in range)"
    ),
)


@given(SOURCES, st.booleans())
def test_where_the_limits_come_from_is_said_in_korean_and_chinese_with_its_values(
    source: str, from_runs: bool
) -> None:
    source += NOT_ROLLED_UP if from_runs else ""
    values = re.findall(r"[a-z0-9-]+ v\d+ \([0-9a-f]{12}\)|\d+", source)
    for language in ("ko", "zh"):
        said = source_words(source, speaker(language))
        assert said != source
        assert not re.search(r"\b(limits|profile|range|runs|stored|bounds)\b", said), said
        for value in values:
            assert value in said
    assert source_words(source) == source  # English: the wording as stored


@given(st.floats(0, 480), st.text(alphabet="0123456789-: ", min_size=1, max_size=16))
def test_a_time_axis_label_stays_inside_its_chart(x: float, label: str) -> None:
    drawn = _tick_label(x, 10.0, label, 480)
    anchor = re.search(r'text-anchor="(\w+)"', drawn)
    assert anchor is not None
    extent = CHAR_WIDTH * len(label)
    left = {"start": x, "middle": x - extent / 2, "end": x - extent}[anchor[1]]
    if extent < 240:  # a label that fits half the chart fits it from its tick
        assert left >= -1
        assert left + extent <= 481
