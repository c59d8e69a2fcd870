//! A population: n_s >= 2 registered meshes with the same vertices (in correspondence) and the same faces,
//! ordered by natural sort of their names, moved with ONE common offset and scale into the unit box.

use super::Mesh;
use crate::error::{Error, Result};

/// unit = (original - offset) * scale. The same for every shape (per-shape scaling would break rigidity).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Normalization {
    pub offset: [f64; 3],
    pub scale: f64,
}

impl Normalization {
    pub const IDENTITY: Normalization = Normalization { offset: [0.0; 3], scale: 1.0 };

    pub fn to_unit(&self, p: [f64; 3]) -> [f64; 3] {
        [
            (p[0] - self.offset[0]) * self.scale,
            (p[1] - self.offset[1]) * self.scale,
            (p[2] - self.offset[2]) * self.scale,
        ]
    }

    pub fn to_original(&self, p: [f64; 3]) -> [f64; 3] {
        [p[0] / self.scale + self.offset[0], p[1] / self.scale + self.offset[1], p[2] / self.scale + self.offset[2]]
    }

    /// A unit-box length (a distance, an error) in the original units.
    pub fn length_to_original(&self, x: f64) -> f64 {
        x / self.scale
    }
}

/// Registered shapes in unit-box coordinates.
///
/// The coordinates are stored once, in single precision (12 bytes per vertex and shape, see
/// [`crate::memory`]): every reader gets them as f64 ([`Population::point`], [`Population::shape`]), the
/// widened f32 values, so every consumer sees the same numbers and all arithmetic stays in f64. The unit box
/// keeps every coordinate within [0, 1], where f32 resolves 6e-8 (the input positions are f32 in most files:
/// glTF, point caches, binary PLY). Clones share the coordinates (a fit's pipeline, the page's models and a
/// generated population's truth hold the same copy); [`Population::set_shapes`] replaces them.
#[derive(Debug, Clone, PartialEq)]
pub struct Population {
    /// Shape names in the order used (natural sort).
    pub names: Vec<String>,
    /// Triangles shared by every shape.
    pub faces: std::sync::Arc<Vec<[u32; 3]>>,
    /// `points[i * n_vertices + j]`: vertex j of shape i, unit-box coordinates in f32.
    points: std::sync::Arc<Vec<[f32; 3]>>,
    n_vertices: usize,
    /// How the original coordinates were mapped into the unit box.
    pub normalization: Normalization,
    /// Where the shapes came from, for people: "11 OBJ files", "48 morph targets of mesh 'horse' in
    /// horse.glb, ...", "241 frames of animation 'Walk' (sampled at its keyframes, 24 fps) ...".
    pub source: String,
    /// A glTF's animations that move its mesh and the one the poses came from (None for other sources).
    pub clips: Option<super::gltf::Clips>,
    /// What is worked out once for these coordinates: the poses in farthest-first order
    /// ([`Population::pose_order`]) and the faces the connectivity follows ([`Population::graph_faces`]).
    derived: Derived,
}

/// The slots for [`Population::pose_order`] and [`Population::graph_faces`], shared by the clones that share
/// the coordinates. Not part of a population's value: two populations with equal coordinates are equal whether
/// or not they are filled.
#[derive(Debug, Clone, Default)]
struct Derived(std::sync::Arc<DerivedSlots>);
#[derive(Debug, Default)]
struct DerivedSlots {
    pose_order: std::sync::OnceLock<Vec<usize>>,
    /// None: no seams, the faces themselves.
    graph_faces: std::sync::OnceLock<Option<Vec<[u32; 3]>>>,
}
impl PartialEq for Derived {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// One shape of a [`Population`]: its vertices' unit-box coordinates, widened to f64 when read.
#[derive(Debug, Clone, Copy)]
pub struct Shape<'a> {
    points: &'a [[f32; 3]],
}

impl<'a> Shape<'a> {
    /// Vertex j.
    #[inline]
    pub fn get(&self, j: usize) -> [f64; 3] {
        widen(self.points[j])
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The vertices in order.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = [f64; 3]> + DoubleEndedIterator + Clone + 'a {
        self.points.iter().map(|&p| widen(p))
    }

    /// A copy in f64.
    pub fn to_vec(&self) -> Vec<[f64; 3]> {
        self.iter().collect()
    }

    /// The stored single-precision coordinates.
    pub fn as_f32(&self) -> &'a [[f32; 3]] {
        self.points
    }
}

/// A stored coordinate as the f64 every reader sees.
#[inline(always)]
pub fn widen(p: [f32; 3]) -> [f64; 3] {
    [p[0] as f64, p[1] as f64, p[2] as f64]
}

/// Above this many bytes of f64 poses, [`Sources::MeshFiles`] reads its files twice
/// rather than hold every pose in f64 until the unit box is known (24 bytes per vertex-pose beside the
/// population's 12). 8 MB is about 350 000 vertex-poses: smaller populations are read once (a second reading
/// would add 35-50 % to their load time, in Node, for a few MB).
pub const READ_TWICE_ABOVE_BYTES: usize = 8 << 20;

/// A unit-box coordinate as stored (rounded to nearest f32).
#[inline(always)]
pub fn narrow(p: [f64; 3]) -> [f32; 3] {
    [p[0] as f32, p[1] as f32, p[2] as f32]
}

/// Natural order of names: digit runs compare as numbers ("2.obj" < "10.obj"), the rest byte-wise,
/// case-insensitively first.
/// The error for the first name that comes twice in `sorted` (names in natural order): the poses are ordered by
/// their names, so two files of one name (from two folders, say) cannot be told apart nor put in order.
fn repeated_name<'a>(sorted: impl Iterator<Item = &'a str>) -> Option<Error> {
    let mut last: Option<&str> = None;
    for name in sorted {
        if last == Some(name) {
            return Some(Error::Population {
                file: name.to_string(),
                message: "two of the files are named so: the poses are ordered by their file names, so each needs \
                          its own; rename one, or open the files of one folder at a time"
                    .into(),
            });
        }
        last = Some(name);
    }
    None
}

pub fn natural_cmp(a: &str, b: &str) -> std::cmp::Ordering {
    use std::cmp::Ordering;
    let (ab, bb) = (a.as_bytes(), b.as_bytes());
    let (mut i, mut j) = (0, 0);
    while i < ab.len() && j < bb.len() {
        if ab[i].is_ascii_digit() && bb[j].is_ascii_digit() {
            let si = i;
            while i < ab.len() && ab[i].is_ascii_digit() {
                i += 1;
            }
            let sj = j;
            while j < bb.len() && bb[j].is_ascii_digit() {
                j += 1;
            }
            let na = a[si..i].trim_start_matches('0');
            let nb = b[sj..j].trim_start_matches('0');
            let ord = na.len().cmp(&nb.len()).then_with(|| na.cmp(nb));
            if ord != Ordering::Equal {
                return ord;
            }
        } else {
            let ord = ab[i].to_ascii_lowercase().cmp(&bb[j].to_ascii_lowercase());
            if ord != Ordering::Equal {
                return ord;
            }
            i += 1;
            j += 1;
        }
    }
    (ab.len() - i).cmp(&(bb.len() - j)).then_with(|| a.cmp(b))
}

/// [`Population::graph_faces`] when some vertices are the same point in every pose: the faces, then each face
/// with such a vertex again with it replaced by the other vertex at that point (for a later one the first, the
/// one of lowest index; for the first the next one).
/// None when there are none. Exact equality of the stored coordinates: duplicates written by an exporter are
/// the same numbers, and two vertices that only touch in some poses (lips, fingertips) stay apart.
fn seam_bridged(pop: &Population) -> Option<Vec<[u32; 3]>> {
    let nv = pop.n_vertices;
    let first = pop.points.get(..nv)?;
    // the vertices in the order of their first pose's coordinates: equal points next to each other
    let key = |j: u32| first[j as usize].map(f32::to_bits);
    let mut order: Vec<u32> = (0..nv as u32).collect();
    order.sort_unstable_by_key(|&j| (key(j), j));
    let mut same = vec![u32::MAX; nv];
    let mut any = false;
    let mut lead = 0;
    for k in 1..order.len() {
        let (r, j) = (order[lead], order[k]);
        if key(j) != key(r) {
            lead = k;
            continue;
        }
        let everywhere = pop.shapes().all(|s| s.points[j as usize] == s.points[r as usize]);
        if everywhere {
            same[j as usize] = r;
            any = true;
        }
    }
    if !any {
        return None;
    }
    // each face at such a point again on the other vertex there (a later one's on the first, the first's on the
    // first later one), so that both have the neighbours of both: the same distances along the edges
    let mut other = same.clone();
    for j in 0..nv {
        let r = same[j];
        if r != u32::MAX && other[r as usize] == u32::MAX {
            other[r as usize] = j as u32;
        }
    }
    let mut faces = pop.faces.to_vec();
    for f in pop.faces.iter() {
        if f.iter().any(|&v| other[v as usize] != u32::MAX) {
            let g = f.map(|v| if other[v as usize] == u32::MAX { v } else { other[v as usize] });
            if g[0] != g[1] && g[1] != g[2] && g[0] != g[2] {
                faces.push(g);
            }
        }
    }
    Some(faces)
}

/// Where the poses of a population come from: the input of [`Population::read`], the one constructor.
pub enum Sources<'a> {
    /// Files in memory, (name, bytes), each read by the reader its extension calls for ([`super::load`]: OBJ,
    /// PLY, glTF, FBX, USD, point caches, a .zip of any of them); errors in natural order of the names.
    Files(Vec<(String, Vec<u8>)>),
    /// OBJ or PLY files of one pose each, read one at a time: `fetch(i, buffer)` puts the bytes of `names[i]` in
    /// the buffer (emptied first), asked for in natural order of the names, so each file's text goes as soon as
    /// it is read. The page hands dropped files over this way and so do [`Sources::Paths`] of such files (with
    /// every text in memory at once, a population's peak was its text: docs/decisions.md). Only the first mesh
    /// keeps its faces; every other is checked against them as it is read, as [`Sources::Meshes`] are checked.
    /// The same population and the same errors as [`Sources::Files`]; a file `fetch` cannot give comes before
    /// them all (in the order of `names`).
    ///
    /// A population whose poses would take more than [`READ_TWICE_ABOVE_BYTES`] in f64 is read twice: the first
    /// pass checks every file and finds the unit box, the second reads only the positions
    /// ([`super::load::read_positions`]) and stores each pose straight into the f32 population (the same
    /// numbers: the unit box is the same minimum and maximum). Its peak is then the population's 12 bytes per
    /// vertex-pose and one file, not the 36 of every pose in f64 and in f32 together.
    MeshFiles { names: &'a [String], fetch: &'a mut dyn FnMut(usize, &mut Vec<u8>) -> Result<()> },
    /// The mesh files of directories (every file of an extension [`super::load::FORMATS`] lists, and `.vrm` and
    /// `.bin`, any case) and files named (one of another extension is refused by name). OBJ and PLY files alone
    /// are read one at a time ([`Sources::MeshFiles`]), so their bytes are never all in memory. (Compiles on
    /// wasm32 too, where std::fs reports "unsupported" at run time.)
    Paths(Vec<std::path::PathBuf>),
    /// Meshes already read, (name, mesh).
    Meshes(Vec<(String, Mesh)>),
    /// Shapes already in the unit box (generated data, tests), with their names and the faces.
    UnitShapes { names: Vec<String>, faces: Vec<[u32; 3]>, shapes: Vec<Vec<[f64; 3]>> },
    /// A population as a model file stored it ([`crate::model_file`]).
    Saved(Saved),
}

impl Sources<'_> {
    /// [`Sources::Paths`] of any kind of path.
    pub fn paths<P: AsRef<std::path::Path>>(paths: &[P]) -> Sources<'static> {
        Sources::Paths(paths.iter().map(|p| p.as_ref().to_path_buf()).collect())
    }
}

/// A population as a model file stored it: its unit-box points as they were, pose after pose, with the names in
/// their order; `file` names the model file in errors.
pub struct Saved {
    pub file: String,
    pub names: Vec<String>,
    pub faces: Vec<[u32; 3]>,
    pub points: Vec<[f32; 3]>,
    pub normalization: Normalization,
    pub source: String,
}

/// How [`Population::read`] reads its sources.
#[derive(Debug, Clone, Default)]
pub struct ReadOptions {
    /// Choices for glTF, FBX and USD files (which animation, which frames...).
    pub gltf: super::gltf::Options,
}

impl Population {
    /// The population of `sources`: validated (at least 2 poses of one mesh, finite coordinates, within the
    /// memory budget), ordered by natural sort of the names, and moved into the unit box by one offset and one
    /// scale. Every error found, in natural order of the files' names (one for sources that stop at the first).
    pub fn read(sources: Sources<'_>, options: &ReadOptions) -> std::result::Result<Population, Vec<Error>> {
        let one = |e: Error| vec![e];
        match sources {
            Sources::Files(files) => Population::from_files_all_errors_with(files, &options.gltf),
            Sources::MeshFiles { names, fetch } => Population::read_one_at_a_time(names, fetch, READ_TWICE_ABOVE_BYTES),
            Sources::Paths(paths) => Population::from_paths_with(&paths, &options.gltf).map_err(one),
            Sources::Meshes(named) => Population::from_meshes_sharing(named, false).map_err(one),
            Sources::UnitShapes { names, faces, shapes } => {
                Population::from_unit_shapes(names, faces, shapes).map_err(one)
            }
            Sources::Saved(s) => {
                Population::from_saved(&s.file, s.names, s.faces, s.points, s.normalization, s.source).map_err(one)
            }
        }
    }

    /// [`Population::read`] with the default options, and its first error only: for the callers that report one
    /// error and pass it on with `?` as a [`crate::Error`] (generated data, the model file, the CLI, tests).
    pub fn new(sources: Sources<'_>) -> Result<Population> {
        Population::read(sources, &ReadOptions::default()).map_err(|mut e| e.swap_remove(0))
    }
}

impl Population {
    pub fn n_shapes(&self) -> usize {
        self.points.len().checked_div(self.n_vertices).unwrap_or(0)
    }

    pub fn n_vertices(&self) -> usize {
        self.n_vertices
    }

    /// Vertex j of shape i, unit-box coordinates.
    #[inline]
    pub fn point(&self, i: usize, j: usize) -> [f64; 3] {
        debug_assert!(j < self.n_vertices);
        widen(self.points[i * self.n_vertices + j])
    }

    /// Shape i. Panics if there is no shape i (as indexing does); [`Population::get_shape`] does not.
    #[inline]
    pub fn shape(&self, i: usize) -> Shape<'_> {
        self.get_shape(i).unwrap_or_else(|| panic!("no shape {i}: the population has {} shapes", self.n_shapes()))
    }

    /// Shape i, or None.
    pub fn get_shape(&self, i: usize) -> Option<Shape<'_>> {
        let nv = self.n_vertices;
        (i < self.n_shapes()).then(|| Shape { points: &self.points[i * nv..(i + 1) * nv] })
    }

    /// Every shape in order.
    pub fn shapes(&self) -> impl ExactSizeIterator<Item = Shape<'_>> + DoubleEndedIterator + Clone + '_ {
        let nv = self.n_vertices.max(1);
        self.points.chunks_exact(nv).map(|points| Shape { points })
    }

    /// An error when every shape is the first one moved as a whole (each vertex within 1e-6 of the unit box of
    /// its place there, once each shape's centroid is taken out): such poses have no motion to learn, and the
    /// page refuses them as it refuses a bad file, keeping what it had. None otherwise. (The fit makes the same
    /// check on its data: `mfa::aecm`.)
    pub fn still_error(&self) -> Option<Error> {
        let centroid = |s: Shape<'_>| {
            let n = s.len().max(1) as f64;
            s.iter().fold([0.0; 3], |a, p| [a[0] + p[0] / n, a[1] + p[1] / n, a[2] + p[2] / n])
        };
        let first = self.shapes().next()?;
        let c0 = centroid(first);
        let moved = self.shapes().skip(1).any(|s| {
            let c = centroid(s);
            s.iter().zip(first.iter()).any(|(p, q)| (0..3).any(|d| ((p[d] - c[d]) - (q[d] - c0[d])).abs() > 1e-6))
        });
        let names = match self.names.len() {
            0..=3 => self.names.join(", "),
            n => format!("{} and {} more", self.names[..2].join(", "), n - 2),
        };
        (!moved).then(|| Error::Population {
            file: names,
            message: format!(
                "all {} poses are the same shape (every vertex at the same place in each, up to one move of the whole \
                 mesh): there is no motion to learn; open poses in which the parts move",
                self.n_shapes()
            ),
        })
    }

    /// Mean over the shapes of the mean squared distance of the vertices from the shape's centroid (unit box):
    /// the population's size, the same however the poses are turned (which its bounding box is not).
    pub fn mean_squared_radius(&self) -> f64 {
        let nv = self.n_vertices.max(1) as f64;
        let per_shape = |s: Shape<'_>| {
            let c = s.iter().fold([0.0; 3], |a, p| [a[0] + p[0], a[1] + p[1], a[2] + p[2]]).map(|x| x / nv);
            s.iter().map(|p| (0..3).map(|d| (p[d] - c[d]).powi(2)).sum::<f64>()).sum::<f64>() / nv
        };
        self.shapes().map(per_shape).sum::<f64>() / self.n_shapes().max(1) as f64
    }

    /// A copy of every shape in f64 (`[i][j]`: vertex j of shape i), for code that wants slices; 24 bytes per
    /// vertex and shape, twice the stored size.
    pub fn unit_shapes(&self) -> Vec<Vec<[f64; 3]>> {
        self.shapes().map(|s| s.to_vec()).collect()
    }

    /// Vertex j in every shape.
    pub fn track(&self, j: usize) -> Vec<[f64; 3]> {
        (0..self.n_shapes()).map(|i| self.point(i, j)).collect()
    }

    /// Replaces the shapes with `shapes` (unit-box coordinates, each rounded to f32 as stored; as many
    /// vertices each as now; the normalisation is kept). For tests and variants of a population.
    pub fn set_shapes(&mut self, shapes: &[Vec<[f64; 3]>]) {
        assert!(shapes.iter().all(|s| s.len() == self.n_vertices), "every shape needs {} vertices", self.n_vertices);
        self.points = std::sync::Arc::new(shapes.iter().flatten().map(|&p| narrow(p)).collect());
        self.derived = Derived::default();
    }

    /// An order of the poses that depends on the coordinates alone (the part rule's farthest-first order,
    /// [`crate::parts::patches::spread_poses`]): `compute` runs the first time it is asked for, and the
    /// population and its clones keep the answer until their shapes are replaced.
    pub fn pose_order(&self, compute: impl FnOnce() -> Vec<usize>) -> &[usize] {
        self.derived.0.pose_order.get_or_init(compute)
    }

    /// The triangles for the code that follows the mesh's connectivity (the patches and the merge tree, the
    /// parts' adjacency, islands, the part graph and its joints): the faces, and where two vertices are the same
    /// point in every pose (an exporter split them at a seam or per face corner, or two pieces of the mesh meet
    /// there), every face of each again on the other, so that a part does not end at a seam. The faces
    /// themselves when no two vertices are (the usual case). Drawing, volumes and exports use `faces`.
    pub fn graph_faces(&self) -> &[[u32; 3]] {
        self.derived.0.graph_faces.get_or_init(|| seam_bridged(self)).as_deref().unwrap_or(&self.faces)
    }

    /// The population of the listed vertices only (`vertices[c]` becomes vertex c), with `faces` over the new
    /// numbering: the same shapes, names and unit box (the coordinates are copied as stored, so every reader
    /// sees the same numbers as in `self`). For a coarse mesh of a large population.
    pub fn restricted(&self, vertices: &[usize], faces: Vec<[u32; 3]>) -> Population {
        debug_assert!(faces.iter().flatten().all(|&v| (v as usize) < vertices.len()));
        let points = self.shapes().flat_map(|s| vertices.iter().map(move |&j| s.points[j])).collect();
        Population::assembled(
            self.names.clone(),
            faces,
            points,
            vertices.len(),
            self.normalization,
            self.source.clone(),
        )
    }

    /// A population from its parts, with nothing derived yet (every constructor ends here).
    fn assembled(
        names: Vec<String>,
        faces: Vec<[u32; 3]>,
        points: Vec<[f32; 3]>,
        n_vertices: usize,
        normalization: Normalization,
        source: String,
    ) -> Population {
        Population {
            names,
            faces: std::sync::Arc::new(faces),
            points: std::sync::Arc::new(points),
            n_vertices,
            normalization,
            source,
            clips: None,
            derived: Derived::default(),
        }
    }

    /// [`Sources::Saved`].
    fn from_saved(
        file: &str,
        names: Vec<String>,
        faces: Vec<[u32; 3]>,
        points: Vec<[f32; 3]>,
        normalization: Normalization,
        source: String,
    ) -> Result<Population> {
        let n_vertices = points.len() / names.len().max(1);
        if names.len() < 2 || n_vertices == 0 || points.len() != names.len() * n_vertices {
            return Err(Error::ModelFile {
                file: file.into(),
                message: format!(
                    "{} points cannot be {} poses of one mesh; save the model again",
                    points.len(),
                    names.len()
                ),
            });
        }
        let mut sorted: Vec<&str> = names.iter().map(|n| n.as_str()).collect();
        sorted.sort_unstable();
        if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
            return Err(Error::ModelFile {
                file: file.into(),
                message: format!("two poses are named '{}'; the file is damaged: save the model again", w[0]),
            });
        }
        Ok(Population::assembled(names, faces, points, n_vertices, normalization, source))
    }

    /// [`Sources::Meshes`]; with `faces_of_first`, only the first mesh (in natural order) carries the
    /// faces and the others none (one copy of the faces instead of one per shape).
    fn from_meshes_sharing(mut named: Vec<(String, Mesh)>, faces_of_first: bool) -> Result<Population> {
        if named.len() < 2 {
            let file = named.first().map_or_else(|| "(none)".to_string(), |n| n.0.clone());
            return Err(Error::Population {
                file,
                message: format!(
                    "a population needs at least 2 shapes, got {}; add more poses of the same mesh",
                    named.len()
                ),
            });
        }
        named.sort_by(|a, b| natural_cmp(&a.0, &b.0));
        if let Some(e) = repeated_name(named.iter().map(|n| n.0.as_str())) {
            return Err(e);
        }
        let (first_name, first) = (&named[0].0, &named[0].1);
        // (with faces_of_first, a mesh of the first one's vertex count carries no faces to compare)
        let checked = named
            .iter()
            .enumerate()
            .filter(|(k, (_, mesh))| *k == 0 || !(faces_of_first && mesh.positions.len() == first.positions.len()));
        if let Some((_, e)) = first_mismatch(checked.map(|(_, (name, mesh))| (name.as_str(), mesh))) {
            return Err(e);
        }
        if let Some(e) = named.iter().find_map(|(name, mesh)| first_non_finite(name, &mesh.positions)) {
            return Err(e);
        }
        // The smallest fit (one part) of this population must fit in the memory budget: refuse now, before
        // the normalised copy is made.
        crate::memory::check(first.positions.len(), named.len(), 1, crate::memory::budget_bytes()?)?;
        let (lo, hi) = crate::geometry::bounds(named.iter().flat_map(|(_, mesh)| &mesh.positions));
        let normalization = unit_box(first_name, lo, hi)?;
        let faces = first.faces.clone();
        let n_vertices = first.positions.len();
        let mut names = Vec::with_capacity(named.len());
        let mut points = Vec::with_capacity(named.len() * n_vertices);
        for (name, mesh) in named {
            // each pose's f64 positions are freed as soon as they are stored
            points.extend(mesh.positions.iter().map(|&p| narrow(normalization.to_unit(p))));
            names.push(name);
        }
        let source = format!("{} shapes", names.len());
        Ok(Population::assembled(names, faces, points, n_vertices, normalization, source))
    }

    /// [`Sources::Files`]: sorted by name, then read ([`Population::from_files_with`]).
    fn from_files_all_errors_with(
        mut files: Vec<(String, Vec<u8>)>,
        options: &super::gltf::Options,
    ) -> std::result::Result<Population, Vec<Error>> {
        files.sort_by(|a, b| natural_cmp(&a.0, &b.0));
        Population::from_files_with(files, options).map_err(|e| {
            if e.is_empty() {
                vec![Error::Io("no files were given".into())]
            } else {
                e
            }
        })
    }

    /// [`Sources::MeshFiles`], reading twice above `read_twice_above` bytes of f64 poses.
    fn read_one_at_a_time(
        names: &[String],
        mut fetch: impl FnMut(usize, &mut Vec<u8>) -> Result<()>,
        read_twice_above: usize,
    ) -> std::result::Result<Population, Vec<Error>> {
        use super::load::FileKind;
        if names.is_empty() {
            return Err(vec![Error::Io("no files were given".into())]);
        }
        let mut order: Vec<usize> = (0..names.len()).collect();
        order.sort_by(|&a, &b| natural_cmp(&names[a], &names[b]));
        if let Some(e) = repeated_name(order.iter().map(|&i| names[i].as_str())) {
            return Err(vec![e]);
        }
        let other: Vec<Error> = order
            .iter()
            .filter(|&&i| !matches!(FileKind::of(&names[i]), FileKind::Obj | FileKind::Ply))
            .map(|&i| Error::Population {
                file: names[i].clone(),
                message: "is not an OBJ or PLY file: read a set with it as Sources::Files".into(),
            })
            .collect();
        if !other.is_empty() {
            return Err(other);
        }
        // (each file's error with its place in `order`, so that a mismatch found among the files that read
        // joins them in order)
        let (mut named, mut errors): (Vec<(String, Mesh)>, Vec<(usize, Error)>) =
            (Vec::with_capacity(names.len()), Vec::new());
        let mut unread: Vec<(usize, Error)> = Vec::new();
        let mut bytes = Vec::new();
        // the first error the whole set's checks would meet among the files that read (reported with the files'
        // own errors, [`first_mismatch`]), and its file's place in `order`
        let mut mismatch: Option<(usize, Error)> = None;
        // read twice: only the first pose's positions are kept; the unit box and the first non-finite
        // coordinate are found as the files go by
        let mut twice = false;
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        let mut non_finite: Option<Error> = None;
        for (at, &i) in order.iter().enumerate() {
            bytes.clear();
            if let Err(e) = fetch(i, &mut bytes) {
                unread.push((i, e));
                continue;
            }
            let mut mesh = match super::load::read_mesh(&names[i], &bytes) {
                Ok(m) => m,
                Err(e) => {
                    errors.push((at, e));
                    continue;
                }
            };
            if twice {
                (lo, hi) = crate::geometry::bounds([lo, hi].iter().chain(&mesh.positions));
                if non_finite.is_none() {
                    non_finite = first_non_finite(&names[i], &mesh.positions);
                }
            }
            // (a reader's vector grows by doubling: what is kept holds no more than its points)
            if !twice {
                mesh.positions.shrink_to_fit();
            }
            match named.first() {
                None => {
                    mismatch = check_first_mesh(&names[i], &mesh).err().map(|e| (at, e));
                    twice = names.len() >= 2 && mesh.positions.len() * names.len() * 24 > read_twice_above;
                    if twice {
                        (lo, hi) = crate::geometry::bounds(&mesh.positions);
                        non_finite = first_non_finite(&names[i], &mesh.positions);
                    }
                    named.push((names[i].clone(), mesh));
                }
                Some((first_name, first)) => {
                    if mismatch.is_none() {
                        mismatch = check_same_mesh(first_name, first, &names[i], &mesh).err().map(|e| (at, e));
                    }
                    let positions = if twice { Vec::new() } else { mesh.positions };
                    named.push((names[i].clone(), Mesh { positions, faces: Vec::new() }));
                }
            }
        }
        if !unread.is_empty() {
            unread.sort_by_key(|u| u.0);
            return Err(unread.into_iter().map(|u| u.1).collect());
        }
        if !errors.is_empty() {
            errors.extend(mismatch);
            errors.sort_by_key(|e| e.0);
            return Err(errors.into_iter().map(|e| e.1).collect());
        }
        // (with fewer than two shapes, that is the error)
        if let Some((_, e)) = mismatch.filter(|_| named.len() >= 2) {
            return Err(vec![e]);
        }
        let (n_obj, n_ply) = order.iter().fold((0, 0), |(o, p), &i| match FileKind::of(&names[i]) {
            FileKind::Ply => (o, p + 1),
            _ => (o + 1, p),
        });
        let source = super::load::mesh_files_source(n_obj, n_ply);
        if !twice {
            let mut population = Population::from_meshes_sharing(named, true).map_err(|e| vec![e])?;
            population.source = source;
            return Ok(population);
        }
        // the checks of from_meshes_sharing, in its order, then the second pass
        if let Some(e) = non_finite {
            return Err(vec![e]);
        }
        let n_vertices = named[0].1.positions.len();
        crate::memory::check(n_vertices, named.len(), 1, crate::memory::budget_bytes().map_err(|e| vec![e])?)
            .map_err(|e| vec![e])?;
        let normalization = unit_box(&named[0].0, lo, hi).map_err(|e| vec![e])?;
        let mut points = Vec::with_capacity(named.len() * n_vertices);
        points.extend(named[0].1.positions.iter().map(|&p| narrow(normalization.to_unit(p))));
        named[0].1.positions = Vec::new();
        for &i in &order[1..] {
            bytes.clear();
            let again = fetch(i, &mut bytes)
                .and_then(|_| super::load::read_positions(&names[i], &bytes))
                .map_err(|e| vec![e])?;
            if again.len() != n_vertices || first_non_finite(&names[i], &again).is_some() {
                return Err(vec![Error::Population {
                    file: names[i].clone(),
                    message: "changed while it was read (the second reading differs from the first); load the population again".into(),
                }]);
            }
            points.extend(again.iter().map(|&p| narrow(normalization.to_unit(p))));
        }
        let mut faces = std::mem::take(&mut named[0].1.faces);
        faces.shrink_to_fit();
        let names = named.into_iter().map(|n| n.0).collect();
        Ok(Population::assembled(names, faces, points, n_vertices, normalization, source))
    }

    /// Reads every file (name, bytes) with the reader its extension calls for, then checks and places the poses
    /// as [`Sources::Meshes`].
    fn from_files_with(
        files: Vec<(String, Vec<u8>)>,
        options: &super::gltf::Options,
    ) -> std::result::Result<Population, Vec<Error>> {
        let loaded = super::load::load_with(files, options)?;
        let mut population = Population::from_meshes_sharing(loaded.poses, false).map_err(|e| vec![e])?;
        population.source = loaded.source;
        population.clips = loaded.clips;
        Ok(population)
    }

    /// [`Sources::UnitShapes`].
    fn from_unit_shapes(names: Vec<String>, faces: Vec<[u32; 3]>, shapes: Vec<Vec<[f64; 3]>>) -> Result<Population> {
        if names.len() != shapes.len() {
            return Err(Error::Population {
                file: names.first().cloned().unwrap_or_else(|| "(none)".into()),
                message: format!("{} names for {} shapes; give one name per shape", names.len(), shapes.len()),
            });
        }
        // the faces once, on the shape that comes first in natural order (the one the others are checked against)
        let first = (0..names.len()).min_by(|&a, &b| natural_cmp(&names[a], &names[b]));
        let mut faces = Some(faces);
        let named = names
            .into_iter()
            .zip(shapes)
            .enumerate()
            .map(|(k, (n, positions))| {
                let faces = if Some(k) == first { faces.take().unwrap_or_default() } else { Vec::new() };
                (n, Mesh { positions, faces })
            })
            .collect();
        Population::from_meshes_sharing(named, true)
    }

    /// [`Sources::Paths`]: the first error.
    fn from_paths_with(paths: &[std::path::PathBuf], options: &super::gltf::Options) -> Result<Population> {
        let mut files = Vec::new();
        for p in paths {
            if p.is_dir() {
                let rd = std::fs::read_dir(p)
                    .map_err(|e| Error::Io(format!("cannot read directory {}: {e}", p.display())))?;
                for entry in rd {
                    let entry = entry.map_err(|e| Error::Io(format!("cannot read directory {}: {e}", p.display())))?;
                    let path = entry.path();
                    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
                    if path.is_file() && super::load::FileKind::is_known_extension(&name) {
                        files.push(path);
                    }
                }
            } else {
                files.push(p.to_path_buf());
            }
        }
        if files.is_empty() {
            return Err(Error::Io(format!(
                "no mesh files found in the given paths (posemfa reads {}); pass a folder of them or the files \
                 themselves",
                super::load::formats_read()
            )));
        }
        let kind = |f: &std::path::PathBuf| {
            super::load::FileKind::of(&f.file_name().map(|n| n.to_string_lossy()).unwrap_or_default())
        };
        if files.iter().all(|f| matches!(kind(f), super::load::FileKind::Obj | super::load::FileKind::Ply)) {
            return Population::from_mesh_paths(files);
        }
        let mut loaded = Vec::with_capacity(files.len());
        for f in files {
            let bytes = std::fs::read(&f).map_err(|e| Error::Io(format!("cannot read {}: {e}", f.display())))?;
            let name = f.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
            loaded.push((name, bytes));
        }
        loaded.sort_by(|a, b| natural_cmp(&a.0, &b.0));
        Population::from_files_with(loaded, options).map_err(|mut e| {
            if e.is_empty() {
                Error::Io("no files were given".into())
            } else {
                e.swap_remove(0)
            }
        })
    }

    /// The end of [`Population::from_paths_with`] for one OBJ or PLY file per pose, with the same result and
    /// the same error as reading every file first ([`Sources::MeshFiles`]): each file
    /// is read into one reused buffer and parsed straight away, in natural order, so the files' bytes are never
    /// all in memory (36 MB of fresh pages, a fault per 4 KB, for horse-gallop). The error is the first file
    /// that cannot be read in the given order, else the first file that does not parse in natural order, else
    /// what [`Sources::Meshes`] says.
    fn from_mesh_paths(files: Vec<std::path::PathBuf>) -> Result<Population> {
        use std::io::Read;
        let names: Vec<String> =
            files.iter().map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()).collect();
        let mut fetch = |i: usize, buffer: &mut Vec<u8>| {
            std::fs::File::open(&files[i])
                .and_then(|mut file| file.read_to_end(buffer))
                .map(|_| ())
                .map_err(|e| Error::Io(format!("cannot read {}: {e}", files[i].display())))
        };
        Population::read_one_at_a_time(&names, &mut fetch, READ_TWICE_ABOVE_BYTES).map_err(|mut e| e.swap_remove(0))
    }
}

/// The unit box of points within `lo`..`hi`: the offset `lo` and one scale for every axis, 1 over the largest
/// side; an error (named by `first_name`, the population's first file) when there is no extent to scale.
fn unit_box(first_name: &str, lo: [f64; 3], hi: [f64; 3]) -> Result<Normalization> {
    let side = (0..3).map(|d| hi[d] - lo[d]).fold(0.0, f64::max);
    if !(side > 0.0) {
        return Err(Error::Population {
            file: first_name.to_string(),
            message: "all vertices of all shapes are at one point; there is no shape to fit: load the real meshes"
                .into(),
        });
    }
    // 1/side must be finite too (a subnormal extent, say 1e-310, would give an infinite scale and NaN).
    if !side.is_finite() || !(1.0 / side).is_finite() {
        return Err(Error::Population {
            file: first_name.to_string(),
            message: format!(
                "the shapes span {side:e} units, which double precision cannot scale into a unit box; \
                 rescale the meshes (the same way for every pose) to an ordinary size"
            ),
        });
    }
    Ok(Normalization { offset: lo, scale: 1.0 / side })
}

/// The error for the first of `positions` (file `name`'s) with a non-finite coordinate, if any.
fn first_non_finite(name: &str, positions: &[[f64; 3]]) -> Option<Error> {
    let j = positions.iter().position(|p| p.iter().any(|c| !c.is_finite()))?;
    Some(Error::Population {
        file: name.to_string(),
        message: format!("vertex {} has a non-finite coordinate; fix or remove it", j + 1),
    })
}

/// What [`Sources::Meshes`] asks of the first mesh in natural order: vertices, triangles, and every
/// triangle's indices naming a vertex.
fn check_first_mesh(first_name: &str, first: &Mesh) -> Result<()> {
    if first.positions.is_empty() {
        return Err(Error::Population { file: first_name.to_string(), message: "has no vertices".into() });
    }
    if first.faces.is_empty() {
        return Err(Error::Population {
            file: first_name.to_string(),
            message: "has no triangles; posemfa needs triangle meshes (f lines)".into(),
        });
    }
    if let Some(k) = first.faces.iter().position(|f| f.iter().any(|&v| v as usize >= first.positions.len())) {
        return Err(Error::Population {
            file: first_name.to_string(),
            message: format!(
                "triangle {} is {:?} (1-based) but the mesh has {} vertices; every index must name a vertex",
                k + 1,
                first.faces[k].map(|x| x as u64 + 1),
                first.positions.len()
            ),
        });
    }
    Ok(())
}

/// The first problem [`Sources::Meshes`]'s checks of the first mesh and of the others against it meet,
/// with the place of its mesh in `meshes` (natural order): for a set where other files failed to read, whose
/// errors it joins (a file a vertex short was only named once the broken ones had been mended).
pub(super) fn first_mismatch<'a>(meshes: impl IntoIterator<Item = (&'a str, &'a Mesh)>) -> Option<(usize, Error)> {
    let mut meshes = meshes.into_iter().enumerate();
    let (_, (first_name, first)) = meshes.next()?;
    if let Err(e) = check_first_mesh(first_name, first) {
        return Some((0, e));
    }
    meshes.find_map(|(k, (name, mesh))| check_same_mesh(first_name, first, name, mesh).err().map(|e| (k, e)))
}

/// What [`Sources::Meshes`] asks of every other mesh: the first one's vertex count and its very faces.
fn check_same_mesh(first_name: &str, first: &Mesh, name: &str, mesh: &Mesh) -> Result<()> {
    // two files of one name (dropped from two folders): "1.obj has ... but 1.obj has" would say nothing
    let first_name =
        &if name == first_name { format!("the first file, also named {first_name},") } else { first_name.to_string() };
    let differ = |what: &str, here: usize, there: usize, rule: &str| {
        Err(Error::Population {
            file: name.to_string(),
            message: format!("has {here} {what} but {first_name} has {there}; {rule}"),
        })
    };
    // fewer than the first: also what a file cut short by a copy or download that stopped has
    let cut = |here: usize, there: usize| {
        if here < there {
            " (or, if this file is a copy of the same mesh, it was cut short: copy or export it again)"
        } else {
            ""
        }
    };
    let (here, there) = (mesh.positions.len(), first.positions.len());
    if here != there {
        let rule = format!("every shape must be the same mesh in another pose{}", cut(here, there));
        return differ("vertices", here, there, &rule);
    }
    let (here, there) = (mesh.faces.len(), first.faces.len());
    if here != there {
        return differ("triangles", here, there, &format!("every shape must share the same faces{}", cut(here, there)));
    }
    if let Some(k) = (0..mesh.faces.len()).find(|&k| mesh.faces[k] != first.faces[k]) {
        return Err(Error::Population {
            file: name.to_string(),
            message: format!(
                "triangle {} is {:?} but in {} it is {:?} (1-based); every shape must share the same faces",
                k + 1,
                mesh.faces[k].map(|x| x + 1),
                first_name,
                first.faces[k].map(|x| x + 1)
            ),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn poses_that_are_one_shape_moved_as_a_whole_are_still() {
        let base = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let moved = |dx: f64, bend: f64| -> Vec<[f64; 3]> {
            base.iter().enumerate().map(|(j, p)| [p[0] + dx, p[1], if j == 2 { bend } else { 0.0 }]).collect()
        };
        let pop = |shapes| {
            Population::new(crate::mesh::Sources::UnitShapes {
                names: vec!["a.obj".into(), "b.obj".into()],
                faces: vec![[0, 1, 2]],
                shapes,
            })
        };
        let still = pop(vec![moved(0.0, 0.0), moved(0.25, 0.0)]).unwrap().still_error().expect("still");
        assert!(
            matches!(&still, Error::Population { file, message } if file == "a.obj, b.obj"
            && message.starts_with("all 2 poses are the same shape")),
            "{still:?}"
        );
        assert!(pop(vec![moved(0.0, 0.0), moved(0.25, 0.01)]).unwrap().still_error().is_none());
    }

    #[test]
    fn vertices_at_one_point_in_every_pose_are_joined_for_the_connectivity_only() {
        // two triangles that share an edge's points but not its vertices (2 = 4 and 1 = 5 in every pose), and
        // vertex 6 on vertex 0 in the first pose only (touching, not the same point)
        let faces = vec![[0, 1, 2], [4, 5, 3], [6, 2, 1]];
        let shape = |t: f64| -> Vec<[f64; 3]> {
            let (a, b, c, d) = ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 1.0, t], [1.5, 1.0, 0.0]);
            vec![a, b, c, d, c, b, [0.0, t, 0.0]]
        };
        let pop = Population::new(crate::mesh::Sources::UnitShapes {
            names: vec!["a".into(), "b".into()],
            faces: faces.clone(),
            shapes: vec![shape(0.0), shape(0.3)],
        })
        .unwrap();
        assert_eq!(*pop.faces, faces, "the faces themselves are as given");
        // the face on 4 and 5 again on 2 and 1, the faces on 1 and 2 again on 5 and 4; vertex 6 is not 0
        assert_eq!(pop.graph_faces(), &[[0, 1, 2], [4, 5, 3], [6, 2, 1], [0, 5, 4], [2, 1, 3], [6, 4, 5]]);
        assert_eq!(crate::parts::islands::island_count(&[0; 7], pop.graph_faces()), 0);
        assert_eq!(crate::parts::islands::island_count(&[0; 7], &pop.faces), 1);
        // without such vertices, the faces
        let plain = Population::new(crate::mesh::Sources::UnitShapes {
            names: vec!["a".into(), "b".into()],
            faces: vec![[0, 1, 2]],
            shapes: vec![shape(0.0)[..3].to_vec(), shape(0.3)[..3].to_vec()],
        })
        .unwrap();
        assert!(std::ptr::eq(plain.graph_faces(), plain.faces.as_slice()));
    }

    fn tri(offset: f64) -> Mesh {
        Mesh { positions: vec![[offset, 0.0, 0.0], [1.0 + offset, 0.0, 0.0], [0.0, 2.0, 0.0]], faces: vec![[0, 1, 2]] }
    }

    /// OBJ text of a quad (two triangles), its first vertex moved by `dx`; `faces` replaces the f lines.
    fn quad_obj(dx: f64, faces: &str) -> Vec<u8> {
        format!("v {dx} 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n{faces}").into_bytes()
    }

    /// Both readers on one set of files, the one-at-a-time reader reading once and reading twice: it must ask
    /// for each file once in natural order, or (twice) for every file in natural order and then again for all
    /// but the first when all of them read. Both ways must give the same population or the same errors.
    fn both(
        files: &[(&str, Vec<u8>)],
    ) -> (std::result::Result<Population, Vec<Error>>, std::result::Result<Population, Vec<Error>>) {
        let all = Population::read(
            crate::mesh::Sources::Files(files.iter().map(|(n, b)| (n.to_string(), b.clone())).collect()),
            &Default::default(),
        );
        let names: Vec<String> = files.iter().map(|(n, _)| n.to_string()).collect();
        let mut want = names.clone();
        want.sort_by(|a, b| natural_cmp(a, b));
        let read = |read_twice_above: usize| {
            let mut asked = Vec::new();
            let one = Population::read_one_at_a_time(
                &names,
                |i, buffer| {
                    asked.push(names[i].clone());
                    buffer.extend_from_slice(&files[i].1);
                    Ok(())
                },
                read_twice_above,
            );
            (one, asked)
        };
        let (once, asked) = read(usize::MAX);
        assert_eq!(asked, want, "each file once, in natural order");
        let (twice, asked) = read(0);
        let mut again = want.clone();
        if asked.len() > want.len() {
            again.extend_from_slice(&want[1..]);
        }
        assert_eq!(asked, again, "every file in natural order, then all but the first again");
        match (&once, &twice) {
            (Ok(a), Ok(b)) => {
                assert_eq!(a, b);
                assert_eq!(
                    (&a.source, a.normalization.scale, a.normalization.offset),
                    (&b.source, b.normalization.scale, b.normalization.offset)
                );
            }
            _ => assert_eq!(messages(&once), messages(&twice)),
        }
        (all, once)
    }

    fn messages(r: &std::result::Result<Population, Vec<Error>>) -> Vec<String> {
        r.as_ref().err().map(|e| e.iter().map(|x| x.to_string()).collect()).unwrap_or_default()
    }

    #[test]
    fn two_files_of_one_name_are_refused_by_that_name() {
        // two folders' 2.obj picked together: which pose is which cannot be told, nor their order
        let f = "f 1 2 3\nf 1 3 4\n";
        let files = vec![
            ("2.obj".to_string(), quad_obj(0.0, f)),
            ("1.obj".to_string(), quad_obj(0.1, f)),
            ("2.obj".to_string(), quad_obj(0.2, f)),
        ];
        let want = "file 2.obj: two of the files are named so: the poses are ordered by their file names, so each needs its own; rename one, or open the files of one folder at a time";
        assert_eq!(
            messages(&Population::read(crate::mesh::Sources::Files(files.clone()), &Default::default())),
            [want]
        );
        let names: Vec<String> = files.iter().map(|f| f.0.clone()).collect();
        let one = Population::read_one_at_a_time(
            &names,
            |i, b| {
                b.extend_from_slice(&files[i].1);
                Ok(())
            },
            usize::MAX,
        );
        assert_eq!(messages(&one), [want]);
        // distinct names read as before
        assert!(Population::read(
            crate::mesh::Sources::Files(vec![files[0].clone(), files[1].clone()]),
            &Default::default()
        )
        .is_ok());
    }

    #[test]
    fn files_read_one_at_a_time_give_the_same_population_and_the_same_errors() {
        let f = "f 1 2 3\nf 1 3 4\n";
        // a good set, given out of order: the same population, source and all
        let (all, one) =
            both(&[("10.obj", quad_obj(0.3, f)), ("2.obj", quad_obj(0.1, f)), ("1.obj", quad_obj(0.0, f))]);
        let (all, one) = (all.unwrap(), one.unwrap());
        assert_eq!(one.names, all.names);
        assert_eq!(one.faces, all.faces);
        assert_eq!(one.points, all.points);
        assert_eq!(one.source, all.source);
        assert_eq!(one.normalization.scale, all.normalization.scale);
        // other faces in 2.obj, another vertex count in 10.obj: the first of them in natural order, as before
        let bad: Vec<(&str, Vec<u8>)> = vec![
            ("10.obj", b"v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n".to_vec()),
            ("1.obj", quad_obj(0.0, f)),
            ("2.obj", quad_obj(0.1, "f 1 2 4\nf 2 3 4\n")),
        ];
        let (all, one) = both(&bad);
        assert_eq!(messages(&one), messages(&all));
        assert!(messages(&one)[0].contains("2.obj"), "{:?}", messages(&one));
        // and with a file that does not read: that file's error and the first mismatch among the files that
        // read, in natural order, from both (not the mismatch only once the broken file is mended)
        let mut worse = bad.clone();
        worse.push(("3.obj", b"v 0 0 zero\n".to_vec()));
        let (all, one) = both(&worse);
        assert_eq!(messages(&one), messages(&all));
        let m = messages(&one);
        assert_eq!(m.len(), 2, "{m:?}");
        assert!(m[0].contains("2.obj") && m[0].contains("same faces") && m[1].contains("3.obj"), "{m:?}");
        // the files that read agree: the broken file's error alone
        let (all, one) =
            both(&[("1.obj", quad_obj(0.0, f)), ("2.obj", quad_obj(0.1, f)), ("3.obj", b"v 0 0 zero\n".to_vec())]);
        assert_eq!(messages(&one), messages(&all));
        assert!(messages(&one).len() == 1 && messages(&one)[0].contains("3.obj"), "{:?}", messages(&one));
        // the first mesh's own faults come first; one file alone is too few
        let (all, one) = both(&[("1.obj", quad_obj(0.0, "")), ("2.obj", quad_obj(0.1, f))]);
        assert_eq!(messages(&one), messages(&all));
        let (all, one) = both(&[("1.obj", quad_obj(0.0, "f 1 2 9\n"))]);
        assert_eq!(messages(&one), messages(&all));
    }

    #[test]
    fn files_read_twice_give_the_later_checks_errors_and_see_a_changed_file() {
        let f = "f 1 2 3\nf 1 3 4\n";
        // (the readers refuse non-finite numbers themselves) an extent too wide to scale, then every vertex at
        // one point: both readers agree
        let (all, one) = both(&[("1.obj", quad_obj(-1e308, f)), ("2.obj", quad_obj(1e308, f))]);
        assert_eq!(messages(&one), messages(&all));
        assert!(messages(&one)[0].contains("cannot scale into a unit box"), "{:?}", messages(&one));
        let dot = b"v 0 0 0\nv 0 0 0\nv 0 0 0\nv 0 0 0\nf 1 2 3\nf 1 3 4\n".to_vec();
        let (all, one) = both(&[("1.obj", dot.clone()), ("2.obj", dot)]);
        assert_eq!(messages(&one), messages(&all));
        assert!(messages(&one)[0].contains("at one point"), "{:?}", messages(&one));
        // a file that has another vertex count when it is read the second time
        let names = vec!["1.obj".to_string(), "2.obj".to_string()];
        let mut reads = 0;
        let changed = Population::read_one_at_a_time(
            &names,
            |i, buffer| {
                reads += 1;
                let dx = if reads == 3 { "0 0 0\nv 0.5" } else { "0.1" };
                buffer.extend_from_slice(&quad_obj(0.0, f));
                if i == 1 {
                    buffer.clear();
                    buffer.extend_from_slice(format!("v {dx} 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n{f}").as_bytes());
                }
                Ok(())
            },
            0,
        );
        let m = messages(&changed);
        assert!(m.len() == 1 && m[0].contains("2.obj") && m[0].contains("changed while it was read"), "{m:?}");
    }

    #[test]
    fn natural_order() {
        let mut v = vec!["10.obj", "2.obj", "1.obj", "reference.obj", "a10", "a9"];
        v.sort_by(|a, b| natural_cmp(a, b));
        assert_eq!(v, vec!["1.obj", "2.obj", "10.obj", "a9", "a10", "reference.obj"]);
    }

    #[test]
    fn one_common_scale_into_unit_box() {
        let p = Population::new(crate::mesh::Sources::Meshes(vec![("b".into(), tri(1.0)), ("a".into(), tri(0.0))]))
            .unwrap();
        assert_eq!(p.names, vec!["a", "b"]);
        let n = p.normalization;
        assert!((n.scale - 0.5).abs() < 1e-12);
        let back = n.to_original(p.point(1, 1));
        assert!((back[0] - 2.0).abs() < 1e-12);
    }

    /// From a folder or a list of paths, one OBJ/PLY file per pose is read and parsed file by file: the same
    /// population as from the files' bytes, and the same error (the first unreadable file in the given order,
    /// else the first file that does not parse in natural order).
    #[cfg(not(target_arch = "wasm32"))]
    #[test]
    fn paths_read_file_by_file_as_bytes_would() {
        let dir = std::env::temp_dir().join(format!("posemfa-paths-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let obj = |dx: f64| format!("v {dx} 0 0\nv 1 0 0\nv 0 2 0.5\nf 1 2 3\n").into_bytes();
        let ply = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n\
                    element face 1\nproperty list uchar int vertex_indices\nend_header\n3 0 0\n1 0 0\n0 2 0.5\n3 0 1 2\n";
        let files: Vec<(String, Vec<u8>)> =
            vec![("10.obj".into(), obj(0.25)), ("2.obj".into(), obj(-1.0)), ("3.ply".into(), ply.to_vec())];
        for (n, b) in &files {
            std::fs::write(dir.join(n), b).unwrap();
        }
        let from_bytes = Population::new(crate::mesh::Sources::Files(files.clone())).unwrap();
        assert_eq!(from_bytes.source, "2 OBJ and 1 PLY file");
        assert_eq!(Population::new(crate::mesh::Sources::paths(&[&dir])).unwrap(), from_bytes);
        let listed: Vec<_> = ["3.ply", "10.obj", "2.obj"].iter().map(|n| dir.join(n)).collect();
        assert_eq!(Population::new(crate::mesh::Sources::paths(&listed)).unwrap(), from_bytes);
        // Two files that do not parse: the first in natural order is named, as from the bytes.
        std::fs::write(dir.join("10.obj"), b"v 0 0 0\nv 1 0\n").unwrap();
        std::fs::write(dir.join("2.obj"), b"v 0 0 0\nf 1 1 7\n").unwrap();
        let e = Population::new(crate::mesh::Sources::paths(&[&dir])).unwrap_err().to_string();
        assert!(e.starts_with("file 2.obj, line 2:") && e.contains("index 7"), "{e}");
        // A file that cannot be read wins over one that does not parse, even one earlier in natural order.
        let listed = [dir.join("2.obj"), dir.join("9.obj"), dir.join("1.obj")];
        let e = Population::new(crate::mesh::Sources::paths(&listed)).unwrap_err().to_string();
        assert!(e.starts_with("cannot read ") && e.contains("9.obj"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn rejects_mismatch_naming_file() {
        let mut m = tri(0.0);
        m.positions.push([0.0, 0.0, 1.0]);
        let e = Population::new(crate::mesh::Sources::Meshes(vec![("a.obj".into(), tri(0.0)), ("b.obj".into(), m)]))
            .unwrap_err();
        assert!(e.to_string().contains("b.obj") && e.to_string().contains("4 vertices"), "{e}");
        let e = Population::new(crate::mesh::Sources::Meshes(vec![("a.obj".into(), tri(0.0))])).unwrap_err();
        assert!(e.to_string().contains("at least 2"), "{e}");
    }

    #[test]
    fn a_mismatch_between_two_files_of_one_name_tells_them_apart() {
        // 1.obj of a horse and 1.obj of a lion, dropped together from two folders
        let mut m = tri(0.0);
        m.positions.push([0.0, 0.0, 1.0]);
        // (a population refuses two files of one name at once; the mismatch among the files that read, listed
        // beside another file's error, still tells them apart)
        let e = check_same_mesh("1.obj", &tri(0.0), "1.obj", &m).unwrap_err();
        assert!(e.to_string().contains("has 4 vertices but the first file, also named 1.obj, has 3"), "{e}");
        let e = Population::new(crate::mesh::Sources::Meshes(vec![("1.obj".into(), tri(0.0)), ("1.obj".into(), m)]))
            .unwrap_err();
        assert!(e.to_string().contains("two of the files are named so"), "{e}");
    }
}
