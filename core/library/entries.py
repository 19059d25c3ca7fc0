"""What library readers and writers exchange: the materials a file holds (`Entry`), how a reader
is called (`Reader`), and a converted material as a writer receives it (`Converted`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

from pydantic import Field

from ..data.model import Strict
from ..data.schemas import Material
from ..data.textures import Texture


class Entry(Strict):
    """One material found in a file: convertible (``material``), or not (``problem`` says why)."""

    name: str = Field(description="The material's name in its file.")
    file: str = Field(description="The file it was read from.")
    material: Material | None = Field(None, description="The source material; None when it cannot be converted.")
    problem: str = Field("", description="Why it cannot be converted (an unsupported type).")
    unreadable: bool = Field(False, description="The file itself could not be read (``problem`` says where and "
                                                "why): a failure, where an unsupported type is not.")
    notes: list[str] = Field(default_factory=list, description="What the reading changed or left out: inputs with "
                                                               "no counterpart, a correspondence used.")
    textured: list[str] = Field(default_factory=list, description="Inputs driven by a texture or a node graph, "
                                                                  "e.g. \"base_color <- image 'brass.png'\": "
                                                                  "converted with their constant value.")


class Reader(Protocol):
    name: str
    suffixes: tuple[str, ...]
    """File endings it reads (".xml"); a reader may decline a file of its ending (`accepts`)."""

    def accepts(self, path: Path) -> bool:
        """Whether this file is one of its kind (cheap: a look at its first bytes)."""

    def read(self, path: Path) -> list[Entry]:
        """Every material of the file, convertible or not. A file it cannot read at all is a
        ConfigError naming the file."""


@dataclass(frozen=True)
class Converted:
    """A material converted, as a writer receives it: the source's name and the fitted target."""

    name: str
    model: str
    params: dict[str, Any]
    folder: Path
    """The job's result folder (its own native files are there)."""
    textures: dict[str, Texture] = field(default_factory=dict)
    """Parameters read from maps: each `file` relative to the library's folder (`textures/...`)."""
    files: tuple[str, ...] = ()
    """The names of the files the job wrote beside its result (its report's `files`)."""
