"""``/redoc`` offline: ReDoc from the fastapi-offline package's own bundle, with the one
address in it that points at a CDN (the Redocly logo in the side menu,
``https://cdn.redoc.ly/redoc/logo-mini.svg``) replaced by an inline image, so the page
asks nothing of any other host, as ``/docs``.

The bundle is read and patched once, on first request, and served from its own path; the
package's unpatched copy stays where the package mounts it.
"""

from functools import cache
from pathlib import Path

import fastapi_offline
from fastapi import FastAPI, Request
from fastapi.openapi.docs import get_redoc_html
from fastapi.responses import HTMLResponse, Response

BUNDLE = Path(fastapi_offline.__file__).parent / "static" / "redoc.standalone.js"
#: The bundle's one CDN address, and what takes its place: a blank inline image.
CDN_LOGO = "https://cdn.redoc.ly/redoc/logo-mini.svg"
LOCAL_LOGO = "data:image/svg+xml,%3Csvg xmlns='http://www.w3.org/2000/svg' width='1' height='1'/%3E"
SCRIPT_PATH = "/static-offline-redoc/redoc.standalone.js"
FAVICON_PATH = "/static-offline-docs/favicon.png"


@cache
def bundle() -> bytes:
    """ReDoc's standalone bundle without its CDN address."""
    return BUNDLE.read_text(encoding="utf-8").replace(CDN_LOGO, LOCAL_LOGO).encode()


def add_redoc(app: FastAPI, path: str = "/redoc") -> None:
    """Serve ReDoc at ``path`` from the patched bundle (the app's own redoc page off)."""

    @app.get(SCRIPT_PATH, include_in_schema=False)
    async def redoc_script() -> Response:
        return Response(
            bundle(),
            media_type="application/javascript",
            headers={"Cache-Control": "public, max-age=86400"},
        )

    @app.get(path, include_in_schema=False)
    async def redoc_page(request: Request) -> HTMLResponse:
        root = request.scope.get("root_path", "")
        return get_redoc_html(
            openapi_url=f"{root}{app.openapi_url}",
            title=f"{app.title} - ReDoc",
            redoc_js_url=f"{root}{SCRIPT_PATH}",
            with_google_fonts=False,
            redoc_favicon_url=f"{root}{FAVICON_PATH}",
        )
