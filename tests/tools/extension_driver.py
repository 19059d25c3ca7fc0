"""Runs the Blender extension headless as a user would, in a Blender (`bpy`) process of its own:
installs its zip, opens a real `.blend`, and runs each operator; prints what happened as one JSON
line after "RESULT ". Used by tests/e2e/test_blender_extension.py.

    python extension_driver.py ZIP WORK TOOL_PYTHON CORPUS_MITSUBA CORPUS_MTLX
"""

import json
import sys
from pathlib import Path

import bpy

ADDON = "bl_ext.user_default.brdf_remap"


def material(name: str, node: str, **inputs):
    m = bpy.data.materials.new(name)
    if m.node_tree is None:  # Blender before 5.0 makes a material without nodes
        m.use_nodes = True
    tree = m.node_tree
    out = next(n for n in tree.nodes if n.type == "OUTPUT_MATERIAL")
    for n in [n for n in tree.nodes if n.type != "OUTPUT_MATERIAL"]:
        tree.nodes.remove(n)
    bsdf = tree.nodes.new(node)
    for k, v in inputs.items():
        bsdf.inputs[k].default_value = v
    tree.links.new(bsdf.outputs[0], out.inputs["Surface"])
    return m


def scene(path: Path) -> None:
    """A copper (Glossy BSDF) and a red paint (Principled BSDF), each on a sphere, saved."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    mats = [material("copper", "ShaderNodeBsdfGlossy", Color=(0.95, 0.64, 0.54, 1.0), Roughness=0.3),
            material("red paint", "ShaderNodeBsdfPrincipled", **{"Base Color": (0.6, 0.05, 0.05, 1.0),
                                                                 "Roughness": 0.4})]
    empty = bpy.data.materials.new("empty")  # nothing on its output's Surface: listed as unsupported, with why
    if empty.node_tree is None:
        empty.use_nodes = True
    tree = empty.node_tree
    for n in [n for n in tree.nodes if n.type != "OUTPUT_MATERIAL"]:
        tree.nodes.remove(n)
    mats.append(empty)
    for i, m in enumerate(mats):
        bpy.ops.mesh.primitive_uv_sphere_add(location=(3.0 * i, 0.0, 0.0))
        bpy.context.object.name = m.name
        bpy.context.object.data.materials.append(m)
    bpy.ops.wm.save_as_mainfile(filepath=str(path))


def select(name: str) -> None:
    for obj in bpy.context.view_layer.objects:
        obj.select_set(obj.name == name)
    bpy.context.view_layer.objects.active = bpy.data.objects[name]


def surfaces() -> dict:
    """Every material: its users and the BSDF its output's Surface takes."""
    out = {}
    for m in bpy.data.materials:
        node = next((n for n in m.node_tree.nodes if n.type == "OUTPUT_MATERIAL"), None) if m.node_tree else None
        link = node.inputs["Surface"].links[0] if node and node.inputs["Surface"].links else None
        out[m.name] = {"users": m.users, "bsdf": link.from_node.type if link else None}
    return out


def step(log: dict, name: str, call) -> None:
    from bl_ext.user_default.brdf_remap import work

    try:
        result, error = sorted(call()), ""
    except RuntimeError as exc:  # an operator that reports an error raises it in a script
        result, error = ["CANCELLED"], str(exc)
    log[name] = {"result": result, "error": error, "panel": work.SESSION.lines(), "materials": surfaces()}


class Layout:
    """Records what the panel's draw() lays out (no window here to draw it in): its text, the
    operators and menus it offers, and the images it shows."""

    def __init__(self, out: list):
        self.out = out

    def row(self, **kw):
        return self

    column = box = row

    def grid_flow(self, **kw):
        return self

    def label(self, text="", icon="NONE"):
        self.out.append(f"label: {text}")

    def operator(self, idname, text="", icon="NONE"):
        self.out.append(f"operator: {idname}")
        return type("Properties", (), {})()

    def menu(self, idname, text="", icon="NONE"):
        self.out.append(f"menu: {getattr(bpy.types, idname).bl_label}")

    def prop(self, data, name, **kw):
        self.out.append(f"prop: {name}")

    def template_icon(self, icon_value=0, scale=1.0):
        self.out.append("image")  # its icon id is 0 here: without a window no preview is made


def panel() -> list[str]:
    out: list[str] = []
    cls = bpy.types.BRDFREMAP_PT_material
    cls.draw(type("Panel", (), {"layout": Layout(out)})(), bpy.context)
    return out


def main() -> None:
    zip_path, folder, python, mitsuba, mtlx, images = sys.argv[-6:]
    folder = Path(folder)
    blend = folder / "scene.blend"
    scene(blend)
    bpy.ops.extensions.package_install_files(filepath=zip_path, repo="user_default", enable_on_install=True)
    prefs = bpy.context.preferences.addons[ADDON].preferences
    prefs.python, prefs.quality = python, "DRAFT"
    bpy.ops.wm.open_mainfile(filepath=str(blend))
    from bl_ext.user_default.brdf_remap import work

    log: dict = {"operators": sorted(n for n in dir(bpy.ops.brdf_remap))}
    select("copper")
    step(log, "remap copy", lambda: bpy.ops.brdf_remap.remap(model="metallic", scope="SELECTED", in_place=False))
    log["before accept"] = surfaces()
    step(log, "accept copy", bpy.ops.brdf_remap.accept)
    select("empty")
    step(log, "remap unsupported", lambda: bpy.ops.brdf_remap.remap(model="metallic", scope="SELECTED"))
    select("red paint")
    step(log, "remap in place", lambda: bpy.ops.brdf_remap.remap(model="metallic", scope="SELECTED", in_place=True))
    step(log, "accept in place", bpy.ops.brdf_remap.accept)
    select("copper")
    for target in ("GLTF", "MITSUBA", "MATERIALX"):
        step(log, f"export {target}", lambda: bpy.ops.brdf_remap.export(target=target, scope="SELECTED"))
    log["exported"] = sorted(str(p.relative_to(folder)) for p in (folder / "scene.brdf-remap").glob("*/library.*"))
    for name, file in (("mitsuba", mitsuba), ("images", images), ("mtlx", mtlx)):  # the panel: after MaterialX
        step(log, f"import {name}", lambda: bpy.ops.brdf_remap.import_matched(filepath=file))
        step(log, f"accept {name}", bpy.ops.brdf_remap.accept)
    log["panel"] = panel()
    log["images"] = [[str(p) for p in r.images()] for r in work.SESSION.rows]
    prefs.python = str(folder / "no-such-python")
    step(log, "no tool", lambda: bpy.ops.brdf_remap.remap(model="metallic", scope="ALL"))
    log["cancel"] = cancelled(work, python, folder)
    bpy.ops.preferences.addon_disable(module=ADDON)
    log["after disable"] = sorted(n for n in dir(bpy.ops.brdf_remap))
    print("RESULT " + json.dumps(log))


def cancelled(work, python: str, folder: Path) -> dict:
    """A conversion started and cancelled at once: its process and its renderers' gone, no summary."""
    session = work.Session()
    session.start(session.command(python), work.Import(Path(bpy.data.filepath)), [Path(bpy.data.filepath)],
                  "cycles", folder / "cancelled", "DEFAULT")
    job = session.job
    session.cancel()
    return {"exit": job.process.returncode, "summary": (folder / "cancelled" / "convert.json").exists(),
            "panel": session.lines()}


main()
