# The calstation package with its results server (see docker-compose.yml).
# The libraries are those of requirements.lock, each checked against its hashes (`make
# lock` writes it); calstation itself goes on top of them without choosing any of its own.
FROM python:3.11-slim
WORKDIR /app
COPY requirements.lock ./
RUN pip install --no-cache-dir --require-hashes -r requirements.lock
COPY pyproject.toml README.md ./
COPY station ./station
COPY api ./api
COPY db ./db
RUN pip install --no-cache-dir --no-deps . && useradd --system --no-create-home calstation
USER calstation
EXPOSE 8000
CMD ["calstation", "serve", "--host", "0.0.0.0", "--port", "8000", "--workers", "4"]
