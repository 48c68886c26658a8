"""The ``Calstation-Outbox`` header: every report reads back as sent; a header that is
not three whole-number figures named once each is refused, the header named."""

import pytest
from hypothesis import given
from hypothesis import strategies as st

from station.domain.errors import InputError
from station.domain.record.outbox_report import OUTBOX_HEADER, OutboxReport, parse_outbox_header

figures = st.integers(0, 2**31 - 1)
reports = st.builds(OutboxReport, queued=figures, oldest_s=figures, set_aside=figures)


@given(reports)
def test_every_report_reads_back_as_sent(report: OutboxReport) -> None:
    assert parse_outbox_header(report.header()) == report


@given(reports, st.sampled_from(["queued", "oldest_s", "set_aside"]), st.integers(1, 2**40))
def test_a_figure_below_zero_or_beyond_a_column_is_refused(
    report: OutboxReport, name: str, beyond: int
) -> None:
    for figure in (f"-{beyond}", str(2**31 - 1 + beyond)):
        value = report.header().replace(f"{name}={getattr(report, name)}", f"{name}={figure}")
        with pytest.raises(InputError, match=f"^{OUTBOX_HEADER}: "):
            parse_outbox_header(value)


@pytest.mark.parametrize(
    ("value", "named"),
    [
        ("queued=1; oldest_s=0", "set_aside: Field required"),
        ("queued=1; oldest_s=0; set_aside=0; queued=2", "queued given twice"),
        ("queued=1; oldest_s=0; set_aside=0; colour=2", "colour: Extra inputs"),
        ("queued=many; oldest_s=0; set_aside=0", "'queued=many' is not name=whole number"),
        ("queued=1.5; oldest_s=0; set_aside=0", "'queued=1.5' is not name=whole number"),
        ("", "'' is not name=whole number"),
    ],
)
def test_a_header_that_is_not_the_three_figures_is_refused_naming_why(
    value: str, named: str
) -> None:
    with pytest.raises(InputError, match=f"^{OUTBOX_HEADER}: ") as refused:
        parse_outbox_header(value)
    assert named in str(refused.value)
