"""Settings of the results server, read from ``CALSTATION_*`` environment variables."""

from typing import Annotated

from pydantic import Field

from db.settings import DatabaseSettings


class ApiSettings(DatabaseSettings):
    """Database location plus the server's own switches.

    ``read_requires_key``: read endpoints need a station API key too (default: open on
    the plant network). ``max_body_bytes``: larger request bodies are refused with 413.
    ``read_pool_size`` and ``write_pool_size``: database connections of each server
    process for reads and for submissions.
    """

    read_requires_key: bool = False
    max_body_bytes: Annotated[int, Field(ge=1024)] = 1024 * 1024
    read_pool_size: Annotated[int, Field(ge=1)] = 8
    write_pool_size: Annotated[int, Field(ge=1)] = 6
