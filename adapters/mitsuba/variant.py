"""Choose Mitsuba's variant: `llvm_ad_rgb` with a libLLVM that works, else `scalar_rgb`.

Some libLLVM builds (Debian's LLVM 15 on some CPUs) abort the whole process inside drjit
("LLVM ERROR: Cannot select ... fmaximum"), so each candidate is tried in a subprocess first.
The verdict is cached per (mitsuba version, library, library mtime)."""

from __future__ import annotations

import glob
import hashlib
import importlib.metadata
import json
import os
import re
import subprocess
import sys
from dataclasses import asdict, dataclass
from pathlib import Path

_PROBE = r"""
import mitsuba as mi
mi.set_variant("llvm_ad_rgb")
T = mi.ScalarTransform4f
for bsdf in ({"type": "roughconductor", "material": "Au", "distribution": "ggx", "alpha": 0.1},
             {"type": "roughplastic", "distribution": "beckmann", "alpha": 0.1},
             {"type": "principled"}):
    s = mi.load_dict({"type": "scene", "integrator": {"type": "direct"},
        "sensor": {"type": "perspective", "to_world": T().look_at(origin=[0, 0, 6], target=[0, 0, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": 8, "height": 8}},
        "s": {"type": "sphere", "radius": 2.0, "bsdf": bsdf},
        "l": {"type": "point", "position": [3, 3, 3], "intensity": {"type": "rgb", "value": 10.0}}})
    img = mi.render(s, spp=4)
    assert float(mi.TensorXf(img).numpy().max()) > 0
print("ok")
"""


@dataclass
class VariantChoice:
    variant: str
    libllvm: str | None
    reason: str


def _version_key(path: str) -> tuple:
    nums = [int(n) for n in re.findall(r"(\d+)", os.path.basename(path))] or [0]
    return tuple(nums)


def llvm_candidates() -> list[str]:
    env = os.environ.get("DRJIT_LIBLLVM_PATH")
    found = set()
    for pattern in ("/usr/lib/*/libLLVM*.so*", "/usr/lib/llvm-*/lib/libLLVM*.so*", "/usr/local/lib/libLLVM*.so*",
                    "/opt/homebrew/opt/llvm/lib/libLLVM*.dylib", "/usr/lib/libLLVM*.so*"):
        for p in glob.glob(pattern):
            found.add(os.path.realpath(p))
    ordered = sorted(found, key=_version_key, reverse=True)
    return ([env] if env else []) + [p for p in ordered if p != env]


def _cache_file() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "brdfremap" / "mitsuba-llvm-probe.json"


def _read_cache(cache: Path) -> dict:
    """The probe's verdicts so far; a cache that is unreadable or not what this code writes is
    ignored (and rewritten by the next probe), never an error."""
    try:
        known = json.loads(cache.read_text())
    except (OSError, ValueError):
        return {}
    return known if isinstance(known, dict) else {}


def _probe(lib: str, timeout: float = 120.0) -> tuple[bool, str]:
    try:
        stamp = f"{importlib.metadata.version('mitsuba')}|{lib}|{os.stat(lib).st_mtime_ns}"
    except (OSError, importlib.metadata.PackageNotFoundError) as exc:
        return False, str(exc)
    key = hashlib.sha1(stamp.encode()).hexdigest()
    cache = _cache_file()
    known = _read_cache(cache)
    entry = known.get(key)
    if isinstance(entry, dict) and isinstance(entry.get("ok"), bool) and isinstance(entry.get("detail"), str):
        return entry["ok"], entry["detail"]
    env = {**os.environ, "DRJIT_LIBLLVM_PATH": lib}
    try:
        proc = subprocess.run([sys.executable, "-c", _PROBE], env=env, capture_output=True, text=True, timeout=timeout)
        ok = proc.returncode == 0 and proc.stdout.strip().endswith("ok")
        tail = (proc.stderr.strip().splitlines() or [f"exit code {proc.returncode}"])[-1]
        detail = "renders correctly" if ok else tail[:200]
    except subprocess.TimeoutExpired:
        ok, detail = False, f"probe timed out after {timeout:.0f} s"
    known[key] = {"ok": ok, "detail": detail, "stamp": stamp}
    try:
        cache.parent.mkdir(parents=True, exist_ok=True)
        tmp = cache.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(json.dumps(known, indent=1))
        os.replace(tmp, cache)
    except OSError:
        pass
    return ok, detail


def choose_variant() -> VariantChoice:
    """Pick the variant (and set DRJIT_LIBLLVM_PATH) before mitsuba is imported."""
    forced = os.environ.get("BRDFREMAP_MITSUBA_VARIANT")
    if forced:
        return VariantChoice(forced, os.environ.get("DRJIT_LIBLLVM_PATH"), "set by BRDFREMAP_MITSUBA_VARIANT")
    tried = []
    for lib in llvm_candidates():
        ok, detail = _probe(lib)
        if ok:
            os.environ["DRJIT_LIBLLVM_PATH"] = lib
            return VariantChoice("llvm_ad_rgb", lib, f"{os.path.basename(lib)} {detail}")
        tried.append(f"{os.path.basename(lib)}: {detail}")
    why = "; ".join(tried) if tried else "no libLLVM found"
    return VariantChoice(
        "scalar_rgb", None,
        f"no working libLLVM ({why}); scalar_rgb is about 8x slower: apt-get install libllvm19",
    )


def as_dict(choice: VariantChoice) -> dict:
    return asdict(choice)
