# TMEye console server on the simulated rig (or real cameras with --source and a rig file).
FROM node:20-bookworm-slim AS web
WORKDIR /web
COPY web/package.json web/package-lock.json ./
RUN npm ci --no-audit --no-fund
COPY web/ ./
RUN npm run build

FROM python:3.11-slim-bookworm
RUN apt-get update && apt-get install -y --no-install-recommends libgl1 libglib2.0-0 && rm -rf /var/lib/apt/lists/*
WORKDIR /app
COPY pyproject.toml README.md alembic.ini ./
COPY tracker tracker
COPY calibration calibration
COPY tmeye tmeye
COPY server server
COPY alembic alembic
COPY --from=web /web/dist web/dist
RUN pip install --no-cache-dir -e . && useradd --system --home /data tmeye && mkdir -p /data && chown tmeye /data
USER tmeye
ENV TMEYE_DATA_DIR=/data TMEYE_HOST=0.0.0.0 TMEYE_PORT=8080
EXPOSE 8080
VOLUME ["/data"]
HEALTHCHECK --interval=30s --timeout=5s --start-period=60s CMD python -c "import urllib.request,sys; sys.exit(0 if b'\"ok\"' in urllib.request.urlopen('http://127.0.0.1:8080/api/health').read() else 1)"
CMD ["tmeye", "serve"]
