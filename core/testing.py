"""`brdfremap.core.testing`, where adapter authors import the contract kit from: it lives in the
plugin host (`brdfremap.core.host.testing`)."""

from .host.testing import *  # noqa: F401,F403
from .host.testing import (  # noqa: F401
    AdapterContract,
    SphereHits,
    analytic_glass,
    analytic_lambert,
    analytic_mirror,
    box_filtered,
    box_filtered_lambert,
    environment_irradiance,
    point_light_irradiance,
    scene_for,
    sphere_hits,
)
