# Runs inside headless Blender (tests/python/test_blender.py starts it): installs the add-on zip, builds or takes
# an animated mesh, runs bpy.ops.posemfa.learn_rig on it, and measures what Blender then plays.
#
#   blender -b --factory-startup [--python scripts/fixtures/skinned_character.py] \
#       --python tests/python/blender_check.py -- [OUT_FOR_SKINNED] --zip ADDON.zip --out DIR \
#       --scene shapekeys:POSES_DIR | skinned | still  [--bones N] [--influences K] [--joints fixed|free]
#       [--residual] [--render PNG]
#
# DIR/frames/frame-NNN.obj  the frames the add-on read (exact: float32 written shortest-exact), for rig-report
# DIR/result.json           e_rms_blender (the armature's playback with the original deformation muted, against
#                           the frames), e_rms_file (what posemfa measured on its .glb), bones, frames, muted, ...
import json
import os
import re
import sys

import numpy as np

import bpy

args = sys.argv[sys.argv.index("--") + 1:]


def opt(name, default=None):
    return args[args.index(name) + 1] if name in args else default


zip_path, out, scene_arg = opt("--zip"), opt("--out"), opt("--scene")
bones, influences, render = int(opt("--bones", "0")), int(opt("--influences", "4")), opt("--render")
joints, residual = opt("--joints", "fixed"), "--residual" in args
os.makedirs(os.path.join(out, "frames"), exist_ok=True)



def natural_key(name):
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", name)]


def read_obj(path):
    verts, faces = [], []
    for raw in open(path, "rb"):
        p = raw.split()
        if p and p[0] == b"v":
            verts.append(tuple(float(x) for x in p[1:4]))
        elif p and p[0] == b"f":
            faces.append(tuple(int(x.split(b"/")[0]) - 1 for x in p[1:]))
    return verts, faces


def mesh_object(name, verts, faces):
    me = bpy.data.meshes.new(name)
    me.from_pydata(verts, [], faces)
    me.update()
    ob = bpy.data.objects.new(name, me)
    bpy.context.scene.collection.objects.link(ob)
    return ob


scene = bpy.context.scene
kind = scene_arg.split(":")[0]
if kind == "shapekeys":
    # a generated population as shape keys, one key at 1 per frame (as scripts/fixtures/blender_fixtures.py)
    src = scene_arg.split(":", 1)[1]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    names = sorted([n for n in os.listdir(src) if n.endswith(".obj")], key=natural_key)
    verts, faces = read_obj(os.path.join(src, names[0]))
    ob = mesh_object("creature", verts, faces)
    ob.shape_key_add(name="Basis", from_mix=False)
    keys = []
    for n in names[1:]:
        v, _ = read_obj(os.path.join(src, n))
        k = ob.shape_key_add(name=os.path.splitext(n)[0], from_mix=False)
        k.data.foreach_set("co", [c for p in v for c in p])
        keys.append(k)
    scene.frame_start, scene.frame_end = 0, len(keys)
    for frame in range(len(keys) + 1):
        for i, k in enumerate(keys):
            k.value = 1.0 if i + 1 == frame else 0.0
            k.keyframe_insert("value", frame=frame)
elif kind == "skinned":
    # scripts/fixtures/skinned_character.py ran first in this session: its body mesh, under an Armature modifier
    ob = next(o for o in bpy.data.objects if o.type == "MESH" and any(m.type == "ARMATURE" for m in o.modifiers))
elif kind == "still":
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    bpy.ops.mesh.primitive_monkey_add()
    ob = bpy.context.active_object
    scene.frame_start, scene.frame_end = 1, 20
else:
    raise SystemExit(f"unknown --scene {scene_arg}")

# the add-on as a user installs it (after the scene: a factory reset would unload it)
bpy.ops.preferences.addon_install(filepath=os.path.abspath(zip_path), overwrite=True)
bpy.ops.preferences.addon_enable(module="posemfa_rig")
import posemfa_rig.posemfa.blender.addon as addon  # noqa: E402  (the add-on's own copy of posemfa)

for o in bpy.context.view_layer.objects:
    o.select_set(False)
bpy.context.view_layer.objects.active = ob
ob.select_set(True)

if kind == "still":
    try:
        bpy.ops.posemfa.learn_rig()
        result = {"refused": None}
    except RuntimeError as e:
        result = {"refused": str(e)}
    json.dump(result, open(os.path.join(out, "result.json"), "w"))
    print("result", result)
    sys.exit(0)

frames, points, tris = addon.read_animation(bpy.context, ob)
for k, f in enumerate(frames):
    with open(os.path.join(out, "frames", f"frame-{k:04d}.obj"), "w") as fh:
        fh.write("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in points[k].tolist()))
        fh.write("".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in tris.tolist()))

# what the modal operator does with Esc: the fit in a thread, its progress callback answering False
import threading  # noqa: E402
job = addon.Job(bpy.context, ob, bones, influences, "fitted", joints, residual)
seen = []
job_progress = job.progress
job.progress = lambda step: (seen.append(step["stage"]), job_progress(step))[1]
job.cancel = True
worker = threading.Thread(target=job.run_in_thread)
worker.start()
worker.join()
cancelled = {"error": type(job.error).__name__, "steps": len(seen), "built": job.rig is not None}

ret = bpy.ops.posemfa.learn_rig(bones=bones, influences=influences, weights="fitted", joints=joints,
                                residual=residual)
assert ret == {"FINISHED"}, ret
arm = next(o for o in bpy.data.objects if o.name.endswith("posemfa rig"))
e_blender, played = addon.play_error(bpy.context, ob, frames, points)
result = {
    "e_rms_blender": e_blender,
    "e_rms_file": ob["posemfa_e_rms"],
    "bones": len(arm.data.bones),
    "frames": len(frames),
    "vertices": points.shape[1],
    "modifiers_on": [m.name for m in ob.modifiers if m.show_viewport],
    "keys_unmuted": [k.name for k in ob.data.shape_keys.key_blocks[1:] if not k.mute],
    "vertex_groups": len(ob.vertex_groups),
    "colour_attribute": ob.data.color_attributes.active_color.name,
    "action_frames": list(arm.animation_data.action.frame_range),
    "cancelled_in_thread": cancelled,
}
# fixed-length joints: every bone's head keeps its distance to its parent's head over the frames
dist = []
for f in frames:
    scene.frame_set(f)
    d = [(b.head - b.parent.head).length for b in arm.pose.bones if b.parent is not None]
    dist.append(d)
dist = np.array(dist)
result["bone_length_spread"] = float(np.max(np.ptp(dist, axis=0)) / max(1e-12, float(np.max(dist))))
if render:
    scene.frame_set(frames[len(frames) // 2])
    lo, hi = points.reshape(-1, 3).min(axis=0), points.reshape(-1, 3).max(axis=0)
    centre, size = (lo + hi) / 2, float(np.linalg.norm(hi - lo))
    cam_data = bpy.data.cameras.new("camera")
    cam = bpy.data.objects.new("camera", cam_data)
    scene.collection.objects.link(cam)
    w = np.array(ob.matrix_world)
    c = (w @ np.append(centre, 1.0))[:3]
    cam.location = tuple(c + np.array([0.75, -1.1, 0.5]) * size)
    direction = c - np.array(cam.location)
    from mathutils import Vector
    cam.rotation_euler = Vector(tuple(direction)).to_track_quat("-Z", "Y").to_euler()
    scene.camera = cam
    scene.render.engine = "BLENDER_WORKBENCH"
    scene.display.shading.color_type = "VERTEX"
    scene.display.shading.light = "STUDIO"
    scene.display.shading.show_xray = True  # the bones show through the mesh
    scene.display.shading.xray_alpha = 0.55
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 800, 460, 100
    scene.render.image_settings.color_mode = "RGB"
    scene.render.image_settings.compression = 100
    scene.render.film_transparent = False
    # the bones drawn for the picture: a thin cone from each head to its tail, posed
    for pb in arm.pose.bones:
        head = arm.matrix_world @ pb.head
        tail = arm.matrix_world @ pb.tail
        v = tail - head
        bpy.ops.mesh.primitive_cone_add(radius1=0.018 * size, radius2=0.0, depth=v.length,
                                        location=tuple((head + tail) / 2))
        cone = bpy.context.active_object
        cone.rotation_euler = v.to_track_quat("Z", "Y").to_euler()
        cone.color = (0.1, 0.1, 0.1, 1.0)
    scene.render.filepath = render
    bpy.ops.render.render(write_still=True)
json.dump(result, open(os.path.join(out, "result.json"), "w"), indent=1)
print("result", json.dumps(result))
