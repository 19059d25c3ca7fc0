"""The probe scene as a Mitsuba 3 XML file (`remap scene export`), which `mi.load_file` renders as this
adapter does: the same sensor, film, sampler, sphere placement, emitters and integrator, the material
included from `material.xml` beside it (a `<bsdf id="material">`: the white Lambertian as exported, a
user's own in its place). Written as text: nothing here imports Mitsuba."""

from __future__ import annotations

from pathlib import Path
from xml.sax.saxutils import quoteattr

from brdfremap.core.data.atomic import write_text_atomic
from brdfremap.core.data.imageio import read_image, write_exr
from brdfremap.core.data.scene import EnvironmentLight, PointLight, ProbeScene
from brdfremap.core.host.check import ALBEDO

from .envmap import mitsuba_rows

MATERIAL = "material.xml"
WHITE = f"""<scene version="3.0.0">
    <!-- The calibration material: a white Lambertian of albedo {ALBEDO:g}. Put your material here, with the same id. -->
    <bsdf type="twosided" id="material">
        <bsdf type="diffuse">
            <rgb name="reflectance" value="{ALBEDO:g}, {ALBEDO:g}, {ALBEDO:g}"/>
        </bsdf>
    </bsdf>
</scene>
"""


def _v(xs) -> str:
    return ", ".join(f"{x:.9g}" for x in xs)


def _emitter(light, maps: dict[str, Path], here: Path) -> str:
    if isinstance(light, PointLight):
        return (f'    <emitter type="point">\n        <point name="position" value="{_v(light.position)}"/>\n'
                f'        <rgb name="intensity" value="{_v([light.intensity] * 3)}"/>\n    </emitter>')
    # Mitsuba's envmap reads its first and last rows at the poles: the map resampled so it reads the
    # project's convention exactly (`envmap.mitsuba_rows`), beside the scene.
    src = maps[light.map]
    rows = here / f"{src.stem}.mitsuba.exr"
    write_exr(rows, mitsuba_rows(read_image(src)))
    return (f'    <emitter type="envmap">\n        <string name="filename" value={quoteattr(rows.name)}/>\n'
            "    </emitter>")


def scene_xml(scene: ProbeScene, emitters: list[str]) -> str:
    cam, s = scene.camera, scene.sphere
    env = scene.environment is not None
    hide = '\n        <boolean name="hide_emitters" value="true"/>' if env else ""
    return f"""<scene version="3.0.0">
    <!-- brdf-remap probe scene {scene.name!s}: direct light only, linear radiance, black background.
         A material that lets light through needs <integrator type="path"> with max_depth 16 instead.
         mi.load_file(this, spp=N, seed=S) renders it at other samples or another seed. -->
    <default name="spp" value="{scene.spp}"/>
    <default name="seed" value="{scene.seed}"/>
    <integrator type="direct">
        <integer name="emitter_samples" value="1"/>
        <integer name="bsdf_samples" value="{1 if env else 0}"/>{hide}
    </integrator>
    <sensor type="perspective">
        <float name="fov" value="{cam.fov:.9g}"/>
        <string name="fov_axis" value="x"/>
        <transform name="to_world">
            <lookat origin="{_v(cam.position)}" target="{_v(cam.target)}" up="{_v(cam.up)}"/>
        </transform>
        <film type="hdrfilm">
            <integer name="width" value="{scene.resolution}"/>
            <integer name="height" value="{scene.resolution}"/>
            <string name="pixel_format" value="rgb"/>
            <rfilter type="box"/>
        </film>
        <sampler type="multijitter">
            <integer name="sample_count" value="$spp"/>
            <integer name="seed" value="$seed"/>
        </sampler>
    </sensor>
    <include filename="{MATERIAL}"/>
    <shape type="sphere" id="probe">
        <transform name="to_world">
            <scale value="{s.radius:.9g}"/>
            <rotate x="1" angle="-90"/>
            <translate value="{_v(s.center)}"/>
        </transform>
        <ref id="material"/>
    </shape>
{chr(10).join(emitters)}
</scene>
"""


class MitsubaSceneWriter:
    name = "mitsuba"
    suffix = ".xml"
    swap = (f"Mitsuba XML: each scene includes `{MATERIAL}` beside it, a `<bsdf id=\"material\">`: write yours "
            "there (`examples/outside/render_mitsuba.py --material` does it for you).")

    @staticmethod
    def unavailable_reason() -> str | None:
        return None  # text: nothing to import

    def close(self) -> None:
        """Nothing held."""

    def write(self, scene: ProbeScene, path: Path, maps: dict[str, Path]) -> list[Path]:
        here = path.parent
        emitters = [_emitter(x, maps, here) for x in scene.lights]
        out = [write_text_atomic(path, scene_xml(scene, emitters))]
        out += [here / f"{maps[x.map].stem}.mitsuba.exr" for x in scene.lights if isinstance(x, EnvironmentLight)]
        material = here / MATERIAL
        if not material.exists():  # a user's material put there is kept
            out.append(write_text_atomic(material, WHITE))
        return out
