//! FBX import (binary FBX 7.x, as Maya, 3ds Max, MotionBuilder, Blender and character sites write it): the
//! poses of one animated mesh. The node tree is parsed by [`super::fbx_tree`] (every length checked before
//! anything is allocated); this module reads the objects and their connections.
//!
//! Which mesh: the animated mesh model with the most control points, or the one named by [`Options::mesh`]
//! (`--object NAME`: the model's name, its geometry's name, or its index in file order). Its polygons are
//! fan-triangulated as the OBJ reader does (the same triangles in every frame).
//!
//! Which poses ([`Options::source`] to choose):
//! - **animation**: an animation stack that moves the mesh, sampled at the file's frame rate (GlobalSettings
//!   TimeMode / CustomFrameRate) over the stack's span (LocalStart..LocalStop, else ReferenceStart..Stop,
//!   else the keys), or at [`Options::frames`] evenly spaced times. Shape keys / blend shapes:
//!   BlendShapeChannel `DeformPercent` (0-100) times the channel's first Shape's offsets. Skins: every Cluster's
//!   weights, its bind matrix (`Transform`: mesh to bone at bind time) and its bone's global transform at the time
//!   (`Lcl Translation / Rotation / Scaling` curves, with RotationOrder, pre- and post-rotation, pivots and
//!   offsets), linear blend skinning; shapes are applied first. A mesh that is not skinned follows its own
//!   model's (animated) global transform, with its geometric transform. Curves are evaluated with constant or
//!   linear interpolation between keys (cubic keys are read as linear between them: exporters that bake write a
//!   key per frame, where the value is exact).
//! - **morph targets** (no animation): the base mesh and then each blend shape channel at 100 %.
//!
//! The file's axis system (GlobalSettings UpAxis / FrontAxis / CoordAxis and their signs) is turned into
//! Y up, Z front, X right (glTF's), and its UnitScaleFactor (centimetres per unit) into metres; the source
//! says which. Control points that are exact duplicates in the first pose are welded, as the glTF reader does.
//!
//! Errors name the file, the node or object at fault and say what to do.

use super::fbx_tree::{self, Node, Prop};
use super::gltf::{Gltf, Options, PoseSource, Weld};
use super::Mesh;
use crate::error::{Error, Result};
use nalgebra::{Matrix4, Point3, Rotation3, Vector3};
use std::collections::{HashMap, HashSet};

type DVec3 = Vector3<f64>;
type DMat4 = Matrix4<f64>;

/// Nodes whose arrays the reader does not use: not inflated (normals, UVs, colours, edges, materials, ...).
const UNUSED_ARRAYS: &[&str] = &[
    "Normals",
    "NormalsW",
    "NormalsIndex",
    "Binormals",
    "BinormalsW",
    "BinormalsIndex",
    "Tangents",
    "TangentsW",
    "TangentsIndex",
    "UV",
    "UVIndex",
    "Colors",
    "ColorIndex",
    "Edges",
    "Smoothing",
    "Materials",
    "FullWeights",
    "Visibility",
    "Hole",
    "EdgeCrease",
    "VertexCrease",
];

/// FBX time units per second.
const KTIME_PER_SECOND: f64 = 46_186_158_000.0;

fn err(file: &str, message: String) -> Error {
    Error::Mesh { format: crate::error::Format::Fbx, file: file.to_string(), line: 0, message }
}

/// The object's name: the part of "Name\0\x01Class" before the separator.
fn object_name(p: Option<&Prop>) -> String {
    let s = p.and_then(Prop::as_str).unwrap_or("");
    s.split("\u{0}\u{1}").next().unwrap_or("").to_string()
}

struct Object<'a> {
    id: i64,
    /// The node name: Geometry, Model, Deformer, AnimationCurve, ...
    class: &'a str,
    /// Mesh, Shape, Skin, Cluster, BlendShape, BlendShapeChannel, LimbNode, Null, ...
    sub: String,
    name: String,
    node: &'a Node,
}

/// The objects and connections of a file.
struct Doc<'a> {
    file: &'a str,
    objects: HashMap<i64, Object<'a>>,
    /// Objects in file order.
    order: Vec<i64>,
    /// parent -> (child, property) for every connection.
    children: HashMap<i64, Vec<(i64, Option<String>)>>,
    /// child -> (parent, property).
    parents: HashMap<i64, Vec<(i64, Option<String>)>>,
}

impl<'a> Doc<'a> {
    fn new(file: &'a str, tree: &'a fbx_tree::Tree) -> Doc<'a> {
        let mut objects = HashMap::new();
        let mut order = Vec::new();
        if let Some(objs) = tree.node("Objects") {
            for n in &objs.children {
                let Some(id) = n.props.first().and_then(Prop::as_i64) else { continue };
                let sub = n.props.get(2).and_then(Prop::as_str).unwrap_or("").to_string();
                if objects
                    .insert(id, Object { id, class: &n.name, sub, name: object_name(n.props.get(1)), node: n })
                    .is_none()
                {
                    order.push(id);
                }
            }
        }
        let mut children: HashMap<i64, Vec<(i64, Option<String>)>> = HashMap::new();
        let mut parents: HashMap<i64, Vec<(i64, Option<String>)>> = HashMap::new();
        if let Some(conns) = tree.node("Connections") {
            for c in conns.children_named("C") {
                let (Some(child), Some(parent)) =
                    (c.props.get(1).and_then(Prop::as_i64), c.props.get(2).and_then(Prop::as_i64))
                else {
                    continue;
                };
                let prop = c.props.get(3).and_then(Prop::as_str).map(str::to_string);
                children.entry(parent).or_default().push((child, prop.clone()));
                parents.entry(child).or_default().push((parent, prop));
            }
        }
        Doc { file, objects, order, children, parents }
    }

    fn get(&self, id: i64) -> Option<&Object<'a>> {
        self.objects.get(&id)
    }

    /// Children objects of `id` of the given class (and subclass, when given), in connection order.
    fn kids(&self, id: i64, class: &str, sub: Option<&str>) -> Vec<&Object<'a>> {
        self.children
            .get(&id)
            .into_iter()
            .flatten()
            .filter_map(|(c, _)| self.get(*c))
            .filter(|o| o.class == class && sub.is_none_or(|s| o.sub == s))
            .collect()
    }

    /// The parent model of a model (None at the root).
    fn parent_model(&self, id: i64) -> Option<i64> {
        self.parents
            .get(&id)
            .into_iter()
            .flatten()
            .find(|(p, prop)| prop.is_none() && self.get(*p).is_some_and(|o| o.class == "Model"))
            .map(|(p, _)| *p)
    }

    fn array(&self, o: &Object<'a>, child: &str) -> Option<&'a Prop> {
        o.node.child(child).and_then(|c| c.props.first())
    }

    /// A numeric array, borrowed when it is stored as f64 (no copy of the large ones).
    fn f64s(&self, o: &Object<'a>, child: &str) -> Result<Option<std::borrow::Cow<'a, [f64]>>> {
        match self.array(o, child) {
            None => Ok(None),
            Some(Prop::F64s(v)) => Ok(Some(std::borrow::Cow::Borrowed(v.as_slice()))),
            Some(p) => p.to_f64s().map(|v| Some(std::borrow::Cow::Owned(v))).ok_or_else(|| {
                err(
                    self.file,
                    format!(
                        "{} '{}' (id {}): {child} is not a numeric array; the file is damaged: export it again",
                        o.class, o.name, o.id
                    ),
                )
            }),
        }
    }

    fn i64s(&self, o: &Object<'a>, child: &str) -> Result<Option<Vec<i64>>> {
        match self.array(o, child) {
            None => Ok(None),
            Some(p) => p.to_i64s().map(Some).ok_or_else(|| {
                err(
                    self.file,
                    format!(
                        "{} '{}' (id {}): {child} is not an integer array; the file is damaged: export it again",
                        o.class, o.name, o.id
                    ),
                )
            }),
        }
    }
}

/// The values of property `name` in a node's Properties70.
fn p70<'a>(node: &'a Node, name: &str) -> Option<&'a [Prop]> {
    node.child("Properties70")?
        .children_named("P")
        .find(|p| p.props.first().and_then(Prop::as_str) == Some(name))
        .map(|p| p.props.get(4..).unwrap_or(&[]))
}

fn p70_f64(node: &Node, name: &str) -> Option<f64> {
    p70(node, name).and_then(|v| v.first()).and_then(Prop::as_f64)
}

fn p70_i64(node: &Node, name: &str) -> Option<i64> {
    p70(node, name).and_then(|v| v.first()).and_then(Prop::as_i64)
}

fn p70_vec3(node: &Node, name: &str, default: f64) -> DVec3 {
    match p70(node, name) {
        Some([a, b, c, ..]) => {
            DVec3::new(a.as_f64().unwrap_or(default), b.as_f64().unwrap_or(default), c.as_f64().unwrap_or(default))
        }
        _ => DVec3::repeat(default),
    }
}

/// A rotation from Euler angles in degrees, in FBX's rotation order (0 = XYZ: X applied first).
fn euler(deg: DVec3, order: i64) -> DMat4 {
    let r = deg.map(f64::to_radians);
    let x = Rotation3::from_axis_angle(&Vector3::x_axis(), r.x);
    let y = Rotation3::from_axis_angle(&Vector3::y_axis(), r.y);
    let z = Rotation3::from_axis_angle(&Vector3::z_axis(), r.z);
    let m = match order {
        1 => y * z * x, // XZY
        2 => x * z * y, // YZX
        3 => z * x * y, // YXZ
        4 => y * x * z, // ZXY
        5 => x * y * z, // ZYX
        _ => z * y * x, // XYZ (and spheric XYZ)
    };
    m.to_homogeneous()
}

fn translation(v: DVec3) -> DMat4 {
    Matrix4::new_translation(&v)
}

fn inverse(m: &DMat4) -> DMat4 {
    m.try_inverse().unwrap_or_else(DMat4::identity)
}

/// One animation curve: key times (FBX time) and values.
struct Curve {
    times: Vec<i64>,
    values: Vec<f64>,
    /// Per key: constant interpolation to the next key.
    constant: Vec<bool>,
}

impl Curve {
    fn eval(&self, t: i64) -> Option<f64> {
        let n = self.times.len().min(self.values.len());
        if n == 0 {
            return None;
        }
        let k = self.times[..n].partition_point(|&x| x <= t);
        if k == 0 {
            return self.values.first().copied();
        }
        if k >= n {
            return self.values.get(n - 1).copied();
        }
        let (t0, t1) = (self.times[k - 1], self.times[k]);
        let (v0, v1) = (self.values[k - 1], self.values[k]);
        if self.constant.get(k - 1).copied().unwrap_or(false) || t1 <= t0 {
            return Some(v0);
        }
        let u = (t - t0) as f64 / (t1 - t0) as f64;
        Some(v0 + (v1 - v0) * u)
    }
}

/// The animated channels of one stack: (object id, property) -> curve node (id) with its curves by channel.
struct Anim {
    /// (target object, property name) -> ([channel name, curve], defaults by channel name)
    channels: HashMap<(i64, String), (Vec<(String, Curve)>, HashMap<String, f64>)>,
}

impl Anim {
    fn value(&self, target: i64, prop: &str, channel: &str, t: i64) -> Option<f64> {
        let (curves, defaults) = self.channels.get(&(target, prop.to_string()))?;
        let want = format!("d|{channel}");
        curves.iter().find(|(c, _)| *c == want).and_then(|(_, c)| c.eval(t)).or_else(|| defaults.get(&want).copied())
    }
    fn vec3(&self, target: i64, prop: &str, t: i64, rest: DVec3) -> DVec3 {
        DVec3::new(
            self.value(target, prop, "X", t).unwrap_or(rest.x),
            self.value(target, prop, "Y", t).unwrap_or(rest.y),
            self.value(target, prop, "Z", t).unwrap_or(rest.z),
        )
    }
    fn moves(&self, target: i64) -> bool {
        self.channels.keys().any(|(o, _)| *o == target)
    }
    fn key_range(&self) -> Option<(i64, i64)> {
        let all = self.channels.values().flat_map(|(cs, _)| cs.iter().flat_map(|(_, c)| c.times.iter().copied()));
        let (mut lo, mut hi) = (i64::MAX, i64::MIN);
        for t in all {
            lo = lo.min(t);
            hi = hi.max(t);
        }
        (lo <= hi).then_some((lo, hi))
    }
}

fn read_anim(doc: &Doc, stack: &Object) -> Result<Anim> {
    let mut channels = HashMap::new();
    for layer in doc.kids(stack.id, "AnimationLayer", None) {
        for cn in doc.kids(layer.id, "AnimationCurveNode", None) {
            let targets: Vec<(i64, String)> = doc
                .parents
                .get(&cn.id)
                .into_iter()
                .flatten()
                .filter_map(|(p, prop)| prop.as_ref().map(|pr| (*p, pr.clone())))
                .collect();
            if targets.is_empty() {
                continue;
            }
            let mut curves = Vec::new();
            for (c, prop) in doc.children.get(&cn.id).into_iter().flatten() {
                let (Some(o), Some(prop)) = (doc.get(*c), prop) else { continue };
                if o.class != "AnimationCurve" {
                    continue;
                }
                let times = doc.i64s(o, "KeyTime")?.unwrap_or_default();
                let values = doc.f64s(o, "KeyValueFloat")?.map(|v| v.into_owned()).unwrap_or_default();
                if times.len() != values.len() {
                    return Err(err(
                        doc.file,
                        format!(
                            "AnimationCurve {} has {} key times but {} key values; the file is damaged: export it again",
                            o.id,
                            times.len(),
                            values.len()
                        ),
                    ));
                }
                if times.windows(2).any(|w| w[1] < w[0]) {
                    return Err(err(
                        doc.file,
                        format!(
                            "the key times of AnimationCurve {} are not in order; the file is damaged: export it again",
                            o.id
                        ),
                    ));
                }
                // Interpolation per key: KeyAttrFlags (bit 1: constant) shared by KeyAttrRefCount keys each.
                let flags = doc.i64s(o, "KeyAttrFlags")?.unwrap_or_default();
                let counts = doc.i64s(o, "KeyAttrRefCount")?.unwrap_or_default();
                let mut constant = Vec::with_capacity(times.len());
                for (f, &c) in flags.iter().zip(&counts) {
                    let c = usize::try_from(c).unwrap_or(0).min(times.len() - constant.len().min(times.len()));
                    constant.extend(std::iter::repeat(f & 2 != 0).take(c));
                }
                curves.push((prop.clone(), Curve { times, values, constant }));
            }
            let mut defaults = HashMap::new();
            if let Some(p) = cn.node.child("Properties70") {
                for q in p.children_named("P") {
                    if let (Some(n), Some(v)) =
                        (q.props.first().and_then(Prop::as_str), q.props.get(4).and_then(Prop::as_f64))
                    {
                        defaults.insert(n.to_string(), v);
                    }
                }
            }
            for (target, prop) in targets {
                let curves_copy = curves
                    .iter()
                    .map(|(n, c)| {
                        (
                            n.clone(),
                            Curve { times: c.times.clone(), values: c.values.clone(), constant: c.constant.clone() },
                        )
                    })
                    .collect();
                channels.insert((target, prop), (curves_copy, defaults.clone()));
            }
        }
    }
    Ok(Anim { channels })
}

/// A model's local transform at time `t` (rest values where nothing is animated).
fn local_matrix(doc: &Doc, anim: Option<&Anim>, model: i64, t: i64) -> DMat4 {
    let Some(o) = doc.get(model) else { return DMat4::identity() };
    let n = o.node;
    let rest_t = p70_vec3(n, "Lcl Translation", 0.0);
    let rest_r = p70_vec3(n, "Lcl Rotation", 0.0);
    let rest_s = p70_vec3(n, "Lcl Scaling", 1.0);
    let (tr, rot, sc) = match anim {
        Some(a) => (
            a.vec3(model, "Lcl Translation", t, rest_t),
            a.vec3(model, "Lcl Rotation", t, rest_r),
            a.vec3(model, "Lcl Scaling", t, rest_s),
        ),
        None => (rest_t, rest_r, rest_s),
    };
    let order = p70_i64(n, "RotationOrder").unwrap_or(0);
    let active = p70_i64(n, "RotationActive").unwrap_or(1) != 0;
    let pre = if active { euler(p70_vec3(n, "PreRotation", 0.0), 0) } else { DMat4::identity() };
    let post = if active { euler(p70_vec3(n, "PostRotation", 0.0), 0) } else { DMat4::identity() };
    let r_off = translation(p70_vec3(n, "RotationOffset", 0.0));
    let r_piv = translation(p70_vec3(n, "RotationPivot", 0.0));
    let s_off = translation(p70_vec3(n, "ScalingOffset", 0.0));
    let s_piv = translation(p70_vec3(n, "ScalingPivot", 0.0));
    translation(tr)
        * r_off
        * r_piv
        * pre
        * euler(rot, order)
        * inverse(&post)
        * inverse(&r_piv)
        * s_off
        * s_piv
        * Matrix4::new_nonuniform_scaling(&sc)
        * inverse(&s_piv)
}

/// A model's global transform at time `t`, memoised in `cache` (a cycle is cut where it closes).
fn global_matrix(doc: &Doc, anim: Option<&Anim>, model: i64, t: i64, cache: &mut HashMap<i64, DMat4>) -> DMat4 {
    if let Some(m) = cache.get(&model) {
        return *m;
    }
    let mut chain = vec![model];
    let mut seen: HashSet<i64> = HashSet::from([model]);
    let mut cur = model;
    while let Some(p) = doc.parent_model(cur) {
        if cache.contains_key(&p) || !seen.insert(p) {
            if cache.contains_key(&p) {
                chain.push(p);
            }
            break;
        }
        chain.push(p);
        cur = p;
    }
    let mut acc: Option<DMat4> = None;
    for &m in chain.iter().rev() {
        let g = match cache.get(&m) {
            Some(g) => *g,
            None => {
                let l = local_matrix(doc, anim, m, t);
                let g = acc.map_or(l, |a| a * l);
                cache.insert(m, g);
                g
            }
        };
        acc = Some(g);
    }
    acc.unwrap_or_else(DMat4::identity)
}

fn geometric(node: &Node) -> DMat4 {
    translation(p70_vec3(node, "GeometricTranslation", 0.0))
        * euler(p70_vec3(node, "GeometricRotation", 0.0), 0)
        * Matrix4::new_nonuniform_scaling(&p70_vec3(node, "GeometricScaling", 1.0))
}

fn matrix16(doc: &Doc, o: &Object, child: &str) -> Result<Option<DMat4>> {
    match doc.f64s(o, child)? {
        None => Ok(None),
        Some(v) if v.len() == 16 => Ok(Some(DMat4::from_column_slice(&v))),
        Some(v) => Err(err(
            doc.file,
            format!(
                "{} '{}' (id {}): {child} has {} numbers, not 16; the file is damaged: export it again",
                o.class,
                o.name,
                o.id,
                v.len()
            ),
        )),
    }
}

/// A mesh model and its geometry, read.
struct MeshModel {
    model: i64,
    geometry: i64,
    positions: Vec<DVec3>,
    faces: Vec<[u32; 3]>,
}

fn read_geometry(doc: &Doc, model: &Object, geom: &Object) -> Result<MeshModel> {
    let what = format!("Geometry '{}' (id {}) of model '{}'", geom.name, geom.id, model.name);
    let v = doc
        .f64s(geom, "Vertices")?
        .ok_or_else(|| err(doc.file, format!("{what} has no Vertices; export the mesh with its geometry")))?;
    if v.len() % 3 != 0 {
        return Err(err(
            doc.file,
            format!(
                "{what}: Vertices holds {} numbers, not a multiple of 3; the file is damaged: export it again",
                v.len()
            ),
        ));
    }
    let n = v.len() / 3;
    if n > u32::MAX as usize {
        return Err(err(doc.file, format!("{what} has more than 4294967295 control points")));
    }
    let positions: Vec<DVec3> = v.chunks_exact(3).map(|c| DVec3::new(c[0], c[1], c[2])).collect();
    let pvi = doc.i64s(geom, "PolygonVertexIndex")?.ok_or_else(|| {
        err(doc.file, format!("{what} has no PolygonVertexIndex (no polygons); posemfa needs a polygon mesh"))
    })?;
    let mut faces = Vec::with_capacity(pvi.len());
    let mut corners: Vec<u32> = Vec::new();
    for (k, &raw) in pvi.iter().enumerate() {
        let (idx, last) = if raw < 0 { (!raw, true) } else { (raw, false) };
        if idx as u64 >= n as u64 {
            return Err(err(
                doc.file,
                format!("{what}: PolygonVertexIndex[{k}] names control point {idx}, but there are {n}; the file is damaged: export it again"),
            ));
        }
        corners.push(idx as u32);
        if last {
            if let Some((&first, rest)) = corners.split_first() {
                for w in rest.windows(2) {
                    faces.push([first, w[0], w[1]]);
                }
            }
            corners.clear();
        }
    }
    if faces.is_empty() {
        return Err(err(
            doc.file,
            format!("{what} has no polygons with 3 or more corners; posemfa needs a polygon mesh"),
        ));
    }
    Ok(MeshModel { model: model.id, geometry: geom.id, positions, faces })
}

/// A blend shape channel: its id and the (sparse) offsets of its first shape.
struct Channel<'a> {
    id: i64,
    name: String,
    rest_percent: f64,
    /// The control points the shape moves (each checked against the mesh) ...
    points: Vec<u32>,
    /// ... and their offsets, 3 numbers each (the file's array, borrowed when it holds doubles).
    offsets: std::borrow::Cow<'a, [f64]>,
}

impl Channel<'_> {
    /// Adds the offsets times `w` to the control points `p`.
    fn add_to(&self, p: &mut [[f64; 3]], w: f64) {
        for (&i, d) in self.points.iter().zip(self.offsets.chunks_exact(3)) {
            if let Some(v) = p.get_mut(i as usize) {
                for c in 0..3 {
                    v[c] += d[c] * w;
                }
            }
        }
    }
}

fn read_channels<'a>(doc: &Doc<'a>, mm: &MeshModel) -> Result<Vec<Channel<'a>>> {
    let mut out = Vec::new();
    let n = mm.positions.len();
    for bs in doc.kids(mm.geometry, "Deformer", Some("BlendShape")) {
        for ch in doc.kids(bs.id, "Deformer", Some("BlendShapeChannel")) {
            let Some(shape) = doc.kids(ch.id, "Geometry", Some("Shape")).into_iter().next() else { continue };
            let what = format!("Shape '{}' (id {}) of blend shape channel '{}'", shape.name, shape.id, ch.name);
            let idx = doc.i64s(shape, "Indexes")?.unwrap_or_default();
            let v = doc.f64s(shape, "Vertices")?.unwrap_or_default();
            if v.len() != 3 * idx.len() {
                return Err(err(
                    doc.file,
                    format!("{what} has {} indexes but {} numbers of offsets (3 per index); the file is damaged: export it again", idx.len(), v.len()),
                ));
            }
            let mut points = Vec::with_capacity(idx.len());
            for (k, &i) in idx.iter().enumerate() {
                if i < 0 || i as u64 >= n as u64 {
                    return Err(err(
                        doc.file,
                        format!("{what}: Indexes[{k}] names control point {i}, but the mesh has {n}; the file is damaged: export it again"),
                    ));
                }
                points.push(i as u32);
            }
            let rest_percent = ch
                .node
                .child_prop("DeformPercent")
                .and_then(Prop::as_f64)
                .or_else(|| p70_f64(ch.node, "DeformPercent"))
                .unwrap_or(0.0);
            out.push(Channel { id: ch.id, name: ch.name.clone(), rest_percent, points, offsets: v });
        }
    }
    Ok(out)
}

/// A skin cluster: its bone model, bind matrix (mesh to bone space at bind time) and weights.
struct Cluster {
    bone: i64,
    /// The file's Transform (mesh to bone at bind time) times the mesh's geometric transform.
    bind: DMat4,
    weights: Vec<(usize, f64)>,
}

fn read_clusters(doc: &Doc, mm: &MeshModel, geo: &DMat4) -> Result<Vec<Cluster>> {
    let mut out = Vec::new();
    let n = mm.positions.len();
    for skin in doc.kids(mm.geometry, "Deformer", Some("Skin")) {
        for cl in doc.kids(skin.id, "Deformer", Some("Cluster")) {
            let what = format!("Cluster '{}' (id {}) of skin '{}'", cl.name, cl.id, skin.name);
            let idx = doc.i64s(cl, "Indexes")?.unwrap_or_default();
            let w = doc.f64s(cl, "Weights")?.unwrap_or_default();
            if idx.len() != w.len() {
                return Err(err(
                    doc.file,
                    format!(
                        "{what} has {} indexes but {} weights; the file is damaged: export it again",
                        idx.len(),
                        w.len()
                    ),
                ));
            }
            let Some(bone) = doc.kids(cl.id, "Model", None).first().map(|b| b.id) else {
                if idx.is_empty() {
                    continue;
                }
                return Err(err(
                    doc.file,
                    format!(
                        "{what} weights {} control points but is linked to no bone; export the skin with its skeleton",
                        idx.len()
                    ),
                ));
            };
            // `Transform` in the file is the mesh-to-bone matrix at bind time (TransformLink^-1 times the mesh's
            // bind matrix, as the FBX SDK writes it); `TransformLink` (the bone's bind matrix) is not needed.
            let transform = matrix16(doc, cl, "Transform")?.ok_or_else(|| {
                err(
                    doc.file,
                    format!(
                        "{what} has no Transform (its bind matrix), so its rest pose is unknown; export the skin again"
                    ),
                )
            })?;
            let mut weights = Vec::with_capacity(idx.len());
            for (k, (&i, &wt)) in idx.iter().zip(w.iter()).enumerate() {
                if i < 0 || i as u64 >= n as u64 {
                    return Err(err(
                        doc.file,
                        format!("{what}: Indexes[{k}] names control point {i}, but the mesh has {n}; the file is damaged: export it again"),
                    ));
                }
                weights.push((i as usize, wt));
            }
            out.push(Cluster { bone, bind: transform * geo, weights });
        }
    }
    Ok(out)
}

/// The file's axes and unit: the matrix to Y up / Z front / X right in metres, and a description.
fn axis_system(tree: &fbx_tree::Tree) -> (DMat4, String) {
    let gs = tree.node("GlobalSettings");
    let int = |name: &str, default: i64| gs.and_then(|g| p70_i64(g, name)).unwrap_or(default);
    let (up, up_s) = (int("UpAxis", 1), int("UpAxisSign", 1));
    let (front, front_s) = (int("FrontAxis", 2), int("FrontAxisSign", 1));
    let (coord, coord_s) = (int("CoordAxis", 0), int("CoordAxisSign", 1));
    let unit = gs.and_then(|g| p70_f64(g, "UnitScaleFactor")).filter(|u| u.is_finite() && *u > 0.0).unwrap_or(1.0);
    let axis = |a: i64, s: i64| {
        let mut v = DVec3::zeros();
        if (0..3).contains(&a) {
            v[a as usize] = if s < 0 { -1.0 } else { 1.0 };
        }
        v
    };
    let (c, u, f) = (axis(coord, coord_s), axis(up, up_s), axis(front, front_s));
    let distinct =
        [coord, up, front].iter().all(|a| (0..3).contains(a)) && coord != up && up != front && coord != front;
    let rows = if distinct {
        nalgebra::Matrix3::from_rows(&[c.transpose(), u.transpose(), f.transpose()])
    } else {
        nalgebra::Matrix3::identity()
    };
    let scale = unit / 100.0;
    let m = (rows * scale).to_homogeneous();
    let names = ["X", "Y", "Z"];
    let sign = |s: i64| if s < 0 { "-" } else { "+" };
    let axes = if !distinct {
        "axis system not stated, taken as Y up".to_string()
    } else if up == 1 && up_s >= 0 && front == 2 && front_s >= 0 && coord == 0 && coord_s >= 0 {
        "Y up".to_string()
    } else {
        format!(
            "{}{} up, {}{} front, {}{} right turned to +Y up{}",
            sign(up_s),
            names[up as usize],
            sign(front_s),
            names[front as usize],
            sign(coord_s),
            names[coord as usize],
            if rows.determinant() < 0.0 { " (the file's axes are left-handed: mirrored)" } else { "" }
        )
    };
    let units = if unit == 100.0 {
        "metres (UnitScaleFactor 100)".to_string()
    } else if unit == 1.0 {
        "centimetres (UnitScaleFactor 1) turned to metres".to_string()
    } else {
        format!("UnitScaleFactor {unit} (cm per unit) turned to metres")
    };
    (m, format!("{axes}, {units}"))
}

/// The file's frame rate (GlobalSettings TimeMode, CustomFrameRate).
fn frame_rate(tree: &fbx_tree::Tree) -> f64 {
    let gs = tree.node("GlobalSettings");
    let mode = gs.and_then(|g| p70_i64(g, "TimeMode")).unwrap_or(0);
    let custom = gs.and_then(|g| p70_f64(g, "CustomFrameRate")).filter(|f| f.is_finite() && *f > 0.0 && *f <= 1000.0);
    match mode {
        1 => 120.0,
        2 => 100.0,
        3 => 60.0,
        4 => 50.0,
        5 => 48.0,
        6 | 7 => 30.0,
        8 | 9 => 30000.0 / 1001.0,
        10 => 25.0,
        11 => 24.0,
        12 => 1000.0,
        13 => 24000.0 / 1001.0,
        15 => 96.0,
        16 => 72.0,
        17 => 60000.0 / 1001.0,
        18 => 120000.0 / 1001.0,
        _ => custom.unwrap_or(24.0),
    }
}

/// Reads the poses of one mesh of a binary FBX file.
pub fn read(file: &str, bytes: &[u8], options: &Options) -> Result<Gltf> {
    let budget = crate::memory::budget_bytes()?;
    let tree = fbx_tree::parse_skipping(file, bytes, budget, UNUSED_ARRAYS)?;
    let (weld, poses, description) = poses(file, &tree, options, budget)?;
    // The file's decoded arrays are freed before every pose gets its faces: the allocator can hand their
    // memory on instead of new pages.
    drop(tree);
    Ok(weld.finish(file, poses, description))
}

/// The poses of the chosen mesh (its kept points), its weld, and the description of what was read.
fn poses(
    file: &str,
    tree: &fbx_tree::Tree,
    options: &Options,
    budget: u64,
) -> Result<(Weld, Vec<(String, Vec<[f64; 3]>)>, String)> {
    let doc = Doc::new(file, tree);

    // Mesh models, with their geometry.
    let mut candidates: Vec<(&Object, &Object)> = Vec::new();
    for &id in &doc.order {
        let Some(o) = doc.get(id) else { continue };
        if o.class == "Model" && o.sub == "Mesh" {
            if let Some(g) = doc.kids(o.id, "Geometry", Some("Mesh")).into_iter().next() {
                candidates.push((o, g));
            }
        }
    }
    if candidates.is_empty() {
        return Err(err(
            file,
            "the file holds no mesh (no Model of type Mesh with a Geometry); export the character with its mesh".into(),
        ));
    }
    let count = |g: &Object| match doc.array(g, "Vertices") {
        Some(Prop::F64s(v)) => v.len() / 3,
        Some(Prop::F32s(v)) => v.len() / 3,
        _ => 0,
    };
    let stacks: Vec<&Object> =
        doc.order.iter().filter_map(|id| doc.get(*id)).filter(|o| o.class == "AnimationStack").collect();
    let anims: Vec<(&Object, Anim)> =
        stacks.iter().map(|s| read_anim(&doc, s).map(|a| (*s, a))).collect::<Result<_>>()?;

    // What moves a mesh model: its own transform or an ancestor's, its blend shape channels, its skin's bones
    // (or their ancestors).
    let movers = |model: &Object, geom: &Object| -> Vec<i64> {
        let mut ids = Vec::new();
        let chain = |start: i64, ids: &mut Vec<i64>| {
            let mut cur = Some(start);
            let mut seen = HashSet::new();
            while let Some(c) = cur {
                if !seen.insert(c) {
                    break;
                }
                ids.push(c);
                cur = doc.parent_model(c);
            }
        };
        chain(model.id, &mut ids);
        for bs in doc.kids(geom.id, "Deformer", Some("BlendShape")) {
            ids.extend(doc.kids(bs.id, "Deformer", Some("BlendShapeChannel")).iter().map(|c| c.id));
        }
        for skin in doc.kids(geom.id, "Deformer", Some("Skin")) {
            for cl in doc.kids(skin.id, "Deformer", Some("Cluster")) {
                for b in doc.kids(cl.id, "Model", None) {
                    chain(b.id, &mut ids);
                }
            }
        }
        ids
    };
    let is_animated = |model: &Object, geom: &Object| {
        let ids = movers(model, geom);
        anims.iter().any(|(_, a)| ids.iter().any(|&i| a.moves(i)))
    };
    let label = |o: &Object| if o.name.is_empty() { format!("model {}", o.id) } else { o.name.clone() };
    let (model, geom) = match &options.mesh {
        Some(w) => candidates
            .iter()
            .enumerate()
            .find(|(i, (m, g))| m.name == *w || g.name == *w || i.to_string() == *w)
            .map(|(_, c)| *c)
            .ok_or_else(|| {
                let names: Vec<String> = candidates.iter().map(|(m, _)| label(m)).collect();
                err(file, format!("no mesh is called or numbered `{w}`; the file has {}", names.join(", ")))
            })?,
        None => {
            let animated: Vec<&(&Object, &Object)> = candidates.iter().filter(|(m, g)| is_animated(m, g)).collect();
            let pool: Vec<&(&Object, &Object)> =
                if animated.is_empty() { candidates.iter().collect() } else { animated };
            let mut best = pool[0];
            for c in &pool {
                if count(c.1) > count(best.1) {
                    best = c;
                }
            }
            *best
        }
    };
    let mname = label(model);
    let mm = read_geometry(&doc, model, geom)?;
    let n_file = mm.positions.len();
    let geo = geometric(model.node);
    let channels = read_channels(&doc, &mm)?;
    let clusters = read_clusters(&doc, &mm, &geo)?;
    let (axes, axes_note) = axis_system(tree);
    let fps = frame_rate(tree);

    // Influences per control point.
    let mut influences: Vec<Vec<(usize, f64)>> = vec![Vec::new(); if clusters.is_empty() { 0 } else { n_file }];
    for (c, cl) in clusters.iter().enumerate() {
        for &(i, w) in &cl.weights {
            if w != 0.0 {
                if let Some(slot) = influences.get_mut(i) {
                    slot.push((c, w));
                }
            }
        }
    }

    let ids = movers(model, geom);
    let moving: Vec<&(&Object, Anim)> = anims.iter().filter(|(_, a)| ids.iter().any(|&i| a.moves(i))).collect();
    let use_animation = match options.source {
        PoseSource::Animation => true,
        PoseSource::MorphTargets => false,
        PoseSource::Auto => !moving.is_empty() || options.animation.is_some(),
    };

    // Every pose of the file's control points: the base, the blend shapes at their percents, then the mesh's
    // transform (or its skin); welded (`Weld::keep`) and checked as it is made.
    let weld = Weld::new(&mm.positions, &mm.faces);
    let base: Vec<[f64; 3]> = mm.positions.iter().map(|v| [v.x, v.y, v.z]).collect();
    let mut spare: Vec<[f64; 3]> = Vec::new();
    // Returns the pose's kept points and whether all its points (kept or not) are finite numbers.
    let mut pose_at = |anim: Option<&Anim>, t: i64, percents: &[f64]| -> (Vec<[f64; 3]>, bool) {
        // The weld keeps every point (the usual case): the pose is made in the vector it is returned in;
        // else in `spare`, reused from pose to pose, and its kept points copied out.
        let mut p = if weld.is_identity() { Vec::with_capacity(n_file) } else { std::mem::take(&mut spare) };
        p.clear();
        p.extend_from_slice(&base);
        for (ch, &pc) in channels.iter().zip(percents) {
            if pc != 0.0 {
                ch.add_to(&mut p, pc / 100.0);
            }
        }
        let mut cache = HashMap::new();
        let mesh_global = global_matrix(&doc, anim, mm.model, t, &mut cache) * geo;
        let rigid = Affine::new(&(axes * mesh_global));
        let mut finite = true;
        if clusters.is_empty() {
            for v in &mut p {
                *v = rigid.apply(v);
                finite &= v[0].is_finite() & v[1].is_finite() & v[2].is_finite();
            }
        } else {
            let mats: Vec<Affine> = clusters
                .iter()
                .map(|cl| Affine::new(&(axes * global_matrix(&doc, anim, cl.bone, t, &mut cache) * cl.bind)))
                .collect();
            for (v, infl) in p.iter_mut().zip(&influences) {
                let total: f64 = infl.iter().map(|(_, w)| w).sum();
                *v = if infl.is_empty() || total <= 0.0 {
                    rigid.apply(v)
                } else {
                    let at = DVec3::from(*v);
                    let s: DVec3 =
                        infl.iter().map(|&(c, w)| DVec3::from(mats[c].apply(&at.into())) * (w / total)).sum();
                    s.into()
                };
                finite &= v[0].is_finite() & v[1].is_finite() & v[2].is_finite();
            }
        }
        if weld.is_identity() {
            return (p, finite);
        }
        let kept = weld.keep(&p);
        spare = p;
        (kept, finite)
    };

    let mut poses: Vec<(String, Vec<[f64; 3]>)> = Vec::new();
    // A pose with a coordinate that is not a finite number is refused (every control point, welded or not).
    let mut push = |name: String, (p, finite): (Vec<[f64; 3]>, bool)| -> Result<()> {
        if !finite {
            return Err(err(
                file,
                format!("{mname} at {name} has coordinates that are not finite numbers (a transform, bind matrix or curve holds NaN or infinity); the file is damaged: export it again"),
            ));
        }
        poses.push((name, p));
        Ok(())
    };
    let description;
    if use_animation {
        let chosen = match &options.animation {
            Some(w) => anims
                .iter()
                .enumerate()
                .find(|(i, (s, _))| s.name == *w || i.to_string() == *w)
                .map(|(_, a)| a)
                .ok_or_else(|| {
                    let names: Vec<String> = stacks.iter().map(|s| format!("'{}'", s.name)).collect();
                    err(
                        file,
                        format!(
                            "no animation (take) is called or numbered `{w}`; the file has {}",
                            if names.is_empty() { "none".into() } else { names.join(", ") }
                        ),
                    )
                })?,
            None => {
                let span = |a: &(&Object, Anim)| a.1.key_range().map_or(0, |(lo, hi)| hi - lo);
                let mut best: Option<&(&Object, Anim)> = None;
                for a in &moving {
                    if best.is_none_or(|b| span(a) > span(b)) {
                        best = Some(a);
                    }
                }
                best.ok_or_else(|| {
                    err(file, format!("no animation moves {mname} (its blend shapes, its bones or its transform); export the animation (bake it), or read its blend shapes as morph targets"))
                })?
            }
        };
        let (stack, anim) = (chosen.0, &chosen.1);
        let ktime = |name: &str| p70_i64(stack.node, name);
        let keys = anim.key_range();
        let (start, stop) = match (ktime("LocalStart"), ktime("LocalStop")) {
            (s, Some(e)) if e > s.unwrap_or(0) => (s.unwrap_or(0), e),
            _ => match (ktime("ReferenceStart"), ktime("ReferenceStop")) {
                (s, Some(e)) if e > s.unwrap_or(0) => (s.unwrap_or(0), e),
                _ => keys.unwrap_or((0, 0)),
            },
        };
        let seconds = (stop - start) as f64 / KTIME_PER_SECOND;
        let n_times = match options.frames {
            Some(0) => return Err(err(file, "--frames must be at least 1".into())),
            Some(f) => f,
            None => {
                let n = (seconds * fps).round() + 1.0;
                if !n.is_finite() || n > 1.0e7 {
                    return Err(err(
                        file,
                        format!("animation '{}' spans {seconds} s, {n} frames at {fps} fps; the file is damaged, or sample it at fewer times (--frames N)", stack.name),
                    ));
                }
                n.max(1.0) as usize
            }
        };
        crate::memory::check(n_file, n_times, 1, budget).map_err(|e| {
            err(
                file,
                format!("animation '{}' at {n_times} frames: {e}; sample it at fewer times (--frames N)", stack.name),
            )
        })?;
        let times: Vec<i64> = match options.frames {
            Some(f) => (0..f)
                .map(|i| {
                    if f == 1 {
                        start
                    } else {
                        start + ((stop - start) as f64 * i as f64 / (f - 1) as f64).round() as i64
                    }
                })
                .collect(),
            None => (0..n_times).map(|i| start + (i as f64 / fps * KTIME_PER_SECOND).round() as i64).collect(),
        };
        let fps_text = format!("{fps:.3}").trim_end_matches('0').trim_end_matches('.').to_string();
        let how = match options.frames {
            Some(f) => format!("sampled at {f} evenly spaced times"),
            None => format!(
                "{fps_text} fps, {:.3} s to {:.3} s",
                start as f64 / KTIME_PER_SECOND,
                stop as f64 / KTIME_PER_SECOND
            ),
        };
        let what = match (channels.is_empty(), clusters.is_empty()) {
            (false, false) => format!("{} blend shapes, skinned by {} bones", channels.len(), clusters.len()),
            (false, true) => format!("{} blend shapes", channels.len()),
            (true, false) => format!("skinned by {} bones", clusters.len()),
            (true, true) => "its transform".to_string(),
        };
        description =
            format!("{} frames of {mname} in {file} (animation '{}', {how}; {what})", times.len(), stack.name);
        let w = times.len().to_string().len();
        for (fi, &t) in times.iter().enumerate() {
            let percents: Vec<f64> = channels
                .iter()
                .map(|c| anim.value(c.id, "DeformPercent", "DeformPercent", t).unwrap_or(c.rest_percent))
                .collect();
            push(format!("frame {:0w$}", fi + 1), pose_at(Some(anim), t, &percents))?;
        }
    } else {
        if channels.is_empty() {
            return Err(err(
                file,
                format!(
                    "{mname} has no blend shapes and no animation moves it, so the file holds one pose; export the poses as \
                     shape keys / blend shapes or as an animation (bake it)"
                ),
            ));
        }
        crate::memory::check(n_file, channels.len() + 1, 1, budget)
            .map_err(|e| err(file, format!("{} blend shapes of {mname}, each one pose: {e}", channels.len())))?;
        description = format!(
            "{} frames of {mname} in {file} (its {} blend shapes at 100 %, after the base)",
            channels.len() + 1,
            channels.len()
        );
        let w = (channels.len() + 1).to_string().len();
        push(format!("shape {:0w$} base", 0), pose_at(None, 0, &vec![0.0; channels.len()]))?;
        for k in 0..channels.len() {
            let mut p = vec![0.0; channels.len()];
            p[k] = 100.0;
            push(format!("shape {:0w$} {}", k + 1, channels[k].name), pose_at(None, 0, &p))?;
        }
    }
    let others: Vec<String> = candidates.iter().filter(|(m, _)| m.id != model.id).map(|(m, _)| label(m)).collect();
    let more = if others.is_empty() {
        String::new()
    } else {
        format!(" (other meshes: {}; --object NAME picks one)", others.join(", "))
    };
    Ok((weld, poses, format!("{description}{more}; {axes_note}")))
}

impl Weld {
    /// The poses (kept points) named and with their faces, and how many vertices.
    pub(super) fn finish(self, file: &str, poses: Vec<(String, Vec<[f64; 3]>)>, description: String) -> Gltf {
        let (n_file, n_welded) = (self.n_file, self.kept.len());
        let weld_note = if n_welded == n_file {
            format!("{n_file} vertices")
        } else {
            format!("{n_file} vertices welded to {n_welded} (duplicates split by the exporter)")
        };
        let source = format!("{description}; {weld_note}");
        let poses = poses
            .into_iter()
            .map(|(name, positions)| (format!("{file} {name}"), Mesh { positions, faces: self.faces.clone() }))
            .collect();
        // (FBX takes and USD clips are not offered to choose from yet: the CLI's --animation picks a take)
        Gltf { file: file.to_string(), poses, source, vertices_in_file: n_file, vertices_welded: n_welded, clips: None }
    }
}

/// Welds control points that are exact duplicates in the file, names the poses and says how many vertices.
pub(super) fn weld(
    file: &str,
    base: &[DVec3],
    faces: &[[u32; 3]],
    poses_raw: Vec<(String, Vec<DVec3>)>,
    description: String,
) -> Gltf {
    let weld = Weld::new(base, faces);
    let poses = poses_raw.into_iter().map(|(name, pos)| (name, weld.keep(&pos))).collect();
    weld.finish(file, poses, description)
}

/// A 4x4 transform applied to points: nalgebra's `transform_point`, without its division by w when the last row
/// is 0 0 0 1 (w is then exactly 1: the same numbers, one division less per coordinate).
struct Affine {
    m: DMat4,
    r: nalgebra::Matrix3<f64>,
    t: DVec3,
    affine: bool,
}

impl Affine {
    fn new(m: &DMat4) -> Affine {
        let affine = m[(3, 0)] == 0.0 && m[(3, 1)] == 0.0 && m[(3, 2)] == 0.0 && m[(3, 3)] == 1.0;
        Affine { m: *m, r: m.fixed_view::<3, 3>(0, 0).into_owned(), t: m.fixed_view::<3, 1>(0, 3).into_owned(), affine }
    }

    fn apply(&self, v: &[f64; 3]) -> [f64; 3] {
        let p = DVec3::from(*v);
        if self.affine {
            (self.r * p + self.t).into()
        } else {
            self.m.transform_point(&Point3::from(p)).coords.into()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fuzzing::{fbx_node, tiny_fbx_with};

    /// The tiny quad with its corners 0 and 2 stored twice (as exporters split them at seams): points 3 and 4
    /// repeat 0 and 2, and the shape moves points 2 and 3 by `offsets`.
    fn split_quad(offsets: Vec<f64>) -> Vec<u8> {
        let bytes = tiny_fbx_with(
            |g| {
                let v = vec![0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 0., 0., 1., 1., 0., 0., 1., 0.];
                g[0] = fbx_node("Vertices", vec![Prop::F64s(v)], vec![]);
                g[1] = fbx_node("PolygonVertexIndex", vec![Prop::I32s(vec![0, 1, -3, 3, 4, -6])], vec![]);
            },
            false,
        );
        with_shape_offsets(bytes, offsets)
    }

    /// Replaces the shape's 6 offsets (the plain f64 array after the node name `Vertices` that holds 6).
    fn with_shape_offsets(mut bytes: Vec<u8>, offsets: Vec<f64>) -> Vec<u8> {
        let pat: Vec<u8> = [&[8u8][..], b"Vertices", b"d", &6u32.to_le_bytes()].concat();
        let at = bytes.windows(pat.len()).position(|w| w == &pat[..]).expect("the shape's offsets") + pat.len() + 8;
        let raw: Vec<u8> = offsets.iter().flat_map(|x| x.to_le_bytes()).collect();
        bytes[at..at + 48].copy_from_slice(&raw);
        bytes
    }

    #[test]
    fn duplicate_control_points_are_welded_in_every_pose() {
        let f = read("split.fbx", &split_quad(vec![0., 0., 1., 0., 0., 2.]), &Default::default()).unwrap();
        assert!(f.source.ends_with("; 6 vertices welded to 4 (duplicates split by the exporter)"), "{}", f.source);
        assert_eq!(f.poses.len(), 3);
        for (_, m) in &f.poses {
            assert_eq!(m.faces, vec![[0, 1, 2], [0, 2, 3]]);
        }
        // Point 2 rises to 0.5 at 50 %; point 3's offset goes with it, welded into point 0.
        assert_eq!(f.poses[1].1.positions, vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.5], [0.0, 1.0, 0.0]]);
        assert_eq!(f.poses[2].1.positions[2], [1.0, 1.0, 1.0]);
    }

    #[test]
    fn a_non_finite_point_is_refused_even_where_welded_away() {
        let e = read("nan.fbx", &split_quad(vec![0., 0., 1., 0., 0., f64::NAN]), &Default::default())
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "file nan.fbx: Quad at frame 2 has coordinates that are not finite numbers (a transform, bind matrix or curve holds NaN or \
             infinity); the file is damaged: export it again"
        );
    }
}
