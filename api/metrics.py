"""The results server's Prometheus metrics: what they are, how they are counted, ``/metrics``.

:class:`ServerMetrics` holds one app's metrics in a registry of its own (several apps in
one test process never collide); :class:`MetricsMiddleware` counts every HTTP request by
route template (``/api/v1/runs/{run_id}``, never the raw path: a serial in a label
would make a series per unit), method and status, and times it to its answer's start (an
event stream's lifetime is no latency). A 4xx to a run submission is also counted as
refused, by reason (:data:`REFUSAL_BY_STATUS`, or the reason a handler named with
:func:`refuse`). Runs stored are counted by the route when the database stored them, so
a retried submission (answered 200, already stored) is not counted twice.

With several worker processes (``calstation serve --workers N``) each worker counts its
own, in prometheus-client's multiprocess mode: ``calstation serve`` sets
``PROMETHEUS_MULTIPROC_DIR`` before the workers start, and ``/metrics`` adds up every
worker's files, whichever worker answers the scrape.
"""

import os
import re
import time

from fastapi import APIRouter, FastAPI, Request, Response
from fastapi.routing import APIRoute, iter_route_contexts
from prometheus_client import (
    CollectorRegistry,
    Counter,
    Gauge,
    Histogram,
    generate_latest,
)
from prometheus_client.multiprocess import MultiProcessCollector
from starlette.routing import Match, compile_path
from starlette.types import ASGIApp, Message, Receive, Scope, Send

#: The environment variable of prometheus-client's multiprocess mode (its own name).
MULTIPROC_DIR = "PROMETHEUS_MULTIPROC_DIR"

#: The text format every Prometheus reads (the client's newer 1.0.0 adds nothing used here).
CONTENT_TYPE = "text/plain; version=0.0.4; charset=utf-8"

#: The route label of a request no route matched (one series, whatever the path).
UNMATCHED = "<unmatched>"

#: The run submission route, whose 4xx answers count as refused submissions.
SUBMISSION = ("POST", "/api/v1/runs")

#: Why a run submission was refused, by its answer's status (unless a handler named it).
REFUSAL_BY_STATUS = {
    400: "unreadable",
    401: "unauthorized",
    403: "wrong_key",
    409: "conflict",
    413: "too_large",
    422: "invalid",
}

#: Latency buckets (seconds): a lookup answers in milliseconds, a report in seconds.
LATENCY_BUCKETS = (0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5, 5.0, 10.0, 30.0)


class ServerMetrics:
    """One app's metrics, in a registry of its own."""

    def __init__(self) -> None:
        self.registry = CollectorRegistry(auto_describe=True)
        r = self.registry
        self.requests = Counter(
            "calstation_http_requests",
            "HTTP requests answered, by route template, method and status",
            ["route", "method", "status"],
            registry=r,
        )
        self.latency = Histogram(
            "calstation_http_request_duration_seconds",
            "Seconds from a request's arrival to its answer's start, by route template",
            ["route", "method"],
            buckets=LATENCY_BUCKETS,
            registry=r,
        )
        self.runs_stored = Counter(
            "calstation_runs_stored",
            "Runs stored (once each: a retried submission is not counted again)",
            ["station", "verdict", "part_number"],
            registry=r,
        )
        self.submissions_refused = Counter(
            "calstation_run_submissions_refused",
            "Run submissions refused, by reason",
            ["reason"],
            registry=r,
        )
        self.report_processes = Gauge(
            "calstation_report_pool_processes",
            "Report processes of the server (each worker's added up)",
            registry=r,
            multiprocess_mode="livesum",
        )
        self.report_busy = Gauge(
            "calstation_report_pool_busy",
            "Report processes working on a report or the dashboard now",
            registry=r,
            multiprocess_mode="livesum",
        )
        self.report_waiting = Gauge(
            "calstation_report_pool_waiting",
            "Requests waiting for a free report process now",
            registry=r,
            multiprocess_mode="livesum",
        )
        self.reports_busy_refused = Counter(
            "calstation_report_pool_refused",
            "Reads answered 503 because every report process stayed busy",
            registry=r,
        )

    def exposition(self) -> bytes:
        """The text format of every metric (every worker's, in multiprocess mode)."""
        directory = os.environ.get(MULTIPROC_DIR)
        if directory:
            registry = CollectorRegistry()
            MultiProcessCollector(registry, path=directory)  # type: ignore[no-untyped-call]
            return generate_latest(registry)
        return generate_latest(self.registry)


def refuse(request: Request, reason: str) -> None:
    """Name why this request (a run submission) is refused, for the refusal counter."""
    request.state.refusal = reason


def documented_paths(app: FastAPI) -> list[str]:
    """The paths of ``app``'s OpenAPI document, in its order: those of its API routes kept
    in the schema, routers' prefixes included, as FastAPI's ``get_openapi`` walks them."""
    return list(
        dict.fromkeys(
            context.path_format
            for context in iter_route_contexts(app.routes)
            if isinstance(context.original_route, APIRoute)
            and context.include_in_schema
            and context.path_format is not None
        )
    )


class RouteTemplates:
    """The route template of a request: the path of the OpenAPI operation it matches
    (``/api/v1/runs/{run_id}``), else the path of the route the router chose (pages kept
    out of the document), else of a top-level route or mount it falls under (a request
    answered before routing, e.g. 413, has one too), else :data:`UNMATCHED`."""

    def __init__(self, app: FastAPI) -> None:
        self._app = app
        self._operations: list[tuple[re.Pattern[str], str]] | None = None

    def _documented(self) -> list[tuple[re.Pattern[str], str]]:
        """The document's paths, in its order, read off the routes as FastAPI writes them
        (:func:`documented_paths`), not by building the document: that took ~0.7 s of a
        fresh server's first request, its first ``/healthz``."""
        if self._operations is None:  # every route is included by the first request
            self._operations = [
                (compile_path(template)[0], template) for template in documented_paths(self._app)
            ]
        return self._operations

    def __call__(self, scope: Scope) -> str:
        path = scope["path"]
        for pattern, template in self._documented():
            if pattern.match(path):
                return template
        chosen = getattr(scope.get("route"), "path", None)
        if isinstance(chosen, str):
            return chosen
        for route in self._app.router.routes:
            match, _ = route.matches(scope)
            top = getattr(route, "path", None)
            if match is not Match.NONE and isinstance(top, str):
                return top
        return UNMATCHED


class MetricsMiddleware:
    """ASGI middleware counting and timing every HTTP request (the app's outermost)."""

    def __init__(self, app: ASGIApp, metrics: ServerMetrics, templates: RouteTemplates) -> None:
        self.app = app
        self.metrics = metrics
        self.templates = templates

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        started = time.perf_counter()
        answered = False

        async def counted(message: Message) -> None:
            nonlocal answered
            if message["type"] == "http.response.start":
                # Counted before the client can read the answer: a scrape that follows
                # it sees it.
                answered = True
                self._count(scope, int(message["status"]), time.perf_counter() - started)
            await send(message)

        try:
            await self.app(scope, receive, counted)
        finally:
            if not answered:  # the app failed: the server error middleware answers 500
                self._count(scope, 500, time.perf_counter() - started)

    def _count(self, scope: Scope, status: int, seconds: float) -> None:
        route, method = self.templates(scope), scope["method"]
        self.metrics.requests.labels(route, method, str(status)).inc()
        self.metrics.latency.labels(route, method).observe(seconds)
        if (method, route) == SUBMISSION and 400 <= status < 500:
            named = scope.get("state", {}).get("refusal")
            reason = named or REFUSAL_BY_STATUS.get(status, str(status))
            self.metrics.submissions_refused.labels(reason).inc()


def get_metrics(request: Request) -> ServerMetrics:
    """The app's metrics."""
    metrics: ServerMetrics = request.app.state.metrics
    return metrics


router = APIRouter(tags=["metrics"])


@router.get(
    "/metrics",
    response_class=Response,
    responses={
        200: {
            "description": "every metric in the Prometheus text format (version 0.0.4)",
            "content": {"text/plain": {"schema": {"type": "string"}}},
        }
    },
)
async def metrics(request: Request) -> Response:
    """The server's metrics for Prometheus (``docs/metrics.md``)."""
    return Response(get_metrics(request).exposition(), media_type=CONTENT_TYPE)


def install_metrics(app: FastAPI) -> ServerMetrics:
    """Give ``app`` its metrics, their middleware and ``GET /metrics``."""
    app.state.metrics = server_metrics = ServerMetrics()
    app.include_router(router)
    app.add_middleware(MetricsMiddleware, metrics=server_metrics, templates=RouteTemplates(app))
    return server_metrics
