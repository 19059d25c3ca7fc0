"""Shader inputs under the names earlier versions of their standards gave them. Data, no MaterialX import.

`materialx` upgrades a document's own structure from earlier MaterialX versions as it reads it;
it does not know a shading model's renamed inputs, which then fail validation ("Input
'specular_anisotropy' doesn't match declaration"). Each rename here says where it comes from;
an input a later version dropped is left out, with its note."""

from __future__ import annotations

RENAMED: dict[str, dict[str, tuple[str, str]]] = {
    "open_pbr_surface": {
        "specular_anisotropy": ("specular_roughness_anisotropy", "OpenPBR before 1.0"),
        "coat_anisotropy": ("coat_roughness_anisotropy", "OpenPBR before 1.0"),
        "base_roughness": ("base_diffuse_roughness", "OpenPBR before 1.0"),
        "subsurface_anisotropy": ("subsurface_scatter_anisotropy", "OpenPBR before 1.0"),
        "transmission_anisotropy": ("transmission_scatter_anisotropy", "OpenPBR before 1.0"),
    },
    "standard_surface": {
        "specular_ior": ("specular_IOR", "Standard Surface as some exporters write it (lower-case ior)"),
        "coat_ior": ("coat_IOR", "Standard Surface as some exporters write it (lower-case ior)"),
        "thin_film_ior": ("thin_film_IOR", "Standard Surface as some exporters write it (lower-case ior)"),
    },
}
"""shader category -> {old input name: (its name now, where the old one comes from)}."""

DROPPED: dict[str, dict[str, str]] = {
    "open_pbr_surface": {
        "specular_rotation": "OpenPBR 1.0 has no anisotropy rotation (a tangent input turns it)",
        "coat_rotation": "OpenPBR 1.0 has no coat anisotropy rotation (a tangent input turns it)",
    },
}
"""shader category -> {old input name: why it is left out}."""


def upgrade_inputs(shader) -> list[str]:
    """Rename, in place, the inputs of a MaterialX shader node that an earlier version of its
    standard names otherwise (where the node has no input of the new name already), and remove
    the ones a later version dropped; return a note for each. Every name here is absent from the
    shader's current definition, so a current document is left as it is."""
    category = shader.getCategory()
    renamed, dropped = RENAMED.get(category, {}), DROPPED.get(category, {})
    notes = []
    for inp in list(shader.getInputs()):
        old = inp.getName()
        if old in renamed and shader.getInput(renamed[old][0]) is None:
            new, origin = renamed[old]
            inp.setName(new)
            notes.append(f"{old} is read as {new} ({category}: the name in {origin})")
        elif old in dropped:
            shown = inp.getValueString() if inp.hasValueString() else "a connection"
            shader.removeInput(old)
            notes.append(f"{old} = {shown} is left out: {dropped[old]}")
    return notes
