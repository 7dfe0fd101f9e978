"""A headless Chromium that loads a page and screenshots it, driven over the DevTools
protocol (the websocket client viser itself depends on): for tests of `lf3pm view`
in a real browser. Software WebGL (SwiftShader), so no GPU is needed."""

from __future__ import annotations

import base64
import json
import os
import shutil
import signal
import subprocess
import tempfile
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest

from lf3pm.view import free_port

CANDIDATES = ("chromium", "chromium-browser", "google-chrome")


def chromium() -> str | None:
    """The path of a Chromium-like browser, or None."""
    return next((path for path in map(shutil.which, CANDIDATES) if path), None)


#: Marks a test that needs a real browser: skipped, saying how to get one, where none is.
needs_chromium = pytest.mark.skipif(
    chromium() is None,
    reason="no Chromium for the browser test (Debian: apt-get install chromium; `make test` "
    "installs it when run as root)",
)


def screenshot(url: str, path: Path, *, seconds: float = 20.0, size=(1280, 800), ready=None) -> np.ndarray:
    """Loads ``url`` in headless Chromium, waits until ``ready(image)`` holds for a
    screenshot (polled every second; default: never) or ``seconds`` pass, writes the last
    screenshot to ``path`` and returns it as an RGB array."""
    import imageio.v3 as iio
    import websockets.sync.client

    browser = chromium()
    if browser is None:
        raise RuntimeError("no Chromium found (Debian: apt-get install chromium)")
    # Chromium's helpers (renderer, GPU, crash handler) may still write into the profile for
    # a moment after the browser exits: its cleanup must not fail the test.
    with tempfile.TemporaryDirectory(ignore_cleanup_errors=True) as profile:
        debug_port = free_port()
        proc = subprocess.Popen(
            [
                browser,
                "--headless=new",
                "--no-sandbox",
                "--use-angle=swiftshader",
                "--enable-unsafe-swiftshader",
                "--no-first-run",
                "--disable-extensions",
                f"--remote-debugging-port={debug_port}",
                f"--window-size={size[0]},{size[1]}",
                f"--user-data-dir={profile}",
                "about:blank",
            ],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,  # its own process group: stopped with its helpers
        )
        try:
            page = _page(debug_port)
            with websockets.sync.client.connect(page["webSocketDebuggerUrl"], max_size=None) as ws:
                calls = iter(range(1, 1 << 30))

                def call(method, **params):
                    mid = next(calls)
                    ws.send(json.dumps({"id": mid, "method": method, "params": params}))
                    while True:
                        message = json.loads(ws.recv(timeout=60))
                        if message.get("id") == mid:
                            return message.get("result", {})

                call("Page.navigate", url=url)
                deadline = time.monotonic() + seconds
                while True:
                    time.sleep(1.0)
                    data = base64.b64decode(call("Page.captureScreenshot", format="png")["data"])
                    image = iio.imread(data)[..., :3]
                    if (ready is not None and ready(image)) or time.monotonic() > deadline:
                        break
        finally:
            os.killpg(proc.pid, signal.SIGTERM)
            proc.wait(timeout=10)
    Path(path).write_bytes(data)
    return image


def _page(port: int, timeout: float = 30.0) -> dict:
    deadline = time.monotonic() + timeout
    while True:
        try:
            pages = json.load(urllib.request.urlopen(f"http://127.0.0.1:{port}/json", timeout=2))
            return next(p for p in pages if p.get("type") == "page")
        except Exception:  # noqa: BLE001 - the browser is still starting
            if time.monotonic() > deadline:
                raise RuntimeError("headless Chromium did not start") from None
            time.sleep(0.2)
