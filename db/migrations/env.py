"""Alembic environment: runs on the connection handed over by :mod:`db.migrate`."""

from alembic import context

from db import models  # noqa: F401  (registers every table on the metadata)
from db.base import Base
from db.partitions import include_name

connection = context.config.attributes["connection"]
context.configure(
    connection=connection,
    target_metadata=Base.metadata,
    render_as_batch=True,
    compare_type=True,
    include_name=include_name,
)
with context.begin_transaction():
    context.run_migrations()
