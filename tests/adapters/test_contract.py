"""Every built-in adapter, and the analytic example, passes the contract kit."""

from brdfremap.adapters.cycles.adapter import CyclesAdapter
from brdfremap.adapters.mitsuba.adapter import MitsubaAdapter
from brdfremap.adapters.threejs.adapter import ThreeJsAdapter
from brdfremap.core.testing import AdapterContract
from brdfremap_example.adapter import ToyAdapter


class TestMitsubaContract(AdapterContract):
    factory = MitsubaAdapter
    calibration = ("diffuse", {"reflectance": 0.8})


class TestCyclesContract(AdapterContract):
    factory = CyclesAdapter
    calibration = ("diffuse", {"color": 0.8})


class TestThreeJsContract(AdapterContract):
    factory = ThreeJsAdapter
    calibration = ("gltf_pbr", {"base_color": 0.8, "metallic": 0.0, "roughness": 1.0, "specular": 0.0})


class TestToyContract(AdapterContract):
    factory = ToyAdapter
    calibration = ("toy", {"diffuse": 0.8, "specular": 0.0})
