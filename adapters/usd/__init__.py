"""The USD format plugin, through usd-core: stages read as libraries (`reader.py`), converted
libraries written as `library.usda` (`writer.py`). The UsdPreviewSurface model it reads into is
rendered by three.js's USDLoader (`adapters/threejs`). Importing this module imports no USD."""

from brdfremap.core import hookimpl


@hookimpl
def brdfremap_register_formats(register_reader, register_writer):
    from .reader import UsdReader
    from .writer import OpenPbr, UsdWriter

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
        return OpenPbr(open_pbr_inputs, DIRECT)

    register_reader(UsdReader())
    register_writer(UsdWriter("cycles", cycles_models, openpbr={"principled": principled},
                              preview_maps={"principled": {"base_color": "diffuse_color", "metallic": "metallic",
                                                           "roughness": "roughness"}}))
    register_writer(UsdWriter("mitsuba", mitsuba_models))
    register_writer(UsdWriter("threejs", threejs_models,
                              preview_maps={"gltf_pbr": {"base_color": "diffuse_color", "metallic": "metallic",
                                                         "roughness": "roughness"}}))
