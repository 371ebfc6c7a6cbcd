"""Many users, for real: a Debian nginx in front of two `bushing serve` processes, sticky sessions,
the websocket upgrade forwarded, sessions working on both processes and /liveness through it."""

import os
import re
import shutil
import signal
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from app.deploy import nginx_config
from tests.helpers import fetch, off_the_loop

NGINX = shutil.which("nginx") or ("/usr/sbin/nginx" if Path("/usr/sbin/nginx").exists() else None)
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


def start_backend(env: dict) -> tuple[subprocess.Popen, int]:
    """`bushing serve --port 0`: the OS picks the port, the command prints its URL once the
    socket is bound (a request then waits in the listen backlog until the server answers)."""
    proc = subprocess.Popen([sys.executable, "-m", "cli.main", "serve", "--port", "0", "--address", "127.0.0.1"],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, env={**os.environ, **env})
    line = proc.stdout.readline()  # blocks until printed (or the process ends: "")
    found = re.search(r"http://127\.0\.0\.1:(\d+)/", line)
    assert found, f"no URL printed: {line!r}"
    return proc, int(found.group(1))


def listening_socket() -> socket.socket:
    """A socket listening on 127.0.0.1 at a port the OS picks, for nginx to inherit."""
    sock = socket.socket()
    sock.bind(("127.0.0.1", 0))
    sock.listen(128)
    return sock


@pytest.fixture
def balanced(tmp_path):
    if NGINX is None:  # fail, never skip: CI installs it
        pytest.fail("nginx is not installed (apt-get install -y nginx)")
    front = listening_socket()
    port = front.getsockname()[1]
    env = {"BUSHING_ALLOWED_ORIGINS": f"127.0.0.1:{port},localhost:{port}"}
    procs = []
    try:
        backs = []
        for _ in range(2):
            proc, back = start_backend(env)
            procs.append(proc)
            backs.append(back)
        (tmp_path / "nginx.conf").write_text(nginx_config(port, backs, tmp_path))
        # nginx takes over the bound socket instead of binding the port itself: the file
        # descriptors in the NGINX variable are inherited listening sockets (what nginx's own
        # binary upgrade uses), matched to the `listen` address of the configuration
        nginx = subprocess.Popen([NGINX, "-c", str(tmp_path / "nginx.conf"), "-p", str(tmp_path), "-g", "daemon off;"],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, pass_fds=[front.fileno()],
                                 env={**os.environ, "NGINX": f"{front.fileno()};"})
        procs.append(nginx)
        front.close()  # nginx holds it
        yield port, backs, tmp_path / "access.log", nginx
    finally:
        front.close()
        for proc in reversed(procs):
            if proc.poll() is None:
                proc.terminate()
                proc.wait(10)


def test_sessions_on_both_processes_through_nginx(balanced):
    from playwright.sync_api import sync_playwright

    front, backs, access_log, nginx = balanced
    if CHROMIUM is None:
        pytest.fail("Chromium is not installed (apt-get install -y chromium)")
    url = f"http://127.0.0.1:{front}/"

    def six_sessions():  # a Playwright of its own, off any browser test's event loop
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=[
                "--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
                "--disable-sync", "--no-first-run", "--disable-quic"])
            pages = []
            for route in ("alpha", "beta", "gamma", "delta", "epsilon", "zeta"):
                context = browser.new_context(viewport={"width": 1400, "height": 1100})
                context.add_cookies([{"name": "bushing_route", "value": route, "url": url}])
                page = context.new_page()
                page.goto(url)
                page.locator(".bk-Canvas").nth(4).wait_for(timeout=60000)
                pages.append(page)
            for i, page in enumerate(pages):  # each session answers a change of its own
                field = page.get_by_label("Length L (mm)")
                field.fill(str(80 + i))
                field.press("Enter")
                page.wait_for_url(f"**L_mm={80 + i}**", timeout=20000)
            browser.close()

    off_the_loop(six_sessions)
    fetch(f"http://127.0.0.1:{front}/liveness", timeout=10)  # 200 through nginx after the sessions, or it raises
    # a graceful stop: nginx exits once every connection has ended, each logged when it ends
    # (a websocket's line is written when it closes)
    nginx.send_signal(signal.SIGQUIT)
    assert nginx.wait(30) == 0
    lines = access_log.read_text().splitlines()
    websockets = [line for line in lines if "/ws" in line]
    assert len(websockets) >= 6, lines  # one per page at least
    used = {line.split()[0] for line in websockets}
    assert used == {f"127.0.0.1:{p}" for p in backs}, lines  # both processes hold sessions
    assert all(line.split()[1] == "101" for line in websockets)  # every websocket upgraded
