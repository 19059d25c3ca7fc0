"""brdf-remap inside Blender: remap the open file's materials to another Cycles model, export them
to glTF, Mitsuba or MaterialX matched (each remapped and judged, not mapped by formula), and import
another renderer's materials remapped to Cycles. The work runs in brdf-remap's own process (the
Python the preferences name); nothing of the file changes until a result is accepted."""

import bpy
from bpy.props import EnumProperty, StringProperty

from . import operators, panel, work


class BRDFREMAP_preferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    python: StringProperty(name="brdf-remap's Python", subtype="FILE_PATH",
                           description="The Python of a brdf-remap installation (e.g. /path/to/brdf-remap/.venv/bin/"
                                       "python); empty: $BRDF_REMAP_PYTHON, else `remap` on the PATH")
    quality: EnumProperty(name="Quality", items=[
        ("DEFAULT", "Default", "128 px, 16 samples: the verdicts the tool stands by"),
        ("DRAFT", "Draft", "32 px, 8 samples: a first look in seconds, its verdicts rough")])

    def draw(self, context):
        self.layout.prop(self, "python")
        self.layout.prop(self, "quality")


CLASSES = (BRDFREMAP_preferences, *operators.CLASSES, *panel.CLASSES)


@bpy.app.handlers.persistent
def _file_changes(*args) -> None:
    """Another file opened or a new one made: the conversion under way and the results waiting to be
    accepted belong to the file that was open, and go with it."""
    work.SESSION.cancel()
    work.SESSION.discard()


def register() -> None:
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    panel.register()
    bpy.app.handlers.load_pre.append(_file_changes)


def unregister() -> None:
    _file_changes()
    if _file_changes in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.remove(_file_changes)
    panel.unregister()
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
