"""Helpers shared by the tests."""

from __future__ import annotations

import types

from brdfremap.core import hookimpl
from brdfremap.core.host.plugins import collect_adapters, get_plugin_manager


def registry_of(name: str, factory) -> object:
    """A fresh registry holding one adapter, registered through the plugin host as a plugin would."""
    mod = types.ModuleType(f"{name}plug")

    @hookimpl
    def brdfremap_register_adapters(register):
        register(name, factory)

    mod.brdfremap_register_adapters = brdfremap_register_adapters
    return collect_adapters(get_plugin_manager(load_entrypoints=False, plugins=(mod,)))


ROOT = __import__("pathlib").Path(__file__).resolve().parents[1]
MATERIALS = ROOT / "configs" / "materials"


def remap(*args, cwd=None, env=None, timeout=300, **popen):
    """`remap ARGS` in a process of its own, as a user runs it: a CompletedProcess (text)."""
    import os
    import subprocess
    import sys

    cmd = [sys.executable, "-m", "brdfremap.core.cli", *map(str, args)]
    return subprocess.run(cmd, capture_output=True, text=True, cwd=cwd, timeout=timeout,
                          env={**os.environ, **(env or {})}, **popen)


def one_line_error(proc, *words) -> str:
    """The process failed with exit 2 and one line on stderr that names all ``words``."""
    lines = [line for line in proc.stderr.strip().splitlines() if line.strip()]
    assert proc.returncode == 2, (proc.returncode, proc.stderr[-2000:])
    assert len(lines) == 1 and lines[0].startswith("remap: error: "), proc.stderr[-2000:]
    assert "Traceback" not in proc.stderr
    for w in words:
        assert w in lines[0], (w, lines[0])
    return lines[0]


class SmallFilesystem:
    """A tmpfs of ``size`` mounted at ``path`` (root only: the test that needs one runs as root in
    CI), or None when this machine cannot mount one."""

    def __init__(self, path, size="4m", options=""):
        self.path, self.size, self.options = path, size, options

    def __enter__(self):
        import subprocess

        self.path.mkdir(parents=True, exist_ok=True)
        opts = f"size={self.size}" + (f",{self.options}" if self.options else "")
        ok = subprocess.run(["mount", "-t", "tmpfs", "-o", opts, "tmpfs", str(self.path)],
                            capture_output=True).returncode == 0
        self.mounted = ok
        return self.path if ok else None

    def __exit__(self, *exc):
        import subprocess

        if self.mounted:
            subprocess.run(["umount", "-l", str(self.path)], capture_output=True)


def fill(folder, leave: int) -> None:
    """Fill a filesystem until only ``leave`` bytes are free."""
    import os

    st = os.statvfs(folder)
    free = st.f_bavail * st.f_frsize
    with open(os.path.join(folder, "filler"), "wb") as f:
        f.write(b"\0" * max(free - leave, 0))


CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]


def open_in_chromium(page_path, screenshot=None, click=None) -> dict:
    """Load a page in Debian's headless Chromium (driven by playwright): its console errors, its
    images and the broken ones, and a screenshot when asked. Skips (fails in CI) without Chromium."""
    import os
    import shutil

    import pytest

    exe = shutil.which("chromium") or "/usr/bin/chromium"
    if not os.path.exists(exe):
        if os.environ.get("CI"):
            pytest.fail("Chromium must be installed in CI (make system-deps installs Debian's chromium)")
        pytest.skip("Chromium is not installed (apt-get install chromium)")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=exe, args=CHROMIUM_ARGS)
        try:
            page = browser.new_page(viewport={"width": 1200, "height": 1500})
            errors: list[str] = []
            page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.on("requestfailed", lambda r: errors.append(f"request failed: {r.url}"))
            page.goto(f"file://{os.path.abspath(page_path)}")
            page.wait_for_load_state("load")
            images = page.evaluate("document.images.length")
            broken = page.evaluate("Array.from(document.images).filter(i => !i.complete || i.naturalWidth === 0)"
                                   ".map(i => i.getAttribute('src'))")
            if click:
                page.click(click)
            rows = page.evaluate("Array.from(document.querySelectorAll('#summary tbody tr')).map(r => r.dataset.name)")
            if screenshot:
                page.screenshot(path=str(screenshot))
        finally:
            browser.close()
    return {"errors": errors, "images": images, "broken": broken, "rows": rows}


def checker(seed=1, rows=6, cols=12, texel=8):
    """A texture of rows x cols cells of random colours, each texel x texel texels (float32, H x W x 3):
    a mistaken texture layout (flipped, mirrored, turned) is far off."""
    import numpy as np

    cells = np.random.default_rng(seed).uniform(0.05, 0.9, (rows, cols, 3)).astype(np.float32)
    return np.repeat(np.repeat(cells, texel, axis=0), texel, axis=1)
