"""Many users, for real: a Debian nginx in front of two `bushing serve` processes, sticky sessions,
the websocket upgrade forwarded, sessions working on both processes and /liveness through it."""

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from app.deploy import nginx_config
from tests.helpers import free_port, wait_for

NGINX = shutil.which("nginx") or ("/usr/sbin/nginx" if Path("/usr/sbin/nginx").exists() else None)
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


@pytest.fixture
def balanced(tmp_path):
    if NGINX is None:  # fail, never skip: CI installs it
        pytest.fail("nginx is not installed (apt-get install -y nginx)")
    front = free_port()
    backs = [free_port(), free_port()]
    env = {"BUSHING_ALLOWED_ORIGINS": f"127.0.0.1:{front},localhost:{front}"}
    procs = [subprocess.Popen([sys.executable, "-m", "app.cli", "serve", "--port", str(p), "--address", "127.0.0.1"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env={**os.environ, **env})
             for p in backs]
    (tmp_path / "nginx.conf").write_text(nginx_config(front, backs, tmp_path))
    nginx = subprocess.Popen([NGINX, "-c", str(tmp_path / "nginx.conf"), "-p", str(tmp_path), "-g", "daemon off;"],
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        for p in backs:
            wait_for(f"http://127.0.0.1:{p}/liveness", timeout=60)
        wait_for(f"http://127.0.0.1:{front}/liveness", timeout=30)
        yield front, backs, tmp_path / "access.log"
    finally:
        nginx.terminate()
        nginx.wait(10)
        for proc in procs:
            proc.terminate()
            proc.wait(10)


def test_sessions_on_both_processes_through_nginx(balanced):
    from playwright.sync_api import sync_playwright

    front, backs, access_log = balanced
    if CHROMIUM is None:
        pytest.fail("Chromium is not installed (apt-get install -y chromium)")
    url = f"http://127.0.0.1:{front}/"
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
    time.sleep(0.5)
    lines = access_log.read_text().splitlines()
    websockets = [line for line in lines if "/ws" in line]
    used = {line.split()[0] for line in websockets}
    assert used == {f"127.0.0.1:{p}" for p in backs}, lines  # both processes hold sessions
    assert all(line.split()[1] == "101" for line in websockets)  # every websocket upgraded
    wait_for(f"http://127.0.0.1:{front}/liveness", timeout=10)  # 200 through nginx after the sessions, or it raises
