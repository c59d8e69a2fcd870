"""The rig a posemfa .glb holds, read back as numpy arrays (for the Blender add-on and for checks).

Reads exactly what :meth:`posemfa.Model.rig_glb` writes (src/export/gltf.rs): one skinned mesh, one joint per
part under a `skeleton` node that carries the unit box -> original units map, and the `training poses` clip
(keyframe i = pose i). Everything is returned in the mesh's original units, from the file's own float32
numbers, so that playing it here is playing the file (as ``posemfa rig-report`` does).
"""

import json
import struct

import numpy as np

_COMPONENTS = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


class GlbError(ValueError):
    pass


def _quat_matrix(q):
    """3x3 rotation of a glTF quaternion (x, y, z, w), normalised."""
    x, y, z, w = np.asarray(q, dtype=np.float64) / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def _trs(t, q, s):
    m = np.eye(4)
    m[:3, :3] = _quat_matrix(q) * np.asarray(s, dtype=np.float64)[None, :]
    m[:3, 3] = t
    return m


class Rig:
    """A posemfa rig from a .glb.

    rest (n_v, 3) bind positions; faces (n_f, 3); joints (n_v, m) and weights (n_v, m) per vertex (m = 4 or 8);
    names (n_j,) joint names; parents (n_j,) index of each joint's parent, -1 for the root; bind (n_j, 4, 4)
    each joint's rest placement (the inverse of its inverse bind matrix, scale removed: a rigid placement in
    the mesh's units); deform (n_k, n_j, 4, 4) each joint's motion from the bind pose to keyframe k (joint world
    x inverse bind: rigid, original units); local_rotations (n_k, n_j, 4) the clip's local rotations (x, y, z,
    w); animated_translation (n_j,) whether the clip moves the joint's translation (with fixed joints only the
    root's); morphs (n_t, n_v, 3) and morph_weights (n_k, n_t) when the file has residual morph targets.
    """

    def __init__(self, glb):
        if len(glb) < 20 or glb[:4] != b"glTF":
            raise GlbError("not a .glb (no glTF header)")
        _, _, total = struct.unpack_from("<III", glb, 0)
        jlen, jtype = struct.unpack_from("<II", glb, 12)
        if jtype != 0x4E4F534A:
            raise GlbError("no JSON chunk")
        doc = json.loads(glb[20:20 + jlen])
        off = 20 + jlen
        bin_chunk = b""
        if off + 8 <= len(glb):
            blen, _ = struct.unpack_from("<II", glb, off)
            bin_chunk = glb[off + 8:off + 8 + blen]
        self._doc, self._bin = doc, bin_chunk

        prim = doc["meshes"][0]["primitives"][0]
        attrs = prim["attributes"]
        self.rest = self._acc(attrs["POSITION"]).astype(np.float64)
        self.faces = self._acc(prim["indices"]).reshape(-1, 3).astype(np.int64)
        js, ws = [], []
        s = 0
        while f"JOINTS_{s}" in attrs:
            js.append(self._acc(attrs[f"JOINTS_{s}"]).astype(np.int64))
            ws.append(self._acc(attrs[f"WEIGHTS_{s}"]).astype(np.float64))
            s += 1
        if not js:
            raise GlbError("no JOINTS_0 / WEIGHTS_0: not a skinned mesh")
        self.joints, self.weights = np.concatenate(js, axis=1), np.concatenate(ws, axis=1)
        targets = prim.get("targets") or []
        self.morphs = np.stack([self._acc(t["POSITION"]).astype(np.float64) for t in targets]) if targets \
            else np.zeros((0,) + self.rest.shape)

        skin = doc["skins"][0]
        nodes = doc["nodes"]
        joint_nodes = list(skin["joints"])
        slot = {n: k for k, n in enumerate(joint_nodes)}
        parent_node = {}
        for i, n in enumerate(nodes):
            for c in n.get("children", []):
                parent_node[c] = i
        self.names = [nodes[n].get("name", f"joint {k}") for k, n in enumerate(joint_nodes)]
        self.parents = np.array([slot.get(parent_node.get(n, -1), -1) for n in joint_nodes], dtype=np.int64)
        ibm = self._acc(skin["inverseBindMatrices"]).astype(np.float64).reshape(-1, 4, 4).transpose(0, 2, 1)

        anim = next((a for a in doc.get("animations", []) if a.get("name") == "training poses"), None)
        if anim is None:
            raise GlbError("no 'training poses' clip")
        n_keys = len(self._acc(anim["samplers"][0]["input"]))
        local = [(np.array(n.get("translation", [0, 0, 0]), dtype=np.float64),
                  np.array(n.get("rotation", [0, 0, 0, 1]), dtype=np.float64),
                  np.array(n.get("scale", [1, 1, 1]), dtype=np.float64)) for n in nodes]
        tracks = []
        self.animated_translation = np.zeros(len(joint_nodes), dtype=bool)
        self.morph_weights = np.zeros((n_keys, len(targets)))
        for ch in anim["channels"]:
            out = self._acc(anim["samplers"][ch["sampler"]]["output"]).astype(np.float64)
            node, path = ch["target"]["node"], ch["target"]["path"]
            if path == "weights":
                self.morph_weights = out.reshape(n_keys, -1)
                continue
            tracks.append((node, path, out.reshape(n_keys, -1)))
            if path == "translation" and node in slot:
                self.animated_translation[slot[node]] = True

        def world(key):
            loc = [list(t) for t in local]
            for node, path, out in tracks:
                i = {"translation": 0, "rotation": 1, "scale": 2}[path]
                loc[node][i] = out[key]
            cache = {}

            def w(n):
                if n not in cache:
                    m = _trs(*loc[n])
                    cache[n] = w(parent_node[n]) @ m if n in parent_node else m
                return cache[n]
            return np.stack([w(n) for n in joint_nodes]), np.stack([loc[n][1] for n in joint_nodes])

        deform, rots = [], []
        for key in range(n_keys):
            wm, q = world(key)
            deform.append(wm @ ibm)
            rots.append(q)
        self.deform = np.stack(deform)
        self.local_rotations = np.stack(rots)
        bind = np.linalg.inv(ibm)
        scale = np.cbrt(np.linalg.det(bind[:, :3, :3]))
        bind[:, :3, :3] /= scale[:, None, None]
        self.bind = bind

    def _acc(self, index):
        a = self._doc["accessors"][index]
        view = self._doc["bufferViews"][a["bufferView"]]
        dtype = np.dtype(_COMPONENTS[a["componentType"]])
        width = _WIDTH[a["type"]]
        start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
        stride = view.get("byteStride", 0)
        count = a["count"]
        if stride and stride != width * dtype.itemsize:
            raw = np.frombuffer(self._bin, dtype=np.uint8, count=stride * (count - 1) + width * dtype.itemsize,
                                offset=start)
            rows = [np.frombuffer(raw[i * stride:i * stride + width * dtype.itemsize].tobytes(), dtype=dtype)
                    for i in range(count)]
            arr = np.stack(rows)
        else:
            arr = np.frombuffer(self._bin, dtype=dtype, count=count * width, offset=start).reshape(count, width)
        return arr if width > 1 else arr[:, 0]

    @property
    def n_keys(self):
        return self.deform.shape[0]

    def play(self, key):
        """Linear blend skinning of keyframe ``key`` from the file's numbers: (n_v, 3) float64."""
        p = self.rest.copy()
        if len(self.morphs):
            p += np.tensordot(self.morph_weights[key], self.morphs, axes=1)
        out = np.zeros_like(p)
        d = self.deform[key]
        for s in range(self.joints.shape[1]):
            w = self.weights[:, s]
            m = d[self.joints[:, s]]
            out += w[:, None] * (np.einsum("vab,vb->va", m[:, :3, :3], p) + m[:, :3, 3])
        return out


def e_rms(frames, played, bind_pose=0):
    """E_RMS as ``posemfa rig-report`` measures it (Kavan et al. 2010): 1000 ||V - V'||_F / sqrt(3 n_v n_poses)
    divided by the bounding-box diagonal of the pose the rig is bound in, as given."""
    frames = np.asarray(frames, dtype=np.float64)
    played = np.asarray(played, dtype=np.float64)
    b = frames[bind_pose]
    diagonal = np.linalg.norm(b.max(axis=0) - b.min(axis=0))
    return 1000.0 * np.sqrt(np.sum((frames - played) ** 2) / frames[..., 0].size / 3.0) / diagonal
