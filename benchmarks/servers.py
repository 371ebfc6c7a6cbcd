"""The servers the browser benchmarks measure: the explorer of a tree (``bushing serve --port 0``)
and the floor pages (bokeh_floor.py, holoviews_floor.py), each a subprocess, and their stop.
Asserts nothing."""

from __future__ import annotations

import os
import re
import select
import subprocess
import sys
import threading
import time
import urllib.request
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from app_latency import free_port


def start_explorer(cwd: Path) -> tuple[subprocess.Popen, str]:
    """``bushing serve --port 0`` from the tree at ``cwd``; the process and the URL it printed."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}  # that tree's packages
    proc = subprocess.Popen([sys.executable, "-m", "cli.main", "serve", "--port", "0", "--address", "127.0.0.1"],
                            cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    deadline, seen = time.time() + 120, []
    while time.time() < deadline:
        ready, _, _ = select.select([proc.stdout], [], [], 1.0)
        line = proc.stdout.readline() if ready else ""
        seen.append(line)
        url = re.search(r"http://\S+/", line)
        if url:  # keep reading what it prints, so its pipe never fills
            threading.Thread(target=lambda: [None for _ in proc.stdout], daemon=True).start()
            return proc, url.group(0)
        if proc.poll() is not None:
            break
    proc.kill()
    raise RuntimeError("the explorer did not print its URL:\n" + "".join(seen))


# The explorer's sliders answer at once (app.inputs: their value is a priority change, no 50 ms
# debounce); the HoloViews floor's Panel sliders are made to do the same, or the floor would wait
# 50 ms per change that the explorer does not.
FLOOR_SERVE = {
    "bokeh_floor.py": "import bokeh_floor, sys; bokeh_floor.serve_floor(int(sys.argv[1]), 5)",
    "holoviews_floor.py": ("import holoviews_floor, panel, sys; panel.widgets.FloatSlider._priority_changes = "
                           "['value']; holoviews_floor.serve_floor(int(sys.argv[1]), 5)"),
}


def start_floor(script: str) -> tuple[subprocess.Popen, str]:
    """A floor page served by its own script's ``serve_floor`` as a subprocess."""
    port = free_port()
    probe = "/liveness" if "holoviews" in script else "/"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(HERE), str(HERE.parent)])}
    proc = subprocess.Popen([sys.executable, "-c", FLOOR_SERVE[script], str(port)], cwd=HERE.parent, env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 60
    while time.time() < deadline and proc.poll() is None:
        try:
            with urllib.request.urlopen(f"http://localhost:{port}{probe}", timeout=5):
                return proc, f"http://localhost:{port}/"
        except OSError:
            time.sleep(0.2)
    proc.kill()
    raise RuntimeError(f"{script}'s floor did not start")


def stop(proc: subprocess.Popen):
    proc.terminate()
    try:
        proc.wait(10)
    except subprocess.TimeoutExpired:
        proc.kill()
