"""The materialx package and its standard libraries, loaded once a process."""

from __future__ import annotations

import functools

from brdfremap.core.data.errors import ConfigError


def mx():
    try:
        import MaterialX
    except ImportError:
        raise ConfigError("reading MaterialX needs the materialx package: pip install 'materialx==1.39.*'") from None
    return MaterialX


@functools.cache
def standard_libraries():
    """MaterialX's standard libraries, loaded once (about 0.3 s): callers import them into their own
    documents and never change this one."""
    m = mx()
    lib = m.createDocument()
    m.loadLibraries(m.getDefaultDataLibraryFolders(), m.getDefaultDataSearchPath(), lib)
    return lib
