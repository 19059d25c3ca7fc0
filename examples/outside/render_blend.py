"""Render a scene of `remap scene export --format blend` with Blender, as a Blender user would: no
brdf-remap here. The file holds the render settings (Cycles, samples, box filter, no denoiser, EXR
output); only the seed and, optionally, the sphere's material change.

    python render_blend.py EXPORT/blend/probe.blend OUT.exr --seed 0 [--material LIBRARY.blend:NAME]
"""

import argparse

import bpy


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("scene")
    p.add_argument("out")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--material", help="LIBRARY.blend:NAME, appended and put on the sphere in place of 'material'")
    args = p.parse_args()
    bpy.ops.wm.open_mainfile(filepath=args.scene, load_ui=False)
    scene = bpy.context.scene
    scene.cycles.seed = args.seed
    if args.material:
        library, name = args.material.rsplit(":", 1)
        with bpy.data.libraries.load(library, link=False) as (src, dst):
            dst.materials = [name]
        bpy.data.materials["material"].user_remap(dst.materials[0])
    scene.render.filepath = args.out
    scene.render.use_file_extension = False
    bpy.ops.render.render(write_still=True)


if __name__ == "__main__":
    main()
