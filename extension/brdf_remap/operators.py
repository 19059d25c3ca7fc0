"""The operators: remap, export and import start a conversion in the tool's own process, followed by a
timer with Blender's progress bar (Esc or Cancel stops it); without a window (blender -b, tests) they
wait for it. Accept applies a remap's or an import's result in one undoable step."""

from pathlib import Path

import bpy
from bpy.props import BoolProperty, EnumProperty, StringProperty
from bpy_extras.io_utils import ImportHelper

from . import blend, work
from .runner import Refused

SCOPES = (("SELECTED", "Selected", "the materials of the selected objects"),
          ("ALL", "All", "every material of the file"))


def prefs(context):
    addon = context.preferences.addons.get(__package__)
    return addon.preferences if addon is not None else None


def _settings(context) -> tuple[str, str]:
    p = prefs(context)
    return (p.python, p.quality) if p is not None else ("", "DEFAULT")


class _Follows:
    """A conversion started by ``begin`` (which returns False when it could not start, having said
    why), followed in the interface or waited for."""

    _timer = None

    def invoke(self, context, event):
        return self._run(context)

    def execute(self, context):
        return self._run(context)

    def _run(self, context):
        if not self._begin(context):
            return {"CANCELLED"}
        if bpy.app.background or context.window is None:
            return self._wait()
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.5, window=context.window)
        wm.modal_handler_add(self)
        wm.progress_begin(0, 100)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        session = work.SESSION
        if (event.type == "ESC" and event.value == "PRESS") or session.job is None:
            session.cancel()
            return self._end(context, {"CANCELLED"})
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        done, of, _ = session.progress()
        context.window_manager.progress_update(int(100 * done / of) if of else 0)
        _redraw(context)
        if session.job.running():
            return {"PASS_THROUGH"}
        session.finish()
        return self._end(context, {"FINISHED"})

    def cancel(self, context):
        """Blender ends the operator (another file opened, the window closed): the conversion with it."""
        work.SESSION.cancel()
        self._stop(context)

    def _stop(self, context) -> None:
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
            wm.progress_end()

    def _end(self, context, result):
        self._stop(context)
        _redraw(context)
        self.report({"INFO"}, work.SESSION.message)
        return result

    def _wait(self):
        work.SESSION.job.wait()
        work.SESSION.finish()
        self.report({"INFO"}, work.SESSION.message)
        return {"FINISHED"}

    def _begin(self, context) -> bool:
        python, quality = _settings(context)
        try:
            self.begin(context, work.SESSION.command(python), quality)
        except Refused as exc:
            work.SESSION.message = str(exc)
            self.report({"ERROR"}, str(exc))
            return False
        return True


def _materials(context, scope: str) -> list:
    found = blend.selected_materials(context) if scope == "SELECTED" else blend.all_materials()
    if not found:
        raise Refused("no material to convert: select an object that has one, or choose All")
    return found


def _source(materials: list, folder: Path) -> Path:
    return blend.write_materials(materials, folder / "source.blend")


class BRDFREMAP_OT_remap(_Follows, bpy.types.Operator):
    """Remap materials to another Cycles model, fitted in image space and judged under held-out lights"""

    bl_idname = "brdf_remap.remap"
    bl_label = "Remap"
    model: EnumProperty(name="To", items=[(k, label, f"Cycles' {label}") for k, label in work.MODELS])
    scope: EnumProperty(name="Materials", items=SCOPES)
    in_place: BoolProperty(name="In place", default=False,
                           description="Replace each material (else keep the remap beside it as a copy)")

    def begin(self, context, command, quality):
        folder = work.scratch()
        source = _source(_materials(context, self.scope), folder)
        kind = work.Remap(self.model, self.in_place)
        work.SESSION.start(command, kind, [source], f"cycles:{self.model}", folder / "out", quality)


class BRDFREMAP_OT_export(_Follows, bpy.types.Operator):
    """Export materials matched, not mapped by formula: each remapped to the target and judged, written
    next to the .blend"""

    bl_idname = "brdf_remap.export"
    bl_label = "Export matched"
    target: EnumProperty(name="To", items=[(k, e.label, e.label) for k, e in work.EXPORTS.items()])
    scope: EnumProperty(name="Materials", items=SCOPES)

    def begin(self, context, command, quality):
        if not bpy.data.filepath:
            raise Refused("save the file first: a matched export is written next to it")
        here = Path(bpy.data.filepath)
        export = work.EXPORTS[self.target]
        out = here.with_name(f"{here.stem}.brdf-remap") / export.to.replace(":", "-")
        source = _source(_materials(context, self.scope), work.scratch())
        work.SESSION.start(command, work.Exported(export), [source], export.to, out, quality)


class BRDFREMAP_OT_import(_Follows, ImportHelper, bpy.types.Operator):
    """Import another renderer's materials (Mitsuba, MaterialX, glTF, USD, or a folder of images rendered from
    `remap scene export`'s scenes: pick one of its images), each remapped to Cycles"""

    bl_idname = "brdf_remap.import_matched"
    bl_label = "Import matched"
    filepath: StringProperty(subtype="FILE_PATH", options={"SKIP_SAVE", "HIDDEN"})  # the browser each time
    filter_glob: StringProperty(default="*.xml;*.mtlx;*.gltf;*.glb;*.usd;*.usda;*.usdc;*.usdz;*.exr",
                                options={"HIDDEN"})

    def invoke(self, context, event):
        if not self.filepath:
            return ImportHelper.invoke(self, context, event)  # the file browser, then execute: followed
        return self._run(context)

    def begin(self, context, command, quality):
        file = Path(self.filepath)
        if not file.is_file():
            raise Refused(f"{file}: no such file")
        # An image of a folder of images (probe.seed0.exr ...): the folder is the material, rendered elsewhere.
        source = file.parent if file.suffix.lower() == ".exr" else file
        work.SESSION.start(command, work.Import(source), [source], "cycles", work.scratch() / "out", quality)


class BRDFREMAP_OT_accept(bpy.types.Operator):
    """Apply the remapped or imported materials to the file (one step: undo takes it back)"""

    bl_idname = "brdf_remap.accept"
    bl_label = "Accept"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        try:
            self.report({"INFO"}, work.SESSION.accept())
        except Refused as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        _redraw(context)
        return {"FINISHED"}


class BRDFREMAP_OT_discard(bpy.types.Operator):
    """Forget the results (the file was not changed)"""

    bl_idname = "brdf_remap.discard"
    bl_label = "Discard"

    def execute(self, context):
        work.SESSION.discard()
        _redraw(context)
        return {"FINISHED"}


class BRDFREMAP_OT_cancel(bpy.types.Operator):
    """Stop the conversion under way (what finished is kept: a rerun resumes it)"""

    bl_idname = "brdf_remap.cancel"
    bl_label = "Cancel"

    def execute(self, context):
        work.SESSION.cancel()
        return {"FINISHED"}


class BRDFREMAP_OT_report(bpy.types.Operator):
    """Open the full report in the web browser"""

    bl_idname = "brdf_remap.report"
    bl_label = "Open report"

    def execute(self, context):
        index = work.SESSION.out / "index.html" if work.SESSION.out else None
        if index is None or not index.is_file():
            self.report({"ERROR"}, "no report yet: run a conversion first")
            return {"CANCELLED"}
        bpy.ops.wm.url_open(url=index.as_uri())
        return {"FINISHED"}


def _redraw(context) -> None:
    for area in getattr(context.screen, "areas", []):
        if area.type == "PROPERTIES":
            area.tag_redraw()


CLASSES = (BRDFREMAP_OT_remap, BRDFREMAP_OT_export, BRDFREMAP_OT_import, BRDFREMAP_OT_accept,
           BRDFREMAP_OT_discard, BRDFREMAP_OT_cancel, BRDFREMAP_OT_report)
