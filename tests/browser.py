"""A real headless Chromium driven over the DevTools protocol (websocket), for page tests.

:func:`chromium` starts Debian's ``chromium`` with a throw-away profile and a DevTools
port; :meth:`Browser.load` opens a page, waits for its ``load`` event and returns the
console errors, uncaught exceptions and failed loads seen on the way. Without Chromium
the test is skipped with the reason, except in CI (``CI=true``) where it fails.
"""

import base64
import itertools
import json
import os
import shutil
import subprocess
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest
from websockets.sync.client import ClientConnection, connect

from tests.conftest import REPO_ROOT
from tests.servers import local_get

#: Screenshots land here (git-ignored), one PNG per page test.
ARTIFACTS = REPO_ROOT / "artifacts"
FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
    "--remote-debugging-port=0",
)
WIDTH = 1400


def chromium_binary() -> str:
    """Chromium's path; skips the test without it (fails it in CI)."""
    binary = shutil.which("chromium") or shutil.which("chromium-browser")
    if binary is None:
        reason = "Chromium is not installed (apt-get install -y chromium)"
        if os.environ.get("CI") == "true":
            pytest.fail(reason)
        pytest.skip(reason)
    return binary


@dataclass
class PageLoad:
    """What a page load left: problems reported by the browser, and the page."""

    errors: list[str] = field(default_factory=list)


class Browser:
    """One page target of a running Chromium, spoken to over its websocket."""

    def __init__(self, socket: ClientConnection) -> None:
        self.socket = socket
        self.ids = itertools.count(1)
        self.events: list[dict[str, Any]] = []

    def call(self, method: str, timeout: float = 30, **params: Any) -> dict[str, Any]:
        """Send one command and wait for its answer (events meanwhile are kept)."""
        message_id = next(self.ids)
        self.socket.send(json.dumps({"id": message_id, "method": method, "params": params}))
        deadline = time.monotonic() + timeout
        while True:
            message = json.loads(self.socket.recv(timeout=max(deadline - time.monotonic(), 0)))
            if message.get("id") == message_id:
                if "error" in message:
                    raise AssertionError(f"{method}: {message['error']}")
                result: dict[str, Any] = message["result"]
                return result
            self.events.append(message)

    def _wait_for(self, method: str, timeout: float = 30) -> None:
        deadline = time.monotonic() + timeout
        while not any(e.get("method") == method for e in self.events):
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise AssertionError(f"no {method} within {timeout} s")
            self.events.append(json.loads(self.socket.recv(timeout=remaining)))

    def load(self, url: str) -> PageLoad:
        """Open ``url`` and wait for its load event; collect the problems on the way."""
        self.events.clear()
        for domain in ("Page", "Runtime", "Log", "Network"):
            self.call(f"{domain}.enable")
        self.call("Page.navigate", url=url)
        self._wait_for("Page.loadEventFired")
        self.call("Runtime.evaluate", expression="1")  # drain what the load queued
        load = PageLoad()
        for event in self.events:
            method, params = event.get("method"), event.get("params", {})
            if method == "Runtime.consoleAPICalled" and params["type"] in ("error", "assert"):
                load.errors.append(f"console: {params['args']}")
            elif method == "Runtime.exceptionThrown":
                load.errors.append(f"exception: {params['exceptionDetails']}")
            elif method == "Log.entryAdded" and params["entry"]["level"] == "error":
                load.errors.append(f"log: {params['entry']['text']}")
            elif method == "Network.loadingFailed":
                load.errors.append(f"network: {params.get('errorText')}")
        return load

    def evaluate(self, expression: str) -> Any:
        """The value of a JavaScript expression in the page."""
        answer = self.call("Runtime.evaluate", expression=expression, returnByValue=True)
        if "exceptionDetails" in answer:
            raise AssertionError(f"{expression}: {answer['exceptionDetails']}")
        return answer["result"].get("value")

    def follow(self, expression: str) -> None:
        """Evaluate ``expression``, which navigates (a form submitted, a link clicked),
        and wait for the new page's load event."""
        self.events.clear()
        self.evaluate(expression)
        self._wait_for("Page.loadEventFired")

    def wait_for(self, expression: str, timeout: float = 60) -> Any:
        """The value of ``expression`` once it is truthy (checked every 0.1 s); a safety
        net of ``timeout`` seconds, not a speed requirement."""
        deadline = time.monotonic() + timeout
        while not (value := self.evaluate(expression)):
            if time.monotonic() > deadline:
                raise AssertionError(f"{expression} still false after {timeout} s")
            time.sleep(0.1)
        return value

    def evaluate_async(self, expression: str) -> Any:
        """The value of a JavaScript expression that gives a promise, once it settles."""
        answer = self.call(
            "Runtime.evaluate", expression=expression, returnByValue=True, awaitPromise=True
        )
        if "exceptionDetails" in answer:
            raise AssertionError(f"{expression}: {answer['exceptionDetails']}")
        return answer["result"].get("value")

    def requested(self) -> list[str]:
        """The URLs the page asked for since it was loaded."""
        return [
            e["params"]["request"]["url"]
            for e in self.events
            if e.get("method") == "Network.requestWillBeSent"
        ]

    def screenshot(self, name: str, width: int = WIDTH) -> Path:
        """A full-page PNG of the current page under ``artifacts/``, ``width`` px wide."""
        height = int(self.evaluate("document.documentElement.scrollHeight"))
        self.call(
            "Emulation.setDeviceMetricsOverride",
            width=width,
            height=min(height, 8000),
            deviceScaleFactor=1,
            mobile=False,
        )
        shot = self.call("Page.captureScreenshot", format="png", captureBeyondViewport=True)
        ARTIFACTS.mkdir(exist_ok=True)
        path = ARTIFACTS / f"{name}.png"
        path.write_bytes(base64.b64decode(shot["data"]))
        return path


def _devtools_port(profile: Path, process: subprocess.Popen[bytes]) -> int:
    marker = profile / "DevToolsActivePort"
    deadline = time.monotonic() + 30
    while not marker.is_file() or not marker.read_text().strip():
        if process.poll() is not None:
            raise AssertionError(f"chromium exited {process.returncode} at start-up")
        if time.monotonic() > deadline:
            raise AssertionError("chromium opened no DevTools port within 30 s")
        time.sleep(0.05)
    return int(marker.read_text().splitlines()[0])


#: Every host name but the test server's fails to resolve: a plant without internet.
OFFLINE = ("--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1",)


@contextmanager
def chromium_process(profile: Path, flags: tuple[str, ...] = ()) -> Iterator[int]:
    """A headless Chromium with its profile in ``profile``, on a blank page; ``flags`` are
    added to its command line (:data:`OFFLINE`). Yields its DevTools port."""
    binary = chromium_binary()
    process = subprocess.Popen(
        [
            binary,
            *FLAGS,
            *flags,
            f"--user-data-dir={profile}",
            f"--window-size={WIDTH},1000",
            "about:blank",
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        yield _devtools_port(profile, process)
    finally:
        process.terminate()
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


@contextmanager
def chromium(profile: Path, flags: tuple[str, ...] = ()) -> Iterator[Browser]:
    """A Chromium of its own (:func:`chromium_process`), its first page."""
    with chromium_process(profile, flags) as port:
        targets = local_get(f"http://127.0.0.1:{port}/json/list", timeout=10).json()
        page = next(t for t in targets if t["type"] == "page")
        with connect(page["webSocketDebuggerUrl"], max_size=None) as socket:
            yield Browser(socket)


@contextmanager
def fresh_page(port: int) -> Iterator[Browser]:
    """A new page of the Chromium at ``port``, in a browser context of its own (its own
    cookies, storage and cache, like a fresh profile), closed with its context after."""
    version = local_get(f"http://127.0.0.1:{port}/json/version", timeout=10).json()
    with connect(version["webSocketDebuggerUrl"], max_size=None) as socket:
        control = Browser(socket)
        context = control.call("Target.createBrowserContext")["browserContextId"]
        try:
            target = control.call(
                "Target.createTarget",
                url="about:blank",
                browserContextId=context,
                width=WIDTH,
                height=1000,
            )["targetId"]
            page = f"ws://127.0.0.1:{port}/devtools/page/{target}"
            with connect(page, max_size=None) as page_socket:
                yield Browser(page_socket)
        finally:
            control.call("Target.disposeBrowserContext", browserContextId=context)


@pytest.fixture(scope="session")
def chromium_port(tmp_path_factory: pytest.TempPathFactory) -> Iterator[int]:
    """One Chromium for the session (each test gets a fresh page: :func:`browser`)."""
    with chromium_process(tmp_path_factory.mktemp("chromium")) as port:
        yield port


@pytest.fixture
def browser(chromium_port: int) -> Iterator[Browser]:
    """A fresh page, in a browser context of its own, of the session's Chromium."""
    with fresh_page(chromium_port) as browser:
        yield browser
