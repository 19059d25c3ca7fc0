"""Whole libraries: materials read from the files they live in, converted, written back as one
native library per target, with a report people look at.

Rooms: `formats` (readers and writers as plugins, the entries they read), `yaml_reader` (the
project's own material files), `choose` (which target model a material goes to), `convert` (the
jobs through the store and the runner), `html` (index.html)."""
