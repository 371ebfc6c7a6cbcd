"""The Dockerfile stays in step with the README and the command line (no Docker engine here)."""

import json
import re
from pathlib import Path

from app.main import _origins
from tests.helpers import fetch, served

ROOT = Path(__file__).resolve().parents[1]
DOCKERFILE = (ROOT / "Dockerfile").read_text(encoding="utf-8")


def instructions(name):
    return [line for line in DOCKERFILE.splitlines() if line.startswith(name + " ")]


def test_runs_as_a_non_root_user():
    users = instructions("USER")
    assert users and users[-1].split()[1] not in ("root", "0")


def test_serves_the_explorer_on_the_exposed_port_with_a_liveness_check():
    cmd = instructions("CMD")[-1]
    assert '"bushing", "serve"' in cmd or "/bushing\", \"serve\"" in cmd
    port = re.search(r'"--port", "(\d+)"', cmd).group(1)
    assert instructions("EXPOSE")[-1].split()[1] == port
    health = DOCKERFILE[DOCKERFILE.index("HEALTHCHECK"):]
    assert f"127.0.0.1:{port}/liveness" in health


def test_installs_the_package_as_the_readme_does():
    assert "pip install ." in DOCKERFILE and "python3 -m venv" in DOCKERFILE
    for path in ("pyproject.toml", "core", "app"):
        assert path in DOCKERFILE


def test_websocket_origins():
    assert _origins("0.0.0.0", 5006) == ["*"]
    assert "localhost:5006" in _origins("localhost", 5006)


def test_liveness_endpoint_answers():
    """The endpoint the health check asks for, on a real server (on a port the OS picks)."""
    from app.main import create_app

    with served(create_app, liveness=True, verbose=False) as server:
        answer = json.loads(fetch(f"http://127.0.0.1:{server.port}/liveness"))  # 200, or it raises
    assert answer and all(alive is True for alive in answer.values()), answer  # Panel: {path: alive}
