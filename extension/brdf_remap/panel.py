"""The panel in the material properties: the operators, the conversion under way, and each result's
verdict, error and images (source, remap, error), with Accept, Discard and the full report."""

from __future__ import annotations

import bpy
import bpy.utils.previews

from . import work

_previews = None


def _icon(path) -> int:
    """The image as an icon of the panel (loaded once a path)."""
    key = f"{path}@{path.stat().st_mtime_ns}"  # a file written again is a new image
    if key not in _previews:
        _previews.load(key, str(path), "IMAGE")
    return _previews[key].icon_id


class _RemapMenu:
    in_place = False

    def draw(self, context):
        scope = context.window_manager.brdf_remap_scope
        for model, label in work.MODELS:
            op = self.layout.operator("brdf_remap.remap", text=label)
            op.model, op.scope, op.in_place = model, scope, self.in_place


class BRDFREMAP_MT_remap_copy(_RemapMenu, bpy.types.Menu):
    bl_label = "Remap as a copy"


class BRDFREMAP_MT_remap_in_place(_RemapMenu, bpy.types.Menu):
    bl_label = "Remap in place"
    in_place = True


class BRDFREMAP_MT_export(bpy.types.Menu):
    bl_label = "Export matched"

    def draw(self, context):
        for key, export in work.EXPORTS.items():
            op = self.layout.operator("brdf_remap.export", text=export.label)
            op.target, op.scope = key, context.window_manager.brdf_remap_scope


class BRDFREMAP_PT_material(bpy.types.Panel):
    bl_label = "brdf-remap"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "material"

    def draw(self, context):
        layout, session = self.layout, work.SESSION
        _tool(layout, context)
        layout.row().prop(context.window_manager, "brdf_remap_scope", expand=True)
        col = layout.column(align=True)
        row = col.row(align=True)
        row.menu("BRDFREMAP_MT_remap_copy")
        row.menu("BRDFREMAP_MT_remap_in_place")
        row = col.row(align=True)
        row.menu("BRDFREMAP_MT_export", icon="EXPORT")
        row.operator("brdf_remap.import_matched", icon="IMPORT")
        if session.job is not None:
            done, of, _ = session.progress()
            layout.label(text=f"Running: {done}/{of or '?'}", icon="TIME")
            layout.operator("brdf_remap.cancel", icon="CANCEL")
        if session.message:
            layout.label(text=session.message, icon="INFO")
        for r in session.rows:
            _row(layout, r)
        if session.pending:
            row = layout.row(align=True)
            row.operator("brdf_remap.accept", icon="CHECKMARK")
            row.operator("brdf_remap.discard", icon="X")
        if session.out is not None:
            layout.operator("brdf_remap.report", icon="URL")


def _tool(layout, context) -> None:
    from .operators import prefs

    p = prefs(context)
    found = work.SESSION.checked.get(p.python if p is not None else "")
    if isinstance(found, str):
        layout.label(text=found, icon="ERROR")


def _row(layout, r) -> None:
    box = layout.box()
    box.label(text=f"{r.name}: {r.line()}", icon="MATERIAL")
    images = r.images()
    if images:
        grid = box.grid_flow(columns=len(images), align=True)
        for path in images:
            grid.template_icon(icon_value=_icon(path), scale=5.0)


CLASSES = (BRDFREMAP_MT_remap_copy, BRDFREMAP_MT_remap_in_place, BRDFREMAP_MT_export, BRDFREMAP_PT_material)


def register() -> None:
    global _previews
    from .operators import SCOPES

    _previews = bpy.utils.previews.new()
    bpy.types.WindowManager.brdf_remap_scope = bpy.props.EnumProperty(name="Materials", items=SCOPES)


def unregister() -> None:
    global _previews
    del bpy.types.WindowManager.brdf_remap_scope
    if _previews is not None:
        bpy.utils.previews.remove(_previews)
        _previews = None
