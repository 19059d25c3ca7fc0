"""What a library conversion records: each material's state (`ItemStatus`: where its job stands,
or its verdict once judged) and `convert.json` as a model (`ConvertSummary`, `remap schema convert`)."""

from __future__ import annotations

from enum import StrEnum

from pydantic import Field

from ..data.model import Strict

CONVERT_SCHEMA_VERSION = 1


class ItemStatus(StrEnum):
    """A material's state in a conversion: not converted (failed, unsupported), not yet done
    (pending), or its result's verdict. Written as its value."""

    FAILED = "failed"
    UNSUPPORTED = "unsupported"
    UNRELIABLE = "unreliable"
    UNCHECKED = "unchecked"
    MISMATCH = "mismatch"
    OK = "ok"
    PENDING = "pending"

    @property
    def converted(self) -> bool:
        """Whether it has a result (whatever its verdict)."""
        return self not in (ItemStatus.FAILED, ItemStatus.UNSUPPORTED, ItemStatus.PENDING)


class TriedModel(Strict):
    """One model fitted for a material where its first came back a mismatch or unreliable."""

    model: str
    slot: str = Field(description="Its result's folder under materials/.")
    status: ItemStatus
    relative_rmse: float | None
    kept: bool


class MaterialRow(Strict):
    name: str = Field(description="The material's name in its file.")
    file: str
    status: ItemStatus
    reason: str = Field(description="Why it failed or is unsupported ('' otherwise).")
    verdict: str = Field("", description="What its verdict tells beside its status: why it is unreliable, a "
                                         "mismatch or unchecked, and that the target is uniform where the source "
                                         "is textured ('' for a plain ok).")
    slot: str | None = Field(description="Its folder under materials/ (None: no result).")
    model: str | None = Field(description="The target model.")
    model_why: str = Field(description="Why that model, where the adapter chose it.")
    relative_rmse: float | None
    perceptual: float | None
    renders: int | None
    seconds: float | None
    resumed: bool = Field(description="Its result was found from an earlier run.")
    notes: list[str]
    textured: list[str]
    tried: list[TriedModel] = Field(default_factory=list, description="Every model fitted for it where the first "
                                                                      "chosen came back a mismatch or unreliable.")


class ConvertSummary(Strict):
    """`convert.json`: every material of a conversion, and what came of it."""

    schema_version: int = CONVERT_SCHEMA_VERSION
    target: str = Field(description="The target adapter.")
    model: str | None = Field(description="The target model asked for (None: the adapter chose per material).")
    materials: list[MaterialRow]
    converted: int = Field(description="Materials with a result, whatever its verdict.")
    failed: int = Field(description="Materials failed or unsupported.")
    libraries: list[str] = Field(description="The native library files written.")
    library_notes: list[str]
    seconds: float
    ran_in: str = Field(description="Where the jobs ran (this machine's processes, a Dask scheduler).")
