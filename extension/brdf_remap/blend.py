"""The open file's materials in and out of `.blend` files: the ones to convert written to a file of
their own (the tool reads files, never the open session), and converted ones brought in from the
tool's `library.blend`, in place of a material or beside it."""

from __future__ import annotations

from pathlib import Path

import bpy


def selected_materials(context) -> list:
    """The materials in the slots of the selected objects, else the active object's active one."""
    found = {}
    for obj in context.selected_objects or []:
        for slot in getattr(obj, "material_slots", []):
            if slot.material is not None:
                found[slot.material.name] = slot.material
    active = getattr(context, "material", None) or getattr(context.object, "active_material", None)
    if not found and active is not None:
        found[active.name] = active
    return list(found.values())


def all_materials() -> list:
    """Every material of the file that is used (or kept with a fake user) and has a node tree."""
    return [m for m in bpy.data.materials if m.node_tree is not None and (m.users or m.use_fake_user) and not m.library]


def write_materials(materials: list, path: Path) -> Path:
    """The materials (and the images and node groups they use) as a `.blend` of their own, image paths
    made absolute so that the copy finds them."""
    bpy.data.libraries.write(str(path), set(materials), path_remap="ABSOLUTE", fake_user=True)
    return path


def load_materials(library: Path, names: list[str]) -> dict[str, object]:
    """The named materials appended from ``library`` (Blender numbers a name already taken), by the
    name they have there."""
    with bpy.data.libraries.load(str(library), link=False) as (there, here):
        wanted = [n for n in names if n in there.materials]
        here.materials = list(wanted)  # Blender fills the list it is given with the materials
    return dict(zip(wanted, here.materials))


def replace(old, new) -> None:
    """``new`` in place of ``old``: every object and slot that used ``old`` uses ``new``, which takes
    its name (``old`` is left without users: Blender drops it when the file is saved; undo restores it)."""
    name = old.name
    old.user_remap(new)
    old.name = f"{name} (before remap)"
    new.name = name


def keep_beside(new, name: str, model: str) -> None:
    """``new`` kept as a copy beside the material it was remapped from, named after both."""
    new.name = f"{name} ({model})"
    new.use_fake_user = True
