"""A minimal Chrome DevTools Protocol client for the browser tests: device emulation (a true
390 px viewport with ``mobile`` on, which ``--window-size`` cannot give: headless windows are
at least 500 px wide), evaluating a measurement script, full-page screenshots.

Chromium from the system packages; the ``websockets`` client already in the environment.
"""

from __future__ import annotations

import base64
import json
import re
import subprocess
import tempfile
import time
import urllib.request
from pathlib import Path
from typing import Any


class Page:
    """One headless Chromium with one page, driven over the DevTools protocol."""

    def __init__(self, browser: str):
        from websockets.sync.client import connect

        self._profile = tempfile.TemporaryDirectory()
        self._proc = subprocess.Popen(
            [browser, "--headless=new", "--no-sandbox", "--disable-gpu", "--hide-scrollbars", "--remote-debugging-port=0",
             f"--user-data-dir={self._profile.name}", "--no-first-run", "about:blank"],
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        port = None
        deadline = time.time() + 60
        while port is None and time.time() < deadline:
            line = self._proc.stderr.readline()
            found = re.search(r"DevTools listening on ws://[^:]+:(\d+)/", line or "")
            port = int(found.group(1)) if found else None
            if not line and self._proc.poll() is not None:
                break
        if port is None:
            self.close()
            raise RuntimeError("chromium did not start a DevTools endpoint")
        targets = json.loads(urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=10).read())
        url = next(t["webSocketDebuggerUrl"] for t in targets if t.get("type") == "page")
        self._connection = connect(url, max_size=None, open_timeout=30)
        self._ws = self._connection.__enter__()
        self._id = 0
        self.send("Page.enable")

    def send(self, method: str, **params: Any) -> dict:
        """Call ``method`` and return its result (events that arrive meanwhile are dropped)."""
        self._id += 1
        self._ws.send(json.dumps({"id": self._id, "method": method, "params": params}))
        while True:
            message = json.loads(self._ws.recv(timeout=120))
            if message.get("id") == self._id:
                if "error" in message:
                    raise RuntimeError(f"{method}: {message['error']}")
                return message.get("result", {})

    def wait_event(self, name: str, timeout: float = 60) -> None:
        deadline = time.time() + timeout
        while time.time() < deadline:
            message = json.loads(self._ws.recv(timeout=max(deadline - time.time(), 0.1)))
            if message.get("method") == name:
                return

    def open(self, url: str, width: int, height: int = 844) -> None:
        """Emulate a ``width`` x ``height`` viewport (mobile below 600 px) and load ``url``."""
        self.emulate(width, height)
        self._id += 1
        self._ws.send(json.dumps({"id": self._id, "method": "Page.navigate", "params": {"url": url}}))
        self.wait_event("Page.loadEventFired")

    def emulate(self, width: int, height: int) -> None:
        self.send("Emulation.setDeviceMetricsOverride", width=width, height=height, deviceScaleFactor=1,
                  mobile=width < 600)

    def evaluate(self, expression: str) -> Any:
        result = self.send("Runtime.evaluate", expression=expression, returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in result:
            raise RuntimeError(str(result["exceptionDetails"])[:2000])
        return result["result"].get("value")

    def screenshot(self, path: Path, width: int, height: int) -> Path:
        """A full-page PNG: the viewport stretched to the page's height (capped), then captured."""
        self.emulate(width, min(height, 16000))
        data = self.send("Page.captureScreenshot", format="png", captureBeyondViewport=True)["data"]
        path.write_bytes(base64.b64decode(data))
        return path

    def close(self) -> None:
        try:
            self._ws.close()
        except Exception:
            pass
        self._proc.terminate()
        try:
            self._proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self._proc.kill()
        self._profile.cleanup()
