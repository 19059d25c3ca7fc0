"""One job: resolved once, its fit scene chosen, its renders cached and timed, fitted by the
engine, validated under held-out lights, reported. Imports the data room, the plugin host and
the engine (and a table's texel lookup for a textured job)."""
