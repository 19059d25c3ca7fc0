"""`brdfremap.core.protocol`, where plugin authors import the adapter protocol from: it lives in
the plugin host (`brdfremap.core.host.protocol`)."""

from .host.protocol import *  # noqa: F401,F403
from .host.protocol import Adapter  # noqa: F401
