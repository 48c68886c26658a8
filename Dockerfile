# The calstation package with its results server (see docker-compose.yml).
FROM python:3.11-slim
WORKDIR /app
COPY pyproject.toml README.md ./
COPY station ./station
COPY api ./api
COPY db ./db
RUN pip install --no-cache-dir . && useradd --system --no-create-home calstation
USER calstation
EXPOSE 8000
CMD ["calstation", "serve", "--host", "0.0.0.0", "--port", "8000", "--workers", "4"]
