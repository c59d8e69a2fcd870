"""The add-on's operator, ``bpy.ops.posemfa.learn_rig(bones=N, influences=K, weights='fitted')`` (docs/blender.md).

On the active mesh: read its animation as Blender plays it (the evaluated mesh at every frame of the scene's
range: shape keys, armatures, mesh caches, whatever deforms it), fit it with posemfa, write the rig as posemfa's
.glb does (fixed-length joints by default) and build it in the scene from that file's own numbers:

- an Armature object ("<mesh> posemfa rig", at the mesh's place) with one bone per fitted part, parented as the
  part tree, each bone's head at its joint;
- vertex groups (one per bone) with the rig's weights, and an Armature modifier on the mesh;
- a shape key "posemfa bind" holding the rig's bind positions (SSDR chooses them), at value 1;
- an Action on the armature that reproduces frame f at frame f (keys at every frame; the root's location and
  every bone's rotation, as the .glb has them);
- with residual=True, one shape key per frame for what skinning leaves of it, keyed 1 at its frame;
- a colour attribute "posemfa parts" with each vertex's part colour.

The deformation that made the frames is muted, not deleted: the mesh's other shape keys are muted and every
modifier that was on is turned off (turn them back on to see the original). A mesh that does not move over the
frame range is refused with a message that says so.

Run with 'INVOKE_DEFAULT' (the menu, F3) it is modal: the fit runs in a thread (posemfa releases the GIL), the
progress shows in the status bar, and Esc cancels. Called from a script or headless (`blender -b`) it runs to the
end at once.
"""

import colorsys
import threading
import time

import numpy as np

import bpy
from bpy.props import BoolProperty, EnumProperty, IntProperty
from mathutils import Matrix

from .. import Cancelled, Error
from .. import fit as _fit
from ..glb import Rig, e_rms


def read_animation(context, obj):
    """Every frame of the scene's range of ``obj`` as Blender evaluates it, in the object's own space:
    (frames list, (n_frames, n_vertices, 3) float64), and its triangles (n_tri, 3)."""
    scene = context.scene
    frames = list(range(scene.frame_start, scene.frame_end + 1, max(1, scene.frame_step)))
    if len(frames) < 2:
        raise Error(f"the scene's frame range ({scene.frame_start}-{scene.frame_end}) has {len(frames)} frame: "
                    "posemfa learns a rig from at least 2 frames of an animation")
    n = len(obj.data.vertices)
    if n == 0:
        raise Error(f"mesh '{obj.name}' has no vertices")
    out = np.empty((len(frames), n, 3), dtype=np.float32)
    buf = np.empty(3 * n, dtype=np.float32)
    current = scene.frame_current
    try:
        for k, f in enumerate(frames):
            scene.frame_set(f)
            dg = context.evaluated_depsgraph_get()
            ev = obj.evaluated_get(dg)
            me = ev.to_mesh()
            try:
                if len(me.vertices) != n:
                    raise Error(f"frame {f}: '{obj.name}' evaluates to {len(me.vertices)} vertices, its mesh has {n}: "
                                "a modifier adds or removes vertices (subdivision, weld, ...); apply it or turn it "
                                "off, so that every frame is the same vertices")
                me.vertices.foreach_get("co", buf)
                out[k] = buf.reshape(n, 3)
            finally:
                ev.to_mesh_clear()
    finally:
        scene.frame_set(current)
    if np.array_equal(out.min(axis=0), out.max(axis=0)):
        raise Error(f"'{obj.name}' does not move over frames {frames[0]}-{frames[-1]}: posemfa learns a rig from an "
                    "animation (shape keys, an armature, a mesh cache, ... that deform the mesh); animate it or set "
                    "the scene's frame range to where it moves")
    me = obj.data
    me.calc_loop_triangles()
    tris = np.empty(3 * len(me.loop_triangles), dtype=np.int64)
    me.loop_triangles.foreach_get("vertices", tris)
    return frames, out.astype(np.float64), tris.reshape(-1, 3)


def stage_fraction(step):
    """A rough share of the fit done, for the progress bar (0..1)."""
    s = step.get("stage")
    if s == "coarse":
        return 0.05 + 0.2 * min(1.0, step["iteration"] / 100.0)
    if s == "refine":
        return 0.25 + 0.35 * (step["part"] or 0) / max(1, step["of"] or 1)
    if s == "final":
        return 0.6 + 0.3 * min(1.0, step["iteration"] / 150.0)
    return 0.9


def part_colours(n):
    """One colour per part (golden-angle hues), RGBA floats."""
    return np.array([colorsys.hsv_to_rgb((0.13 + 0.618034 * k) % 1.0, 0.55, 0.95) + (1.0,) for k in range(n)])


class Job:
    """One learn_rig: the frames read, the fit, the rig file and the scene objects built from it."""

    def __init__(self, context, obj, bones, influences, weights, joints, residual):
        self.obj = obj
        self.options = dict(bones=bones, influences=influences, weights=weights, joints=joints, residual=residual)
        self.frames, self.points, self.faces = read_animation(context, obj)
        self.cancel = False
        self.fraction = 0.0
        self.stage = "reading"
        self.model = self.rig = self.info = None
        self.error = None

    def progress(self, step):
        self.fraction = stage_fraction(step)
        self.stage = step.get("stage", "")
        return not self.cancel

    def fit(self):
        """Fits and writes the rig (no bpy: runs in a thread when modal)."""
        o = self.options
        params = {"bones": o["bones"]} if o["bones"] > 0 else {}
        self.model = _fit(self.points, self.faces, progress=self.progress, **params)
        self.stage = "rig"
        glb, self.info = self.model.rig_glb(weights=o["weights"], influences=o["influences"], joints=o["joints"],
                                            morphs="residual" if o["residual"] else "none", bind=0)
        self.rig = Rig(glb)
        self.fraction = 0.95

    def run_in_thread(self):
        try:
            self.fit()
        except Exception as e:  # reported by the modal operator in Blender's main thread
            self.error = e

    def build(self, context):
        """The armature, weights, bind key, action, residual keys and part colours (bpy: main thread)."""
        obj, rig, frames = self.obj, self.rig, self.frames
        scene = context.scene
        if context.object is not None and context.object.mode != "OBJECT":
            bpy.ops.object.mode_set(mode="OBJECT")
        names = list(rig.names)
        nj = len(names)

        # -- the armature: bones from the file's joints (head at the joint, pointing at its children)
        arm_data = bpy.data.armatures.new(f"{obj.name} posemfa")
        arm = bpy.data.objects.new(f"{obj.name} posemfa rig", arm_data)
        for coll in obj.users_collection:
            coll.objects.link(arm)
        if not arm.users_collection:
            scene.collection.objects.link(arm)
        arm.parent = obj.parent
        arm.parent_type = obj.parent_type if obj.parent is not None else "OBJECT"
        arm.matrix_world = obj.matrix_world.copy()
        arm_data.display_type = "STICK"
        arm.show_in_front = True
        heads = rig.bind[:, :3, 3]
        rest = rig.rest
        diag = float(np.linalg.norm(rest.max(axis=0) - rest.min(axis=0)))
        dominant = rig.joints[np.arange(len(rest)), np.argmax(rig.weights, axis=1)]
        tails = np.empty_like(heads)
        for k in range(nj):
            children = np.flatnonzero(rig.parents == k)
            if len(children):
                target = heads[children].mean(axis=0)
            else:
                mine = rest[dominant == k]
                target = heads[k] + 2.0 * (mine.mean(axis=0) - heads[k]) if len(mine) else heads[k]
            if np.linalg.norm(target - heads[k]) < 0.02 * diag:
                target = heads[k] + np.array([0.0, 0.0, 0.05 * diag])
            tails[k] = target
        view_layer = context.view_layer
        previous_active = view_layer.objects.active
        view_layer.objects.active = arm
        bpy.ops.object.mode_set(mode="EDIT")
        ebs = []
        for k, name in enumerate(names):
            eb = arm_data.edit_bones.new(name)
            eb.head, eb.tail, eb.roll = tuple(heads[k]), tuple(tails[k]), 0.0
            ebs.append(eb)
        for k in range(nj):
            if rig.parents[k] >= 0:
                ebs[k].parent = ebs[rig.parents[k]]
                ebs[k].use_connect = False
        bpy.ops.object.mode_set(mode="OBJECT")
        view_layer.objects.active = previous_active

        # -- the action: basis_k = B_k^-1 D_p^-1 D_k B_k, so that bone k deforms by D_k (the file's motion)
        rest_m = np.array([np.array(arm_data.bones[name].matrix_local) for name in names])
        rest_inv = np.linalg.inv(rest_m)
        d = rig.deform
        action = bpy.data.actions.new(f"{obj.name} posemfa")
        arm.animation_data_create()
        arm.animation_data.action = action
        x = np.array(frames, dtype=np.float64)
        for k, name in enumerate(names):
            pb = arm.pose.bones[name]
            pb.rotation_mode = "QUATERNION"
            p = rig.parents[k]
            rel = d[:, k] if p < 0 else np.linalg.inv(d[:, p]) @ d[:, k]
            basis = rest_inv[k] @ rel @ rest_m[k]
            quats = np.array([list(Matrix(b[:3, :3].tolist()).to_quaternion()) for b in basis])
            for i in range(1, len(quats)):  # one hemisphere: Blender interpolates components
                if np.dot(quats[i], quats[i - 1]) < 0:
                    quats[i] = -quats[i]
            dp = f'pose.bones["{name}"]'
            channels = [("rotation_quaternion", quats)]
            if rig.animated_translation[k]:
                channels.append(("location", basis[:, :3, 3]))
            for prop, values in channels:
                for i in range(values.shape[1]):
                    fc = action.fcurves.new(f"{dp}.{prop}", index=i, action_group=name)
                    fc.keyframe_points.add(len(x))
                    fc.keyframe_points.foreach_set("co", np.column_stack([x, values[:, i]]).ravel())
                    fc.keyframe_points.foreach_set("interpolation", [1] * len(x))  # LINEAR
                    fc.update()

        # -- mute what made the frames; the mesh's bind positions as a shape key; the weights
        me = obj.data
        turned_off = []
        for m in obj.modifiers:
            if m.show_viewport or m.show_render:
                m.show_viewport = m.show_render = False
                turned_off.append(m.name)
        if me.shape_keys is None:
            obj.shape_key_add(name="Basis", from_mix=False)
        muted = []
        for kb in me.shape_keys.key_blocks[1:]:
            if not kb.mute:
                kb.mute = True
                muted.append(kb.name)
        bind_key = obj.shape_key_add(name="posemfa bind", from_mix=False)
        bind_key.data.foreach_set("co", rest.astype(np.float32).ravel())
        bind_key.slider_min, bind_key.slider_max = 0.0, 1.0
        bind_key.value = 1.0
        if len(rig.morphs):
            keys = me.shape_keys
            keys.animation_data_create()
            if keys.animation_data.action is None:
                keys.animation_data.action = bpy.data.actions.new(f"{obj.name} posemfa residual")
            kact = keys.animation_data.action
            for i, f in enumerate(frames):
                kb = obj.shape_key_add(name=f"posemfa residual {f}", from_mix=False)
                kb.data.foreach_set("co", (rest + rig.morphs[i]).astype(np.float32).ravel())
                kb.relative_key = bind_key  # adds the displacement to the bind positions, not to the basis
                fc = kact.fcurves.new(f'key_blocks["{kb.name}"].value')
                fc.keyframe_points.add(len(x))
                fc.keyframe_points.foreach_set("co", np.column_stack([x, rig.morph_weights[:, i]]).ravel())
                fc.keyframe_points.foreach_set("interpolation", [1] * len(x))
                fc.update()
        for name in names:
            old = obj.vertex_groups.get(name)
            if old is not None:
                obj.vertex_groups.remove(old)
        groups = [obj.vertex_groups.new(name=name) for name in names]
        for v in range(len(rest)):
            for s in range(rig.joints.shape[1]):
                w = float(rig.weights[v, s])
                if w > 0.0:
                    groups[rig.joints[v, s]].add([v], w, "REPLACE")
        mod = obj.modifiers.new("posemfa rig", "ARMATURE")
        mod.object = arm
        mod.use_vertex_groups = True
        mod.use_bone_envelopes = False
        mod.use_deform_preserve_volume = False

        # -- part colours
        labels = np.asarray(self.model.labels)
        colours = part_colours(int(labels.max()) + 1)[labels]
        attr = me.color_attributes.get("posemfa parts") or me.color_attributes.new("posemfa parts", "FLOAT_COLOR",
                                                                                  "POINT")
        attr.data.foreach_set("color", colours.astype(np.float32).ravel())
        me.color_attributes.active_color = attr
        me.update()

        obj["posemfa_e_rms"] = float(self.info["e_rms"])
        obj["posemfa_bones"] = nj
        self.armature = arm
        self.summary = (f"posemfa: {nj} bones from {len(frames)} frames of '{obj.name}' (E_RMS {self.info['e_rms']:.3f}"
                        f" measured on the rig); turned off: {', '.join(turned_off) or 'no modifier'}; muted "
                        f"{len(muted)} shape key(s)")
        return arm


def play_error(context, obj, frames, points):
    """E_RMS of what Blender now plays at each frame against ``points`` (the frames read before)."""
    scene = context.scene
    current = scene.frame_current
    played = np.empty_like(points)
    buf = np.empty(points.shape[1] * 3, dtype=np.float32)
    try:
        for k, f in enumerate(frames):
            scene.frame_set(f)
            ev = obj.evaluated_get(context.evaluated_depsgraph_get())
            me = ev.to_mesh()
            me.vertices.foreach_get("co", buf)
            ev.to_mesh_clear()
            played[k] = buf.reshape(-1, 3)
    finally:
        scene.frame_set(current)
    return e_rms(points, played, 0), played


class POSEMFA_OT_learn_rig(bpy.types.Operator):
    """Learn a rig (armature, weights, action) from the active mesh's animation over the scene's frame range"""

    bl_idname = "posemfa.learn_rig"
    bl_label = "Learn Rig (posemfa)"
    bl_options = {"REGISTER", "UNDO"}

    bones: IntProperty(name="Bones", description="Bones (parts) in the end; 0 = as many as the fit finds",
                       default=0, min=0, max=255)
    influences: IntProperty(name="Influences", description="Most bones per vertex (1-8)", default=4, min=1, max=8)
    weights: EnumProperty(name="Weights", default="fitted", items=[
        ("fitted", "Fitted", "Weights fitted to every frame (SSDR from the parts)"),
        ("smooth", "Smooth", "A smooth blend across each joint"),
        ("rigid", "Rigid", "Each vertex on its part's bone"),
    ])
    joints: EnumProperty(name="Joints", default="fixed", items=[
        ("fixed", "Fixed length", "Bones turn about their joints; only the root moves"),
        ("free", "Free", "Every bone moves freely"),
    ])
    residual: BoolProperty(name="Residual shape keys", default=False,
                           description="One shape key per frame for what skinning leaves of it")

    @classmethod
    def poll(cls, context):
        return context.active_object is not None and context.active_object.type == "MESH"

    def _start(self, context):
        obj = context.active_object
        if obj is None or obj.type != "MESH":
            raise Error("select a mesh object: posemfa rigs the active mesh from its animation")
        return Job(context, obj, self.bones, self.influences, self.weights, self.joints, self.residual)

    def execute(self, context):
        wm = context.window_manager
        wm.progress_begin(0, 100)
        try:
            job = self._start(context)

            def progress(step):
                wm.progress_update(int(100 * stage_fraction(step)))
                return True
            job.progress = progress
            job.fit()
            job.build(context)
        except Cancelled:
            self.report({"WARNING"}, "posemfa: cancelled")
            return {"CANCELLED"}
        except Error as e:
            self.report({"ERROR"}, f"posemfa: {e}")
            return {"CANCELLED"}
        finally:
            wm.progress_end()
        self.report({"INFO"}, job.summary)
        return {"FINISHED"}

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        try:
            self._job = self._start(context)
        except Error as e:
            self.report({"ERROR"}, f"posemfa: {e}")
            return {"CANCELLED"}
        self._thread = threading.Thread(target=self._job.run_in_thread, daemon=True)
        self._thread.start()
        wm = context.window_manager
        wm.progress_begin(0, 100)
        self._timer = wm.event_timer_add(0.2, window=context.window)
        wm.modal_handler_add(self)
        context.workspace.status_text_set("posemfa: learning a rig (Esc cancels)")
        self._t0 = time.time()
        return {"RUNNING_MODAL"}

    def _finish(self, context):
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        context.workspace.status_text_set(None)

    def modal(self, context, event):
        job = self._job
        if event.type == "ESC":
            job.cancel = True
            context.workspace.status_text_set("posemfa: cancelling ...")
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        context.window_manager.progress_update(int(100 * job.fraction))
        if self._thread.is_alive():
            if not job.cancel:
                context.workspace.status_text_set(
                    f"posemfa: {job.stage} ({time.time() - self._t0:.0f} s; Esc cancels)")
            return {"RUNNING_MODAL"}
        self._finish(context)
        if isinstance(job.error, Cancelled):
            self.report({"WARNING"}, "posemfa: cancelled")
            return {"CANCELLED"}
        if job.error is not None:
            self.report({"ERROR"}, f"posemfa: {job.error}")
            return {"CANCELLED"}
        try:
            job.build(context)
        except Error as e:
            self.report({"ERROR"}, f"posemfa: {e}")
            return {"CANCELLED"}
        self.report({"INFO"}, job.summary)
        return {"FINISHED"}


def _menu(self, context):
    self.layout.operator(POSEMFA_OT_learn_rig.bl_idname, text="Learn Rig (posemfa)")


def register():
    bpy.utils.register_class(POSEMFA_OT_learn_rig)
    bpy.types.VIEW3D_MT_object.append(_menu)


def unregister():
    bpy.types.VIEW3D_MT_object.remove(_menu)
    bpy.utils.unregister_class(POSEMFA_OT_learn_rig)
