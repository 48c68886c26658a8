"""The one place the report's pages build a link from: any filter, put into any page's
address by ``href`` and read back as the route reads its query, is the same filter."""

from datetime import UTC, datetime
from urllib.parse import parse_qs, urlsplit

from hypothesis import given
from hypothesis import strategies as st

from api.routes.reports import Period
from station.domain.constants import IDENTIFIER_PATTERN
from station.domain.quality.figures import ReportFilter
from station.report.html import FAILING_RUNS_PATH, REPORT_PATH, RUNS_CSV_PATH, SPLIT_PATH, href

NAMES = st.none() | st.from_regex(IDENTIFIER_PATTERN, fullmatch=True)
#: Moments as the form writes them: whole seconds (UTC, the default plant zone).
MOMENTS = st.none() | st.datetimes(
    min_value=datetime(1971, 1, 1), max_value=datetime(9998, 12, 31), timezones=st.just(UTC)
).map(lambda at: at.replace(microsecond=0))
#: Each page's address and its own parameters beside the filter.
PAGES = [
    (REPORT_PATH, {"format": "csv", "list": "all", "units": "50", "page": "2"}),
    (RUNS_CSV_PATH, {}),
    (SPLIT_PATH, {"parameter": "offset_x", "by": "station"}),
    (FAILING_RUNS_PATH, {"code": "offset_out_of_range"}),
]


@st.composite
def filters(draw: st.DrawFn) -> ReportFilter:
    since, until = draw(MOMENTS), draw(MOMENTS)
    if since is not None and until is not None and until <= since:
        since, until = (until, since) if until < since else (since, None)
    return ReportFilter(
        since=since,
        until=until,
        station_id=draw(NAMES),
        operator_id=draw(NAMES),
        lot=draw(NAMES),
        part_number=draw(NAMES),
    )


@given(filters())
def test_every_page_address_carries_the_whole_filter(filter: ReportFilter) -> None:
    for path, params in PAGES:
        address = urlsplit(href(filter, "UTC", path, **params))
        assert address.path == path
        query = {name: values[-1] for name, values in parse_qs(address.query).items()}
        assert {name: query[name] for name in params} == params
        period = Period(
            since=query.get("from"),
            until=query.get("to"),
            station=query.get("station"),
            operator=query.get("operator"),
            lot=query.get("lot"),
            part_number=query.get("part_number"),
        )
        assert period.filter("UTC") == filter


@given(filters(), NAMES)
def test_a_param_overrides_the_filter_and_none_leaves_it_out(
    filter: ReportFilter, station: str | None
) -> None:
    query = parse_qs(urlsplit(href(filter, "UTC", station=station)).query)
    assert query.get("station") == (None if station is None else [station])
    assert query.get("part_number") == (
        None if filter.part_number is None else [filter.part_number]
    )
