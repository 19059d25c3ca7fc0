"""The project's own material files (`adapter`, `model`, `params`) as a library of one."""

from __future__ import annotations

from pathlib import Path

from ..data.configio import read_yaml
from ..data.schemas import load_material
from .entries import Entry


class YamlReader:
    name = "brdf-remap material (YAML)"
    suffixes = (".yaml", ".yml")

    def accepts(self, path: Path) -> bool:
        """A material file, not an experiment or a scene kept in the same folder."""
        try:
            doc = read_yaml(path)
        except Exception:  # reported by read(), which names the file
            return True
        return isinstance(doc, dict) and "adapter" in doc and "model" in doc

    def read(self, path: Path) -> list[Entry]:
        m = load_material(path)
        return [Entry(name=m.name or path.stem, file=str(path), material=m)]
