# The calstation package with its results server (see docker-compose.yml).
# The libraries are those of requirements.lock, each checked against its hashes (`make
# lock` writes it); calstation itself goes on top of them without choosing any of its own.
# pg_dump and pg_restore (`calstation db backup` / `restore`): Debian 13's client tools,
# PostgreSQL 17, dump and restore servers of 17 and older (the compose file's is 16).
FROM python:3.11-slim-trixie
RUN apt-get update \
    && apt-get install -y --no-install-recommends postgresql-client \
    && rm -rf /var/lib/apt/lists/*
WORKDIR /app
COPY requirements.lock ./
RUN pip install --no-cache-dir --require-hashes -r requirements.lock
COPY pyproject.toml README.md ./
COPY station ./station
COPY api ./api
COPY db ./db
RUN pip install --no-cache-dir --no-deps . && useradd --system --no-create-home calstation \
    && mkdir /backups && chown calstation /backups
USER calstation
EXPOSE 8000
CMD ["calstation", "serve", "--host", "0.0.0.0", "--port", "8000", "--workers", "4"]
