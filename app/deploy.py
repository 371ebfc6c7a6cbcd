"""Deployment helpers: the nginx configuration that puts several `bushing serve` processes behind
one address (``deploy/nginx.conf.template``; the README's Deployment section)."""

from __future__ import annotations

from pathlib import Path

TEMPLATE = Path(__file__).resolve().parents[1] / "deploy" / "nginx.conf.template"


def nginx_config(port: int, backends: list[int], workdir: Path, host: str = "127.0.0.1") -> str:
    """The configuration for nginx listening on ``host:port`` in front of ``backends`` (ports
    on ``host``), with its pid file, logs and temporary files in ``workdir``."""
    text = TEMPLATE.read_text(encoding="utf-8")
    values = {"pid": workdir / "nginx.pid", "error_log": workdir / "error.log", "access_log": workdir / "access.log",
              "temp": workdir, "port": port, "servers": "\n".join(f"        server {host}:{p};" for p in backends)}
    for key, value in values.items():
        text = text.replace("{" + key + "}", str(value))
    return text.replace("listen 127.0.0.1:", f"listen {host}:")
