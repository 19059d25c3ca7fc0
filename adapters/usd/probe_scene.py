"""The probe scene as a USD stage (`remap scene export`): for a user who renders it in a renderer this
tool cannot drive (Blender, Houdini's Karma, Omniverse, usdrecord) and hands the images back.

Conventions (calibrated in Blender 5.0's importer + Cycles against `analytic_lambert` and the Cycles
adapter: examples/outside/render_usd_blender.py):

* Y up, metersPerUnit 1: the scene's lengths are metres, written as they are.
* A point light of radiant intensity I (W/sr) is a SphereLight with ``treatAsPoint``, ``normalize`` on
  and ``inputs:intensity = 4 I``. UsdLux: a sphere light's radiance is intensity × 2^exposure, divided
  by its area 4πr² when normalized; a Lambertian sphere of radiance L sends L·πr² W/sr every way, so a
  normalized one sends intensity / 4, whatever its radius (the point is its limit). Blender reads it as
  a point light of π × intensity W, i.e. 4πI: its radiant intensity is I. Without ``normalize`` Blender
  multiplies by the area, which is 0 for ``treatAsPoint``: the light would go dark.
* An environment is a DomeLight of the map as realised (scale and rotation applied), intensity 1,
  ``texture:format`` latlong, untransformed: the project's equirectangular convention
  (`core.data.environment`: u = atan2(x, -z)/2π from the left, v = acos(y)/π from the top) is the
  OpenEXR latitude-longitude convention UsdLux prescribes for a Y-up dome (longitude +π at the left
  edge is -z, 0 at the centre is +z, +π/2 is +x). Only surfaces see it: hide it from camera rays.
* The sphere is a smooth UV-sphere mesh (its exact centre and radius in customLayerData): Blender turns
  a UsdGeom.Sphere into a 10 × 10 polygon mesh, 20 % off the analytic image at the default probe.
* The material is a UsdPreviewSurface Lambertian (`_material`): specular workflow, black specularColor,
  ior 1. Blender imports it as a Principled BSDF with a black Specular Tint and IOR 1: no reflection at
  any angle. With the IOR left at its 1.5 the black tint still reflects at grazing angles (the rim
  light 85 % too bright, the default probe 0.3 % too dark); the UsdPreviewSurface specification's
  Schlick Fresnel goes to white at grazing whatever F0 is, so a renderer that follows it to the letter
  keeps a thin grazing reflection."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from brdfremap.core.data.atomic import temp_beside
from brdfremap.core.data.errors import RemapError
from brdfremap.core.data.scene import EnvironmentLight, PointLight, ProbeScene
from brdfremap.core.host.check import ALBEDO  # the calibration material's albedo

SPHERE_SEGMENTS = 192
"""Around the sphere (half as many from pole to pole), a 2.4 MB .usda. Against the Cycles adapter's
exact sphere at 64 px, 256 spp: 0.10 % (default probe) and 1.0 % (rim light, where the polygonal
silhouette shows); 128 segments: 0.22 % and 1.8 %; 256: 0.06 % and 0.8 % (4.2 MB)."""
POINT_RADIUS = 1e-3
"""A point light's radius (m), for renderers that ignore treatAsPoint: normalized, its intensity
does not depend on it."""
APERTURE = 0.36
"""The camera's horizontal and vertical aperture in tenths of a scene unit (UsdGeomCamera): a 36 mm
square film back; the focal length gives the field of view."""
MATERIAL_PATH = "/World/Looks/material"


class UsdSceneWriter:
    """`brdfremap_register_scene_writers`: one single-view probe scene as a USD stage (.usda)."""

    name = "usd"
    suffix = ".usda"
    swap = (f"USD: the sphere `/World/Sphere` is bound to `{MATERIAL_PATH}` (a UsdPreviewSurface of the white "
            "Lambertian): bind yours instead. A dome light cannot be hidden from the camera in USD itself: keep the "
            "background black (Blender: film transparent, as `examples/outside/render_usd_blender.py` does).")

    @staticmethod
    def unavailable_reason() -> str | None:
        import importlib.util

        return None if importlib.util.find_spec("pxr") is not None else \
            "usd-core is not installed: pip install 'brdf-remap[threejs]' (it brings usd-core)"

    def close(self) -> None:
        """Nothing held."""

    def write(self, scene: ProbeScene, path: Path, maps: dict[str, Path]) -> list[Path]:
        """The stage at ``path``, naming each environment map in ``maps`` relative to itself."""
        from pxr import Usd, UsdGeom

        if scene.views:
            raise ValueError("write: a scene of several views is written view by view (view_scenes)")
        path = Path(path)
        stage = Usd.Stage.CreateInMemory()
        UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
        UsdGeom.SetStageMetersPerUnit(stage, 1.0)
        stage.SetDefaultPrim(UsdGeom.Xform.Define(stage, "/World").GetPrim())
        camera = _camera(stage, scene)
        _bind(_sphere(stage, scene), _material(stage))
        UsdGeom.Scope.Define(stage, "/World/Lights")
        for i, light in enumerate(scene.point_lights):
            _point_light(stage, f"/World/Lights/light{i}", light)
        if scene.environment is not None:
            _dome(stage, "/World/Lights/environment", scene.environment, maps, path.parent)
        _render_settings(stage, scene, camera)
        stage.GetRootLayer().customLayerData = _layer_data(scene)
        stage.GetRootLayer().documentation = ("brdf-remap probe scene: a white Lambertian sphere (material "
                                              f"{MATERIAL_PATH}, albedo {ALBEDO}) under its lights; swap the "
                                              "material for yours. Black background, direct lighting only.")
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = temp_beside(path).with_suffix(".usda")  # usd-core picks the format by the ending
        try:
            if not stage.GetRootLayer().Export(str(tmp)):
                raise RemapError(f"cannot write {path}: usd-core could not write the stage")
            os.replace(tmp, path)
        finally:
            tmp.unlink(missing_ok=True)
        return [path]


def _layer_data(scene: ProbeScene) -> dict:
    """What the stage cannot say in schema terms but a render script needs: the image, the samples,
    the exact sphere behind the mesh, and the units."""
    from pxr import Gf

    return {"brdfremap": {
        "resolution": scene.resolution, "spp": scene.spp, "seed": scene.seed,
        "sphere_center": Gf.Vec3d(*scene.sphere.center), "sphere_radius": float(scene.sphere.radius),
        "units": "metres; point lights: SphereLight treatAsPoint, normalize, intensity = 4 x radiant intensity "
                 "(W/sr); environment: DomeLight of radiance (W m^-2 sr^-1), untransformed (OpenEXR latlong)",
        "background": "black: the dome lights surfaces only (hide it from camera rays)",
        "integrator": "direct lighting only; image: linear RGB radiance, float32, box filter 1 pixel",
    }}


def _look_at(eye, target, up):
    """The camera's local-to-world matrix (Gf's row vectors): it looks down its -Z with +Y up."""
    from pxr import Gf

    e, t, u = (np.asarray(v, dtype=np.float64) for v in (eye, target, up))
    forward = (t - e) / np.linalg.norm(t - e)
    right = np.cross(forward, u)
    right /= np.linalg.norm(right)
    upv = np.cross(right, forward)
    rows = [(*right, 0.0), (*upv, 0.0), (*(-forward), 0.0), (*e, 1.0)]
    return Gf.Matrix4d(*[float(x) for row in rows for x in row])


def _camera(stage, scene: ProbeScene):
    """A pinhole at the scene's camera: a square film back whose width spans the horizontal field of
    view (the image is square), no depth of field, clipping well around the sphere."""
    from pxr import Gf, UsdGeom

    cam = scene.camera
    camera = UsdGeom.Camera.Define(stage, "/World/Camera")
    camera.AddTransformOp().Set(_look_at(cam.position, cam.target, cam.up))
    camera.CreateProjectionAttr(UsdGeom.Tokens.perspective)
    camera.CreateHorizontalApertureAttr(APERTURE)
    camera.CreateVerticalApertureAttr(APERTURE)
    camera.CreateFocalLengthAttr(APERTURE / 2 / math.tan(math.radians(cam.fov) / 2))
    reach = math.dist(cam.position, scene.sphere.center)
    near = max(1e-4, 0.1 * (reach - scene.sphere.radius))
    camera.CreateClippingRangeAttr(Gf.Vec2f(near, 100.0 * (reach + scene.sphere.radius)))
    camera.GetPrim().SetDocumentation(f"horizontal field of view {cam.fov:g} degrees; square image")
    return camera


def _sphere_mesh(segments: int):
    """(unit positions, which are also the normals; st; face counts; face indices) of a UV sphere, its
    poles on ±Y: a grid of (segments + 1) x (segments / 2 + 1) vertices (the seam and the poles repeated,
    so that `st` is per vertex), quads between rings, triangles at the poles."""
    rings = segments // 2
    theta = np.linspace(0.0, math.pi, rings + 1)  # from +Y down
    phi = np.linspace(0.0, 2 * math.pi, segments + 1)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    unit = np.stack([np.sin(t) * np.sin(p), np.cos(t), np.sin(t) * np.cos(p)], axis=-1).reshape(-1, 3)
    st = np.stack([p / (2 * math.pi), 1.0 - t / math.pi], axis=-1).reshape(-1, 2)
    idx = np.arange((rings + 1) * (segments + 1)).reshape(rings + 1, segments + 1)
    a, b, c, d = idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]  # counter-clockwise seen from outside
    counts, faces = [], []
    for ring in range(rings):
        quad = np.stack([a[ring], b[ring], c[ring], d[ring]], axis=-1)
        if ring == 0:
            quad = quad[:, [0, 1, 2]]  # a and d are both the north pole
        elif ring == rings - 1:
            quad = quad[:, [0, 1, 3]]  # b and c are both the south pole
        counts += [quad.shape[1]] * quad.shape[0]
        faces.append(quad.ravel())
    return unit, st, counts, np.concatenate(faces)


def _sphere(stage, scene: ProbeScene):
    """The probe sphere as a smooth mesh (normals of the exact sphere at its vertices, no subdivision)."""
    from pxr import Gf, Sdf, UsdGeom, Vt

    unit, st, counts, faces = _sphere_mesh(SPHERE_SEGMENTS)
    r, c = scene.sphere.radius, np.asarray(scene.sphere.center, dtype=np.float64)
    mesh = UsdGeom.Mesh.Define(stage, "/World/Sphere")
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy((unit * r + c).astype(np.float32)))
    mesh.CreateNormalsAttr(Vt.Vec3fArray.FromNumpy(unit.astype(np.float32)))
    mesh.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray(counts))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(faces.astype(np.int32)))
    mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    mesh.CreateOrientationAttr(UsdGeom.Tokens.rightHanded)
    mesh.CreateExtentAttr(Vt.Vec3fArray([Gf.Vec3f(*(c - r)), Gf.Vec3f(*(c + r))]))
    UsdGeom.PrimvarsAPI(mesh).CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.vertex).Set(
        Vt.Vec2fArray.FromNumpy(st.astype(np.float32)))
    mesh.GetPrim().SetDocumentation(f"the probe sphere: centre {tuple(scene.sphere.center)}, radius {r:g}, "
                                    f"{SPHERE_SEGMENTS} x {SPHERE_SEGMENTS // 2} faces")
    return mesh


def _material(stage):
    """A white Lambertian of albedo 0.8 as a UsdPreviewSurface: the specular workflow with a black
    specular colour and an IOR of 1 (no interface: Blender then imports a Principled BSDF without any
    reflection; the metallic workflow keeps a 4 % dielectric one), roughness 1 for what remains."""
    from pxr import Gf, Sdf, UsdGeom, UsdShade

    UsdGeom.Scope.Define(stage, MATERIAL_PATH.rsplit("/", 1)[0])
    material = UsdShade.Material.Define(stage, MATERIAL_PATH)
    shader = UsdShade.Shader.Define(stage, f"{MATERIAL_PATH}/PreviewSurface")
    shader.CreateIdAttr("UsdPreviewSurface")
    shader.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(ALBEDO, ALBEDO, ALBEDO))
    shader.CreateInput("useSpecularWorkflow", Sdf.ValueTypeNames.Int).Set(1)
    shader.CreateInput("specularColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(0.0, 0.0, 0.0))
    for name, value in (("roughness", 1.0), ("metallic", 0.0), ("ior", 1.0), ("opacity", 1.0), ("clearcoat", 0.0)):
        shader.CreateInput(name, Sdf.ValueTypeNames.Float).Set(value)
    material.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
    material.GetPrim().SetDocumentation("the probe's material: replace it by yours (keep its name)")
    return material


def _bind(mesh, material) -> None:
    from pxr import UsdShade

    UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(material)


def _point_light(stage, prim_path: str, light: PointLight) -> None:
    """An isotropic point light of radiant intensity ``light.intensity`` W/sr (the module's convention)."""
    from pxr import Gf, UsdGeom, UsdLux

    lux = UsdLux.SphereLight.Define(stage, prim_path)
    UsdGeom.Xformable(lux).AddTranslateOp().Set(Gf.Vec3d(*light.position))
    lux.CreateTreatAsPointAttr(True)
    lux.CreateRadiusAttr(POINT_RADIUS)
    lux.CreateNormalizeAttr(True)
    lux.CreateIntensityAttr(4.0 * light.intensity)
    lux.CreateExposureAttr(0.0)
    lux.CreateColorAttr(Gf.Vec3f(1.0, 1.0, 1.0))
    lux.GetPrim().SetDocumentation(f"radiant intensity {light.intensity:g} W/sr: normalized, intensity = 4 x W/sr "
                                   "(a normalized sphere light of any radius sends intensity / 4 W/sr)")


def _dome(stage, prim_path: str, env: EnvironmentLight, maps: dict[str, Path], folder: Path) -> None:
    """The environment: its map (scale and rotation applied) named relative to the stage, in the default
    orientation, which is the project's convention."""
    from pxr import Gf, Sdf, UsdLux

    if env.map not in maps:
        raise KeyError(f"write: no map file given for the environment {env.map!r}")
    relative = os.path.relpath(Path(maps[env.map]).resolve(), folder.resolve()).replace(os.sep, "/")
    lux = UsdLux.DomeLight.Define(stage, prim_path)
    lux.CreateTextureFileAttr(Sdf.AssetPath(f"./{relative}"))  # anchored to the layer, not a search path
    lux.CreateTextureFormatAttr(UsdLux.Tokens.latlong)
    lux.CreateIntensityAttr(1.0)
    lux.CreateExposureAttr(0.0)
    lux.CreateColorAttr(Gf.Vec3f(1.0, 1.0, 1.0))
    lux.GetPrim().SetDocumentation("radiance as the map's pixels (W m^-2 sr^-1), OpenEXR latlong orientation "
                                   "(Y up, +z at the centre column, +x at a quarter): lights surfaces only, "
                                   "not seen by the camera")


def _render_settings(stage, scene: ProbeScene, camera) -> None:
    """A UsdRender.Settings of the image (square, scene.resolution wide) for renderers that read one
    (husk, usdrecord); samples and seed are in customLayerData."""
    from pxr import Gf, UsdGeom, UsdRender

    UsdGeom.Scope.Define(stage, "/Render")
    settings = UsdRender.Settings.Define(stage, "/Render/settings")
    settings.CreateResolutionAttr(Gf.Vec2i(scene.resolution, scene.resolution))
    settings.CreatePixelAspectRatioAttr(1.0)
    settings.CreateCameraRel().SetTargets([camera.GetPath()])
    stage.SetMetadata("renderSettingsPrimPath", "/Render/settings")
