"""``GET /alerts``: the latest alerts the plant's rules fired (HTML, or JSON), linked
from every page's navigation (:mod:`api.alerts` fires and posts them)."""

import os
from typing import Annotated, Literal

from fastapi import APIRouter, Query, Request
from fastapi.responses import HTMLResponse, Response
from pydantic import BaseModel, Field

from api.deps import ReaderDep
from api.language import LanguageDep
from api.responses import problems
from api.routes.reports import PlantZoneDep
from db.report import recent_alerts
from station.domain.quality.alerts import Alert

router = APIRouter(tags=["pages"])

#: Alerts the page lists (the latest).
LISTED_ALERTS = 100


class AlertsAnswer(BaseModel):
    """The latest alerts and whether this server process checks rules."""

    alerts: list[Alert] = Field(description=f"the latest {LISTED_ALERTS}, the newest first")
    rounds: int | None = Field(
        description="rounds of the alert loop in this server process (None: no rules)"
    )
    process: int = Field(description="the server process that answered (its process id)")


@router.get(
    "/alerts",
    response_class=Response,
    responses={
        200: {
            "model": AlertsAnswer,
            "content": {"text/html": {"schema": {"type": "string"}}},
            "description": "the latest alerts: what fired, when, the evidence, a link to "
            "the units behind it (HTML, or JSON with `format=json`)",
        },
        **problems(422),
    },
)
async def get_alerts(
    request: Request,
    reader: ReaderDep,
    zone: PlantZoneDep,
    language: LanguageDep,
    format: Annotated[Literal["html", "json"], Query(description="the answer's format")] = "html",
) -> Response:
    """The latest alerts, the newest first."""
    # The rounds before the alerts: every round counted has committed what it fired or
    # cleared, so the alerts read after it hold at least that much.
    loop = request.app.state.alert_loop
    rounds = None if loop is None else loop.rounds
    alerts = await reader.run(lambda r: recent_alerts(r.session, LISTED_ALERTS))
    if format == "json":
        answer = AlertsAnswer(alerts=alerts, rounds=rounds, process=os.getpid())
        return Response(answer.model_dump_json(), media_type="application/json")
    from station.report import html

    return HTMLResponse(html.alerts_page(alerts, zone, rounds, language))
