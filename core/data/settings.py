"""What a user chooses about how a remap runs. One model: the CLI flags, an experiment's
`options:` and the benchmark scripts all build it, and its defaults exist only here."""

from __future__ import annotations

from enum import StrEnum
from typing import Literal

from pydantic import Field, field_validator

from .model import Strict


class Scheme(StrEnum):
    AUTO = "auto"
    ONE = "one"
    TWO = "two"
    THREE = "three"


class Start(StrEnum):
    INFORMED = "informed"
    DEFAULTS = "defaults"


class FitScene(StrEnum):
    AUTO = "auto"
    ONE_VIEW = "one-view"
    SAMPLES = "samples"
    AS_GIVEN = "as-given"


class Inputs(StrEnum):
    NEEDED = "needed"
    GIVEN = "given"


class Validation(StrEnum):
    HELD_OUT = "held-out"
    NONE = "none"


class Settings(Strict):
    """The choices that shape a fit. Every field is part of a job's key."""

    scheme: Scheme = Field(Scheme.AUTO, description="auto: two-stage where the target's lobes divide its parameters, "
                                                "else one-stage; one, two, three: the paper's schemes.")
    starts: int = Field(4, ge=1, le=64, description="Starting points tried per stage; the best one starts the fit.")
    coarse: int = Field(32, ge=0, le=4096, description="Resolution of the coarse level where most iterations run "
                                                       "(used when the scene's is at least twice it; 0: none).")
    start: Start = Field(
        Start.INFORMED, description="First start: the exporters' conversion of the source (where both adapters read "
                                "one), or the target model's defaults.")
    precise_spp: int = Field(4, ge=1, le=64, description="A fit that ends at the render noise is polished at this "
                                                         "many times the scene's samples (1: never).")
    threshold: float = Field(0.05, gt=0, lt=10, description="Relative RMSE beyond the render noise above which a "
                                                            "result is not reliable (on the scene and each "
                                                            "validation condition).")
    resolve_limit: float = Field(0.10, gt=0, lt=10, description="Noise floor (the error two renders of one "
                                                                "material show) above which a scene cannot resolve "
                                                                "the material: its own finding, whatever the error.")
    fit_scene: FitScene = Field(
        FitScene.AUTO, description="Where the fit runs. auto: the scene and a second view lit from behind (the rim and "
                            "grazing reflection), or, where the scene cannot resolve the source (its render noise "
                            "over 3 %, e.g. a highlight smaller than a pixel), more samples (up to 16x), else the "
                            "studio environment; one-view: the same without the back light's view; samples: more "
                            "samples only; as-given: the scene as it is (the paper's probe).")
    inputs: Inputs = Field(
        Inputs.NEEDED, description="needed: the target's held inputs that the source's reading needs (a metal's F82 tint "
                              "for a complex IOR, Diffuse Roughness for an Oren-Nayar diffuse) are tried where the "
                              "fit without them leaves more than the noise, and kept where they lower its error by "
                              "a tenth; given: the target's fitted inputs and what the source carries. Tables and "
                              "experiments always fit the given ones (their points all vary the same parameters).")
    validation: Validation = Field(
        Validation.HELD_OUT, description="held-out: after the fit, render source and target under held-out "
                                                  "lights (grazing, rim, headlight, the studio environment) and "
                                                  "judge them too; none: skip (faster, judged on the scene alone).")
    method: Literal["trf", "dogbox"] = Field("trf", description="scipy least-squares method; trf (Trust Region "
                                                                 "Reflective, bounded) is the paper's.")
    jacobian_updates: int = Field(8, ge=0, le=1000, description="Broyden updates of the Jacobian between rendered "
                                                                "ones (0: a rendered one every iteration, as the "
                                                                "paper).")

    @field_validator("coarse")
    @classmethod
    def _coarse(cls, v: int) -> int:
        if 0 < v < 8:
            raise ValueError("must be 0 (off) or at least 8")
        return v

    def for_study(self) -> "Settings":
        """These settings for a table's or an experiment's fits: auto fits there on the job's scene
        alone (one-view), without the back light's view, and on the target's given inputs (a table's
        points all vary the same parameters). Their points are compared with the paper's
        figures and with tables built before it, and a table's lookups are judged against what its
        direct fits reached on that scene."""
        update = {"inputs": Inputs.GIVEN, **({"fit_scene": FitScene.ONE_VIEW} if self.fit_scene == FitScene.AUTO else {})}
        return self.model_copy(update=update)


DEFAULTS = Settings()
