"""The base of the project's data models: strict (an unknown field is an error) and frozen."""

from __future__ import annotations

from typing import Any, ClassVar

from pydantic import BaseModel, ConfigDict, model_validator

UNION_TAGS: set[str] = set()
"""The tags of discriminated unions (a light's `type`): pydantic puts the tag in an error's
location (`lights.0.environment.map`), which error messages leave out (`lights.0.map`)."""


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class WithDerived(Strict):
    """A model that writes some values derived from its fields (computed fields) and, reading a
    document back, drops them: they are recomputed, not trusted."""

    derived_fields: ClassVar[tuple[str, ...]] = ()

    @model_validator(mode="before")
    @classmethod
    def _drop_derived(cls, data: Any) -> Any:
        if isinstance(data, dict):
            return {k: v for k, v in data.items() if k not in cls.derived_fields}
        return data
