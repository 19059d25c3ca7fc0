"""One headless Chromium page running three.js (`web/render.js`), kept for the adapter's life: the
start-up (the browser, the page, three.js's shaders) is paid once. The page is served from
`web/` alone by a local HTTP server bound to 127.0.0.1 (ES modules do not load from file://).
A crash, a lost WebGL context or a page error is a RenderError carrying the browser's last console
lines, and the next render starts a fresh browser. Playwright's synchronous API belongs to the thread
that started it, and one per thread: each page is driven from a thread of its own, so two adapters
in one process (a remap from three.js to three.js) and adapters called from any thread all work."""

from __future__ import annotations

import base64
import collections
import concurrent.futures
import functools
import http.server
import shutil
import threading
import time
import urllib.parse
from pathlib import Path
from typing import Any

import numpy as np

from brdfremap.core.data.errors import RenderError

WEB = Path(__file__).resolve().parent / "web"
THREE = WEB / "node_modules" / "three" / "package.json"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
        "--ignore-gpu-blocklist", "--disable-background-networking", "--disable-component-update", "--disable-sync",
        "--no-first-run", "--disable-quic"]
"""Software WebGL 2 (SwiftShader), with float render targets, and no network of its own."""
START_TIMEOUT_MS = 60_000
CALL_TIMEOUT_S = 300.0
"""A page that does not answer a render in this long is given up (a hung WebGL call): RenderError,
and the next render starts another browser on another thread."""


def chromium() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser")


class _Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args) -> None:  # the page's requests are not the user's business
        pass


class Page:
    """The page, started on first use."""

    def __init__(self) -> None:
        self._server: http.server.ThreadingHTTPServer | None = None
        self._pw = self._browser = self._page = None
        self._console: collections.deque[str] = collections.deque(maxlen=20)
        self._environments: set[str] = set()
        self.startup_seconds = 0.0
        self.info: dict[str, Any] = {}
        self._thread = self._new_thread()

    def _in_thread(self, fn, *args):
        """Run ``fn`` on the page's own thread (playwright's objects live there), at most
        `CALL_TIMEOUT_S`: past it the page and its thread are abandoned (a hung call cannot be
        interrupted), and a fresh thread drives the next browser."""
        future = self._thread.submit(fn, *args)
        try:
            return future.result(timeout=CALL_TIMEOUT_S)
        except concurrent.futures.TimeoutError:
            stuck, self._thread = self._thread, self._new_thread()
            stuck.shutdown(wait=False)
            self._pw = self._browser = self._page = None
            self._environments.clear()
            raise RenderError(f"threejs: the page did not answer in {CALL_TIMEOUT_S:.0f} s{self._said()}") from None

    @staticmethod
    def _new_thread() -> concurrent.futures.ThreadPoolExecutor:
        return concurrent.futures.ThreadPoolExecutor(max_workers=1, thread_name_prefix="threejs-page")

    def _start(self) -> None:
        from playwright.sync_api import sync_playwright

        t0 = time.perf_counter()
        exe = chromium()
        if exe is None:
            raise RenderError("threejs: Chromium is not installed (apt-get install chromium)")
        if self._server is None:
            handler = functools.partial(_Quiet, directory=str(WEB))
            self._server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
            threading.Thread(target=self._server.serve_forever, daemon=True).start()
        try:
            self._pw = sync_playwright().start()
            self._browser = self._pw.chromium.launch(executable_path=exe, args=ARGS)
            page = self._browser.new_page()
            page.route("**/*", functools.partial(_only_from, f"127.0.0.1:{self._server.server_port}"))
            page.on("console", lambda m: self._console.append(f"{m.type}: {m.text}"))
            page.on("pageerror", lambda e: self._console.append(f"page error: {e}"))
            page.goto(f"http://127.0.0.1:{self._server.server_port}/index.html", timeout=START_TIMEOUT_MS)
            page.wait_for_function("window.brdfReady === true", timeout=START_TIMEOUT_MS)
            self.info = page.evaluate("window.brdf.info()")
        except Exception as exc:  # the browser would not launch, the page did not load or start
            said = self._said()
            self._close_here()
            raise RenderError(f"threejs: the page did not start ({_first(exc)}){said}") from None
        self._page = page
        self.startup_seconds = time.perf_counter() - t0
        if not self.info.get("floatTargets"):
            self._close_here()
            raise RenderError("threejs: this Chromium's WebGL 2 has no float render targets (EXT_color_buffer_float): "
                              "linear HDR pixels cannot be read back")

    def _said(self) -> str:
        return ("; the browser said: " + " | ".join(self._console)) if self._console else ""

    def _call(self, script: str, arg: Any) -> Any:
        return self._in_thread(self._call_here, script, arg)

    def _call_here(self, script: str, arg: Any) -> Any:
        if self._page is None:
            self._start()
        try:
            return self._page.evaluate(script, arg)  # type: ignore[union-attr]
        except Exception as exc:  # a crash, a lost context, an error thrown in the page
            said = self._said()
            self._close_here()
            raise RenderError(f"threejs: the render failed ({_first(exc)}){said}") from None

    def environment(self, key: str, rows_bottom_first: np.ndarray) -> None:
        """Hand the page an equirectangular map (H x W x 3, three.js's orientation) once."""
        if key in self._environments and self._page is not None:
            return
        h, w = rows_bottom_first.shape[:2]
        rgba = np.concatenate([rows_bottom_first, np.ones((h, w, 1), np.float32)], axis=-1).astype(np.float32)
        self._call("a => window.brdf.setEnvironment(a[0], a[1], a[2], a[3])",
                   [key, w, h, base64.b64encode(rgba.tobytes()).decode()])
        self._environments.add(key)

    def render(self, request: dict[str, Any], views: int) -> np.ndarray:
        out = self._call("req => window.brdf.render(req)", request)
        r = request["resolution"]
        return np.frombuffer(base64.b64decode(out["pixels"]), np.float32).reshape(views * r, r, 3).copy()

    def close(self) -> None:
        try:
            self._in_thread(self._close_here)
        except RuntimeError:  # at interpreter exit the page's thread is already gone, and the browser with us
            pass

    def _close_here(self) -> None:
        for thing, how in ((self._browser, "close"), (self._pw, "stop")):
            try:
                if thing is not None:
                    getattr(thing, how)()
            except Exception:  # already gone: nothing to release
                pass
        self._pw = self._browser = self._page = None
        self._environments.clear()

    def shutdown(self) -> None:
        """Close the browser, the page's thread and the server; again, nothing."""
        self.close()
        self._thread.shutdown(wait=True)
        self._thread = self._new_thread()
        if self._server is not None:
            self._server.shutdown()
            self._server.server_close()
            self._server = None


def _only_from(host: str, route) -> None:
    """The page loads from its own server and nowhere else: a URI in a glTF (an image's, a buffer's)
    is never fetched from a network."""
    if urllib.parse.urlparse(route.request.url).netloc == host:
        route.continue_()
    else:
        route.abort()


def _first(exc: BaseException) -> str:
    return (str(exc).strip().splitlines() or [type(exc).__name__])[0]
