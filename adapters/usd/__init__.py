"""The USD format plugin, through usd-core: stages read as libraries (`reader.py`), converted
libraries written as `library.usda` (`writer.py`). The UsdPreviewSurface model it reads into is
rendered by three.js's USDLoader (`adapters/threejs`). Importing this module imports no USD."""

from brdfremap.core import hookimpl


@hookimpl
def brdfremap_register_formats(register_reader, register_writer):
    from .reader import UsdReader
    from .writer import MtlxSurface, UsdWriter

    def cycles_models():
        from brdfremap.adapters.cycles.models import MODELS
        return MODELS

    def mitsuba_models():
        from brdfremap.adapters.mitsuba.models import MODELS
        return MODELS

    def threejs_models():
        from brdfremap.adapters.threejs.models import MODELS
        return MODELS

    def principled():
        from brdfremap.adapters.materialx.correspondence import DIRECT, open_pbr_inputs
        return MtlxSurface(open_pbr_inputs, DIRECT)

    def materialx_models():
        from brdfremap.adapters.materialx.models import MODELS
        return MODELS

    def as_itself(category: str):
        def surface():
            from brdfremap.adapters.materialx.models import MODELS
            model = MODELS[category]
            return MtlxSurface(lambda params: {k: v for k, v in params.items() if v != model.param(k).default},
                               {n: n for n in model.names}, model.nodedef)
        return surface

    register_reader(UsdReader())
    register_writer(UsdWriter("cycles", cycles_models, mtlx={"principled": principled},
                              preview_maps={"principled": {"base_color": "diffuse_color", "metallic": "metallic",
                                                           "roughness": "roughness"}}))
    register_writer(UsdWriter("mitsuba", mitsuba_models))
    register_writer(UsdWriter("materialx", materialx_models,
                              mtlx={c: as_itself(c) for c in ("open_pbr_surface", "standard_surface", "gltf_pbr",
                                                              "UsdPreviewSurface", "disney_principled")}))
    register_writer(UsdWriter("threejs", threejs_models,
                              preview_maps={"gltf_pbr": {"base_color": "diffuse_color", "metallic": "metallic",
                                                         "roughness": "roughness"}}))


@hookimpl
def brdfremap_register_scene_writers(register):
    from .probe_scene import UsdSceneWriter

    register(UsdSceneWriter())
