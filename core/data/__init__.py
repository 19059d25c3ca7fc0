"""The data room: material models, the probe scene and its lights, settings, findings, a job's
account of its renders, and the helpers that read and write them (images, YAML, JSON, files).
Imports nothing else of the core."""
