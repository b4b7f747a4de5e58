"""A headless Chromium driven over the DevTools protocol on a pipe (no extra packages): open a
page at a window size, evaluate JavaScript in it and take screenshots."""

from __future__ import annotations

import base64
import fcntl
import itertools
import json
import os
import shutil
import signal
import subprocess
import tempfile
import time
from pathlib import Path

#: Debian's package installs it as ``chromium``.
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")

# Headless, and nothing that reaches for the network or a desktop session.
_FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
    "--remote-debugging-pipe",
)


def _above_nine(fd: int) -> int:
    """``fd`` moved to the lowest free descriptor above 9."""
    moved = fcntl.fcntl(fd, fcntl.F_DUPFD, 10)
    os.close(fd)
    return moved


def _end_group(group: int, timeout: float = 20.0) -> None:
    """Kill every process of process group ``group`` and wait until none is left running (a
    zombie has stopped writing; its reaping is its new parent's business)."""
    deadline = time.monotonic() + timeout
    while _running_in_group(group):
        try:
            os.killpg(group, signal.SIGKILL)
        except ProcessLookupError:
            return
        if time.monotonic() > deadline:
            raise TimeoutError(f"Chromium's process group {group} did not end")
        time.sleep(0.01)


def _running_in_group(group: int) -> bool:
    """Whether a process of process group ``group`` is running (not a zombie)."""
    return any(state != "Z" and in_group == group for state, _, in_group in processes().values())


def processes() -> dict[int, tuple[str, int, int]]:
    """Every process's state letter, parent and process group, by its id (from /proc)."""
    found = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
        except OSError:  # ended while listed
            continue
        # After the command's name: state, parent, process group.
        found[int(entry.name)] = (fields[0], int(fields[1]), int(fields[2]))
    return found


class Browser:
    """One Chromium process and one page; a context manager."""

    def __init__(self, width: int, height: int):
        self.width, self.height = width, height
        self._ids = itertools.count(1)
        self._buffer = b""

    def __enter__(self) -> Browser:
        self._profile = tempfile.TemporaryDirectory()
        # Chromium reads commands from fd 3 and writes replies to fd 4: the child moves the
        # pipe ends there before it starts Chromium.
        to_child, self._to_browser = os.pipe()
        self._from_browser, from_child = os.pipe()
        # Above 9, so that moving one end to 3 or 4 cannot overwrite the other.
        to_child, from_child = (_above_nine(fd) for fd in (to_child, from_child))

        def move_pipes() -> None:  # in the child, before Chromium starts
            os.dup2(to_child, 3)
            os.dup2(from_child, 4)

        self._process = subprocess.Popen(
            [CHROMIUM, *_FLAGS, f"--user-data-dir={self._profile.name}", "about:blank"],
            pass_fds=(3, 4),
            preexec_fn=move_pipes,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            # Its own process group, so that closing ends its helpers too (below).
            start_new_session=True,
        )
        os.close(to_child)
        os.close(from_child)
        target = self._send("Target.createTarget", url="about:blank")["targetId"]
        self._session = self._send("Target.attachToTarget", targetId=target, flatten=True)[
            "sessionId"
        ]
        self.send(
            "Emulation.setDeviceMetricsOverride",
            width=self.width,
            height=self.height,
            deviceScaleFactor=1,
            mobile=False,
        )
        return self

    def __exit__(self, *exc) -> None:
        os.close(self._to_browser)
        os.close(self._from_browser)
        self._process.terminate()
        self._process.wait(timeout=20)
        # Chromium's helpers (zygote, renderer, GPU) can outlive its main process for a moment
        # and still write into the profile while it is removed ("Directory not empty").
        _end_group(self._process.pid)
        self._profile.cleanup()

    @property
    def pid(self) -> int:
        """Chromium's main process."""
        return self._process.pid

    @property
    def profile(self) -> str:
        """The profile folder Chromium was started with."""
        return self._profile.name

    def _send(self, method: str, session: str | None = None, **params) -> dict:
        message_id = next(self._ids)
        message = {"id": message_id, "method": method, "params": params}
        if session:
            message["sessionId"] = session
        os.write(self._to_browser, json.dumps(message).encode() + b"\0")
        while True:
            while b"\0" not in self._buffer:
                chunk = os.read(self._from_browser, 1 << 20)
                if not chunk:
                    raise RuntimeError("chromium closed its DevTools pipe")
                self._buffer += chunk
            raw, self._buffer = self._buffer.split(b"\0", 1)
            reply = json.loads(raw)
            if reply.get("id") == message_id:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply.get("result", {})

    def send(self, method: str, **params) -> dict:
        """A DevTools command to the page; its result."""
        return self._send(method, self._session, **params)

    def evaluate(self, expression: str):
        """The value of a JavaScript expression in the page (promises awaited)."""
        result = self.send(
            "Runtime.evaluate", expression=expression, awaitPromise=True, returnByValue=True
        )
        if "exceptionDetails" in result:
            raise RuntimeError(f"{expression[:80]}: {result['exceptionDetails']}")
        return result["result"].get("value")

    def open(self, url: str, ready: str, timeout: float = 60.0) -> None:
        """Navigate to ``url`` and wait until the JavaScript condition ``ready`` holds."""
        self.send("Page.navigate", url=url)
        deadline = time.monotonic() + timeout
        while not self.evaluate(f"Boolean({ready})"):
            if time.monotonic() > deadline:
                raise TimeoutError(f"{url}: {ready} never held")
            time.sleep(0.2)

    def screenshot(self, path: Path) -> Path:
        """The visible window as a PNG at ``path``."""
        data = self.send("Page.captureScreenshot", format="png")["data"]
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(base64.b64decode(data))
        return path
