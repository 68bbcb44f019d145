# TMEye console server on the simulated rig (or real cameras with --source and a rig file).
# Debian-based (bookworm); runs as the non-root user `tmeye`; the data directory /data is a volume.
# Build: docker build -t tmeye .   Run: docker compose up -d (see docker-compose.yml).
FROM node:20-bookworm-slim AS web
WORKDIR /web
COPY web/package.json web/package-lock.json ./
RUN npm ci --no-audit --no-fund
COPY web/ ./
RUN npm run build

FROM python:3.11-slim-bookworm
RUN apt-get update && apt-get install -y --no-install-recommends libgl1 libglib2.0-0 \
    && rm -rf /var/lib/apt/lists/*
WORKDIR /src
COPY pyproject.toml setup.py README.md alembic.ini constraints.txt ./
COPY tracker tracker
COPY calibration calibration
COPY tmeye tmeye
COPY server server
COPY alembic alembic
COPY --from=web /web/dist web/dist
# A regular (not editable) install: the wheel carries the console (server/web_dist) and the migrations.
RUN pip install --no-cache-dir -c constraints.txt . && rm -rf /src \
    && useradd --system --home-dir /data --shell /usr/sbin/nologin --groups video,dialout tmeye \
    && mkdir -p /data && chown tmeye:tmeye /data
WORKDIR /data
USER tmeye
ENV TMEYE_DATA_DIR=/data TMEYE_HOST=0.0.0.0 TMEYE_PORT=8080 PYTHONUNBUFFERED=1
EXPOSE 8080
VOLUME ["/data"]
STOPSIGNAL SIGTERM
HEALTHCHECK --interval=30s --timeout=5s --start-period=90s --retries=3 \
    CMD python -c "import json,sys,urllib.request; sys.exit(0 if json.load(urllib.request.urlopen('http://127.0.0.1:8080/api/health', timeout=4)).get('status') == 'ok' else 1)"
CMD ["tmeye", "serve"]
