"""Every built-in adapter, and the analytic example, passes the contract kit."""

from brdfremap.adapters.cycles.adapter import CyclesAdapter
from brdfremap.adapters.mitsuba.adapter import MitsubaAdapter
from brdfremap.core.testing import AdapterContract
from brdfremap_example.adapter import ToyAdapter


class TestMitsubaContract(AdapterContract):
    factory = MitsubaAdapter
    calibration = ("diffuse", {"reflectance": 0.8})


class TestCyclesContract(AdapterContract):
    factory = CyclesAdapter
    calibration = ("diffuse", {"color": 0.8})


class TestToyContract(AdapterContract):
    factory = ToyAdapter
    calibration = ("toy", {"diffuse": 0.8, "specular": 0.0})
