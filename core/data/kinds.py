"""The kinds of value a material parameter takes, and how a range is spaced: shared by the
models (`schemas`), the textures that drive parameters, and the tables."""

from __future__ import annotations

from enum import StrEnum


class ParamKind(StrEnum):
    """What a parameter's value is: a number, three numbers, or one of its choices."""

    SCALAR = "scalar"
    RGB = "rgb"
    CHOICE = "choice"


class Lobe(StrEnum):
    """A model's two lobes, each fitted alone where the lobes divide the parameters."""

    DIFFUSE = "diffuse"
    SPECULAR = "specular"


class Scale(StrEnum):
    """How a range is spaced: evenly, or evenly in the logarithm."""

    LINEAR = "linear"
    LOG = "log"
