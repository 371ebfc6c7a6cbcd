"""Deployment helpers: the nginx configuration that puts several `bushing serve` processes behind
one address (``deploy/nginx.conf.template``; docs/serving.md), on one host or on several.

    python -m app.deploy --listen 0.0.0.0:80 --backend 10.0.0.11:5006 --backend 10.0.0.12:5006 \\
        --workdir /var/lib/bushing-nginx > nginx.conf

prints the configuration for nginx listening on ``--listen`` in front of every ``--backend``
(``host:port``, a `bushing serve` process each, on this host or others)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

TEMPLATE = Path(__file__).resolve().parents[1] / "deploy" / "nginx.conf.template"


def backend_address(backend: int | str, host: str = "127.0.0.1") -> str:
    """``host:port`` of a backend given as a port (on ``host``) or as ``host:port``."""
    if isinstance(backend, int) and not isinstance(backend, bool):
        port_text, host_text = str(backend), host
    else:
        host_text, sep, port_text = str(backend).rpartition(":")
        if not sep or not host_text:
            raise ValueError(f"backend {backend!r}: give host:port, e.g. 10.0.0.11:5006")
    if not port_text.isdigit() or not 1 <= int(port_text) <= 65535:
        raise ValueError(f"backend {backend!r}: the port must be a whole number from 1 to 65535")
    if any(c.isspace() or c in ";{}#'\"" for c in host_text):
        raise ValueError(f"backend {backend!r}: not a host name or address")
    return f"{host_text}:{int(port_text)}"


def nginx_config(port: int, backends: list[int | str], workdir: Path, host: str = "127.0.0.1") -> str:
    """The configuration for nginx listening on ``host:port`` in front of ``backends`` (ports
    on ``host``, on 127.0.0.1 if nginx listens on every interface; or ``host:port`` of processes
    on other hosts), with its pid file, logs and
    temporary files in ``workdir``."""
    if not backends:
        raise ValueError("give at least one backend")
    local = "127.0.0.1" if host in ("0.0.0.0", "::", "") else host  # a bare port: a process on this host
    servers = [backend_address(b, local) for b in backends]
    text = TEMPLATE.read_text(encoding="utf-8")
    values = {"pid": workdir / "nginx.pid", "error_log": workdir / "error.log", "access_log": workdir / "access.log",
              "temp": workdir, "port": port, "servers": "\n".join(f"        server {s};" for s in servers)}
    for key, value in values.items():
        text = text.replace("{" + key + "}", str(value))
    return text.replace("listen 127.0.0.1:", f"listen {host}:")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m app.deploy", description=__doc__.split("\n\n")[0])
    parser.add_argument("--listen", default="127.0.0.1:8080", help="host:port nginx listens on")
    parser.add_argument("--backend", action="append", required=True, help="host:port of a bushing serve process")
    parser.add_argument("--workdir", type=Path, default=Path("/var/lib/bushing-nginx"),
                        help="nginx's pid file, logs and temporary files")
    args = parser.parse_args(argv)
    try:
        listen_host, _sep, listen_port = backend_address(args.listen).rpartition(":")
        print(nginx_config(int(listen_port), args.backend, args.workdir, host=listen_host), end="")
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
