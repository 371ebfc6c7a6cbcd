# Bushing Explorer: the browser app, served as a non-root user, with a liveness check.
#   docker build -t bushing-explorer .
#   docker run -p 5006:5006 bushing-explorer        → http://localhost:5006/
# The same steps as the README's run command: a virtual environment, the package, `bushing serve`.
FROM python:3.11-slim

ENV PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    PIP_NO_CACHE_DIR=1 \
    PIP_DISABLE_PIP_VERSION_CHECK=1

WORKDIR /opt/bushing
COPY pyproject.toml README.md LICENSE ./
COPY core ./core
COPY app ./app
COPY cli ./cli
COPY fmu ./fmu
RUN python3 -m venv /opt/venv && /opt/venv/bin/pip install . \
    && useradd --create-home --uid 10001 bushing

USER bushing
WORKDIR /home/bushing
EXPOSE 5006

# Panel's liveness endpoint answers once the server accepts sessions.
HEALTHCHECK --interval=30s --timeout=5s --start-period=30s --retries=3 \
    CMD ["/opt/venv/bin/python", "-c", "import urllib.request; urllib.request.urlopen('http://127.0.0.1:5006/liveness', timeout=4)"]

# Bound to every interface; set BUSHING_ALLOWED_ORIGINS (comma-separated host:port) to restrict
# which page origins may open sessions.
CMD ["/opt/venv/bin/bushing", "serve", "--address", "0.0.0.0", "--port", "5006"]
