"""Builds the Blender extension's installable zip with Blender's own extension tool (the one
`blender --command extension build` runs, shipped in the `bpy` wheel), then validates it with the
same tool: `dist/brdf_remap-VERSION.zip`.

    python extension/build.py [--out DIR]
"""

from __future__ import annotations

import argparse
import importlib.util
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
SOURCE = HERE / "brdf_remap"


def blender_ext() -> Path:
    """Blender's extension command-line tool, from the installed bpy (without importing it)."""
    spec = importlib.util.find_spec("bpy")
    if spec is None or not spec.submodule_search_locations:
        raise SystemExit("build: needs Blender's bpy module (pip install 'bpy==5.0.*', as `make test` does)")
    found = sorted(Path(next(iter(spec.submodule_search_locations))).glob(
        "*/scripts/addons_core/bl_pkg/cli/blender_ext.py"))
    if not found:
        raise SystemExit("build: this bpy has no extension tool (scripts/addons_core/bl_pkg/cli/blender_ext.py)")
    return found[-1]


DOCUMENTED = {
    "": {"schema_version", "id", "version", "name", "tagline", "maintainer", "type", "website", "tags",
         "blender_version_min", "blender_version_max", "license", "copyright", "platforms", "wheels", "permissions",
         "build"},
    "permissions": {"files", "network", "clipboard", "camera", "microphone"},
    "build": {"paths", "paths_exclude_pattern"},
}
"""The manifest's keys Blender's manual documents (schema 1.0.0). Blender's own tool checks their
values and lets an unknown key pass (a newer schema's); here an unknown key is a typo."""


def documented(manifest: Path) -> None:
    """Refuses a manifest key Blender's manual does not document, naming it."""
    import tomllib

    data = tomllib.loads(manifest.read_text(encoding="utf-8"))
    for table, keys in DOCUMENTED.items():
        given = data if not table else data.get(table, {})
        unknown = sorted(set(given) - keys)
        if unknown:
            where = f"[{table}] " if table else ""
            raise SystemExit(f"build: {manifest}: {where}key {unknown[0]!r} is not a documented manifest key "
                             f"(known: {', '.join(sorted(keys))})")


def build(out: Path, source: Path = SOURCE) -> Path:
    documented(source / "blender_manifest.toml")
    out.mkdir(parents=True, exist_ok=True)
    tool = blender_ext()
    before = set(out.glob("brdf_remap-*.zip"))
    run = subprocess.run([sys.executable, str(tool), "build", "--source-dir", str(source), "--output-dir", str(out)],
                         capture_output=True, text=True)
    made = sorted(set(out.glob("brdf_remap-*.zip")) - before) or sorted(out.glob("brdf_remap-*.zip"))
    if run.returncode != 0 or not made:
        raise SystemExit(f"build: Blender's extension tool refused it: {(run.stdout + run.stderr).strip()[-800:]}")
    zip_path = max(made, key=lambda p: p.stat().st_mtime)
    check = subprocess.run([sys.executable, str(tool), "validate", str(zip_path)], capture_output=True, text=True)
    if check.returncode != 0:
        raise SystemExit(f"build: {zip_path} does not validate: {(check.stdout + check.stderr).strip()[-800:]}")
    return zip_path


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=HERE.parent / "dist", help="folder of the zip (default: dist/)")
    print(build(ap.parse_args().out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
