# SPDX-License-Identifier: Apache-2.0
# Blender Cycles as the equal-quality bench's peer (bench/quality.sh).
#
#   blender -b --factory-startup -noaudio -P bench/cycles.py -- SCENE.glb \
#       EYE TARGET FOV_DEG WxH THREADS OUTDIR SAMPLES:SEED [SAMPLES:SEED ...]
#
# Imports the glTF (Blender's own importer), gives every material a Diffuse
# BSDF of its base colour (texture and vertex colour as imported) plus its
# emission, so that Cycles integrates the same Lambertian BRDF as lie-render
# on the bench's Lambertian copies (bench/lambert.c); direct light only
# (every bounce count 0), no world light, no adaptive sampling, no
# denoising, a pixel filter of 0.01 px (samples at the pixel centre, as
# lie-render's one eye ray), the camera of lie-render's --camera
# eye=..,target=..,fov=.. (glTF's +Y up is Blender's +Z).  Each SAMPLES:SEED
# is rendered to OUTDIR/cycles-SAMPLES-SEED.exr (linear RGB, 32-bit float)
# and timed.  Every render syncs the scene and builds its BVH again (with
# persistent data Cycles 3.4 kept the first render's sample count), so
# renders of 1 and 2 samples first measure that set-up, which is taken off
# each time: the times are render times, as lie-render's seconds_render.
# Prints one JSON line per render.
import json
import math
import sys
import time

import bpy
import numpy
from mathutils import Vector

# Blender 3.4's glTF importer still says np.bool, an alias NumPy 1.24
# (Debian 12's) removed; it meant the builtin.
if "bool" not in numpy.__dict__:
    numpy.bool = bool

args = sys.argv[sys.argv.index("--") + 1:]
scene_path, eye, target, fov, size, threads, outdir = args[:7]
runs = [tuple(int(x) for x in r.split(":")) for r in args[7:]]


def vec(s):
    x, y, z = (float(v) for v in s.split(","))
    return Vector((x, -z, y))  # glTF Y-up to Blender Z-up


bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=scene_path)
sc = bpy.context.scene

# Lambert: a Diffuse BSDF fed what fed the Principled BSDF's base colour,
# plus an Emission of its emission input and strength.
for mat in bpy.data.materials:
    if not mat.use_nodes:
        continue
    nt = mat.node_tree
    out = next((n for n in nt.nodes if n.type == "OUTPUT_MATERIAL"), None)
    bsdf = next((n for n in nt.nodes if n.type == "BSDF_PRINCIPLED"), None)
    if out is None or bsdf is None:
        continue
    diff = nt.nodes.new("ShaderNodeBsdfDiffuse")
    diff.inputs["Roughness"].default_value = 0.0  # Lambert, not Oren-Nayar
    src = bsdf.inputs["Base Color"]
    if src.is_linked:
        nt.links.new(src.links[0].from_socket, diff.inputs["Color"])
    else:
        diff.inputs["Color"].default_value = src.default_value
    em = nt.nodes.new("ShaderNodeEmission")
    esrc = bsdf.inputs["Emission"]
    if esrc.is_linked:
        nt.links.new(esrc.links[0].from_socket, em.inputs["Color"])
    else:
        em.inputs["Color"].default_value = esrc.default_value
    em.inputs["Strength"].default_value = bsdf.inputs["Emission Strength"].default_value
    add = nt.nodes.new("ShaderNodeAddShader")
    nt.links.new(diff.outputs["BSDF"], add.inputs[0])
    nt.links.new(em.outputs["Emission"], add.inputs[1])
    nt.links.new(add.outputs["Shader"], out.inputs["Surface"])

# Punctual lights as lie-render takes them: a point's candela as its
# radiant intensity (Blender's importer divided by 683 lm/W and a Cycles
# point of power P radiates P / 4 pi per steradian), and points, not the
# importer's spheres of radius 0.25.
for light in bpy.data.lights:
    light.energy *= 683.0
    if light.type in ("POINT", "SPOT"):
        light.shadow_soft_size = 0.0

# no light from the world
world = bpy.data.worlds.new("black")
world.use_nodes = True
world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
sc.world = world

cam_data = bpy.data.cameras.new("bench")
cam_data.sensor_fit = "VERTICAL"
cam_data.angle = math.radians(float(fov))
cam_data.clip_start = 1e-3 * (vec(target) - vec(eye)).length
cam_data.clip_end = 1e6
cam = bpy.data.objects.new("bench", cam_data)
sc.collection.objects.link(cam)
cam.location = vec(eye)
cam.rotation_mode = "QUATERNION"
cam.rotation_quaternion = (vec(target) - vec(eye)).to_track_quat("-Z", "Y")
sc.camera = cam

w, h = (int(v) for v in size.split("x"))
r = sc.render
r.engine = "CYCLES"
r.resolution_x, r.resolution_y, r.resolution_percentage = w, h, 100
r.threads_mode = "FIXED"
r.threads = int(threads)
r.image_settings.file_format = "OPEN_EXR"
r.image_settings.color_mode = "RGB"
r.image_settings.color_depth = "32"
r.film_transparent = False
sc.view_settings.view_transform = "Standard"
cy = sc.cycles
cy.device = "CPU"
cy.use_adaptive_sampling = False
cy.use_denoising = False
cy.max_bounces = 0
cy.diffuse_bounces = cy.glossy_bounces = cy.transmission_bounces = 0
cy.volume_bounces = cy.transparent_max_bounces = 0
cy.sample_clamp_direct = cy.sample_clamp_indirect = 0.0
cy.filter_width = 0.01
cy.use_animated_seed = False



def render(samples, seed):
    cy.samples = samples
    cy.seed = seed
    t0 = time.perf_counter()
    bpy.ops.render.render()
    return time.perf_counter() - t0


render(1, 0)  # loads the kernels
t1 = render(1, 0)
t2 = render(2, 0)
setup = max(t1 - (t2 - t1), 0.0)
print(json.dumps({"setup_seconds": setup}), flush=True)
for samples, seed in runs:
    dt = max(render(samples, seed) - setup, 0.0)
    path = "%s/cycles-%d-%d.exr" % (outdir, samples, seed)
    bpy.data.images["Render Result"].save_render(path)
    print(json.dumps({"samples": samples, "seed": seed, "seconds": dt, "file": path}), flush=True)
