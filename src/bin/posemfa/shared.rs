//! Option groups several subcommands take (each written once, `#[command(flatten)]` into the subcommands'
//! arguments), the value parsers they use, and the steps they share: read the inputs, fit, articulate.

use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::ValueHint;
use posemfa::export::gltf::{GltfOptions, Joints, Morphs, Weights};
use posemfa::mesh::gltf::PoseSource;
use posemfa::mesh::Population;
use posemfa::mfa::{Algorithm1Params, DistinctParams, FitStart, LambdaRule, Params, PartRule, TreeParams};
use posemfa::model_file::ModelFile;
use posemfa::parts::hierarchy::{FitResult, Pipeline, Progress, Stage};

// ---------------------------------------------------------------- value parsers

/// A value that must be one of `table`'s names (completions and "possible values" list them).
pub fn choice<T: Clone + Send + Sync + 'static>(
    table: &'static [(&'static str, T)],
) -> impl TypedValueParser<Value = T> {
    PossibleValuesParser::new(table.iter().map(|(name, _)| *name)).map(move |name| {
        let found = table.iter().find(|(n, _)| *n == name);
        found.expect("PossibleValuesParser passes only the table's names").1.clone()
    })
}

/// A pose number, from 1.
pub fn pose_number(v: &str) -> Result<usize, String> {
    v.parse::<usize>().map_err(|_| format!("'{v}' is not a pose number (poses are numbered from 1)"))
}

/// A 1-based pose number checked against the population; 0-based.
pub fn pose_index(name: &str, k: usize, n: usize) -> Result<usize, String> {
    if k == 0 || k > n {
        return Err(format!("{name} {k}: poses are numbered 1 to {n} (natural order of the file names)"));
    }
    Ok(k - 1)
}

/// `--bones`: "auto" (None: the part rule's own count) or a number.
#[derive(Clone, Copy)]
struct Bones(Option<usize>);

fn bones(v: &str) -> Result<Bones, String> {
    field(v, "targetParts", |p| p.target_parts).map(Bones)
}

/// A fit parameter read as the page's form reads it ([`Params::set_field`]): the same words for a value it
/// cannot use (what was typed, what is allowed).
fn field<T>(v: &str, name: &str, get: impl Fn(&Params) -> T) -> Result<T, String> {
    let mut p = Params::default();
    p.set_field(name, v)?;
    Ok(get(&p))
}

fn parts_value(v: &str) -> Result<usize, String> {
    field(v, "parts", |p| p.algorithm1.parts)
}

fn seed_value(v: &str) -> Result<u64, String> {
    field(v, "seed", |p| p.seed)
}

fn tol_value(v: &str) -> Result<f64, String> {
    field(v, "tol", |p| p.tol)
}

fn floor_value(v: &str) -> Result<f64, String> {
    field(v, "varianceFloor", |p| p.variance_floor)
}

/// The names of the generated populations (`synth:PRESET`, `posemfa generate PRESET`).
pub fn preset_names() -> Vec<&'static str> {
    posemfa::synth::Preset::ALL.iter().map(|p| p.name()).collect()
}

/// What DIR_OR_FILES may be, after "a": every format read ([`posemfa::mesh::load::formats_read`]) and the
/// presets.
pub fn inputs_help() -> String {
    format!(
        "folder of mesh files or the files themselves (posemfa reads {}; poses in natural order of the names), \
         or synth:PRESET[:VERTICES[:POSES[:SEED[:BAND[:MAX_ANGLE]]]]], a generated population ({}) whose ground \
         truth (adjusted Rand index, rotation error) is then reported too",
        posemfa::mesh::load::formats_read(),
        preset_names().join(", ")
    )
}

/// A preset by its name.
pub fn preset(name: &str) -> Result<posemfa::synth::Preset, String> {
    let found = posemfa::synth::Preset::ALL.iter().find(|p| p.name() == name);
    found.copied().ok_or_else(|| format!("unknown preset '{name}': use one of {}", preset_names().join(", ")))
}

// ---------------------------------------------------------------- inputs and fit options

const PART_RULES: &[(&str, PartRule)] =
    &[("tree", PartRule::Tree), ("distinct", PartRule::Distinct), ("threshold", PartRule::Threshold)];
const POSE_SOURCES: &[(&str, PoseSource)] =
    &[("animation", PoseSource::Animation), ("morph-targets", PoseSource::MorphTargets)];

/// The population to read: files, a folder or a generated population, and which mesh and poses of a glTF, FBX
/// or USD file. Every subcommand that reads a population.
#[derive(clap::Args)]
#[command(next_help_heading = "Input options")]
pub struct InputArgs {
    #[arg(value_name = "DIR_OR_FILES", required_unless_present = "model", value_hint = ValueHint::AnyPath,
          help = format!("A {}; with --model, optional: the poses the model was fitted to (when the model file was \
                          saved without them)", inputs_help()),
          help_heading = "Arguments")]
    pub inputs: Vec<String>,
    /// A fitted model (.posemfa, from `posemfa fit --save` or the page's Save model) in place of fitting: its
    /// parameters, parts and, when it holds them, its poses
    #[arg(long, value_name = "FILE.posemfa", value_hint = ValueHint::FilePath)]
    pub model: Option<std::path::PathBuf>,
    /// glTF, FBX, USD input: the mesh / object (name or index; default the animated one with most vertices,
    /// in glTF with every mesh its skin moves)
    #[arg(long = "object", visible_alias = "mesh", value_name = "NAME")]
    mesh: Option<String>,
    /// glTF / FBX input: the animation or take (name or index; default the one with most keyframes / longest)
    #[arg(long, value_name = "NAME")]
    animation: Option<String>,
    /// glTF / FBX / USD input: N evenly spaced times (default: the keyframes, frames or time samples)
    #[arg(long, value_name = "N")]
    frames: Option<usize>,
    /// glTF / FBX input: animation or morph-targets (default: the animation if one moves the mesh)
    #[arg(long, value_name = "WHAT", value_parser = choice(POSE_SOURCES))]
    poses_from: Option<PoseSource>,
}

impl InputArgs {
    pub fn gltf(&self) -> posemfa::mesh::gltf::Options {
        posemfa::mesh::gltf::Options {
            mesh: self.mesh.clone(),
            animation: self.animation.clone(),
            frames: self.frames,
            source: self.poses_from.unwrap_or_default(),
        }
    }

    /// The population (and its truth when generated).
    pub fn load(&self) -> Result<(Population, Option<posemfa::synth::Generated>), String> {
        load_inputs(&self.inputs, &self.gltf())
    }

    /// Refuses --model in a command that fits every time or fits nothing (`command` names it).
    pub fn no_model(&self, command: &str) -> Result<(), String> {
        match &self.model {
            Some(m) => Err(format!(
                "{command} does not use a saved fit; --model {} is for the commands that use one fit (fit, \
                 interpolate, export-gltf, rig-report, articulate-report)",
                m.display()
            )),
            None => Ok(()),
        }
    }
}

/// The model file at `path`, read and checked.
pub fn read_model(path: &std::path::Path) -> Result<ModelFile, String> {
    let name = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read model file {name}: {e}"))?;
    ModelFile::from_bytes(&name, &bytes).map_err(|e| e.to_string())
}

/// A fit: read from --model (with the poses of DIR_OR_FILES when given, checked to be the model's mesh), or made
/// now from the poses with the fit options. `quiet` false: the stages go to stderr as they start.
pub struct Fitted {
    pub params: Params,
    pub pop: Population,
    pub result: FitResult,
    pub truth: Option<posemfa::synth::Generated>,
    /// The poses are the model's reconstructions, not data: a model file saved without its poses and no
    /// DIR_OR_FILES.
    pub stand_in: bool,
    /// Read from --model: the figures measured on its poses (when it was saved, or now on DIR_OR_FILES).
    pub saved_summary: Option<posemfa::model_file::Summary>,
    /// Read from --model: the rig kept in the file, if any (used when a command asks for that very rig).
    pub saved_rig: Option<posemfa::model_file::SavedRig>,
}

impl FitArgs {
    /// The fit these options ask for (see [`Fitted`]).
    pub fn fitted(&self, quiet: bool) -> Result<Fitted, String> {
        let Some(path) = &self.input.model else {
            let start = self.start()?;
            let (params, pop, truth) = self.load()?;
            let result = run_fit(&params, &start, &pop, quiet)?;
            return Ok(Fitted { params, pop, result, truth, stand_in: false, saved_summary: None, saved_rig: None });
        };
        let mut saved = read_model(path)?;
        let mut truth = None;
        if !self.input.inputs.is_empty() {
            let (pop, t) = self.input.load()?;
            saved = saved.with_population(&path.display().to_string(), pop).map_err(|e| e.to_string())?;
            truth = t;
        }
        Ok(Fitted {
            stand_in: !saved.has_data,
            saved_summary: Some(saved.summary),
            saved_rig: saved.rig,
            params: saved.params,
            pop: saved.population,
            result: saved.result,
            truth,
        })
    }

    /// [`FitArgs::fitted`] for a command that needs the poses themselves (`command` names it): a model saved
    /// without them needs DIR_OR_FILES.
    pub fn fitted_with_data(&self, command: &str) -> Result<Fitted, String> {
        let f = self.fitted(true)?;
        if f.stand_in {
            let path = self.input.model.as_ref().map(|p| p.display().to_string()).unwrap_or_default();
            return Err(format!(
                "model file {path} was saved without its poses, and {command} needs them (the residuals, the skin \
                 weights and the errors are measured on them): give the poses it was fitted to after the options \
                 (DIR_OR_FILES), or save the model with its poses"
            ));
        }
        Ok(f)
    }
}

/// The inputs and the fit parameters: every subcommand that fits.
#[derive(clap::Args)]
#[command(next_help_heading = "Fit options")]
pub struct FitArgs {
    /// Algorithm 1's coarse parts (--part-rule distinct or threshold, --no-refine); the default merge tree
    /// ignores it
    #[arg(long, value_name = "M", default_value_t = Params::default().algorithm1.parts, value_parser = parts_value)]
    parts: usize,
    /// Algorithm 1's k-means++ seed; the default merge tree draws nothing at random and ignores it
    #[arg(long, value_name = "S", default_value_t = Params::default().seed, value_parser = seed_value)]
    seed: u64,
    /// Convergence tolerance on |dL|/n_v
    #[arg(long, value_name = "T", default_value_t = Params::default().tol, value_parser = tol_value)]
    tol: f64,
    /// Iteration cap per AECM run
    #[arg(long, value_name = "N", default_value_t = Params::default().max_iter)]
    max_iter: usize,
    /// Variance floor, unit-box units^2 for a shape of mean squared radius 0.09 (scaled by the population's own)
    #[arg(long, value_name = "F", default_value_t = Params::default().variance_floor, value_parser = floor_value)]
    floor: f64,
    /// The paper's literal eq 18 for Lambda (breaks monotonicity; for teaching)
    #[arg(long = "literal-eq18")]
    literal_eq18: bool,
    /// No parameter-expanded step at the end of cycle 2 (PX-EM, on by default; same optimum)
    #[arg(long)]
    no_px: bool,
    /// No SQUAREM acceleration of AECM (on by default; same optimum, still monotone)
    #[arg(long)]
    no_accel: bool,
    /// How the parts are found: tree (default: a merge tree of small patches, no random start), distinct
    /// (Algorithm 1 from k-means++ with the scale-free rule) or threshold (Algorithm 1 with the paper's rule)
    #[arg(long, value_name = "RULE", value_parser = choice(PART_RULES))]
    part_rule: Option<PartRule>,
    /// Part rules tree and distinct: a joint must explain K times a typical part's variance to keep two parts
    #[arg(long, value_name = "K", default_value_t = Params::default().distinct.distinct_ratio)]
    pub distinct_ratio: f64,
    /// Part rules tree and distinct: a part moving as a fixed blend of two neighbours to within B is flesh
    #[arg(long, value_name = "B", default_value_t = Params::default().distinct.blend_ratio)]
    blend_ratio: f64,
    /// The paper's part rule: stop splitting a part below this mean variance [default: 1e-5] (implies
    /// --part-rule threshold)
    #[arg(long, value_name = "E")]
    refine_threshold: Option<f64>,
    /// Algorithm 1: most sub-parts per coarse part
    #[arg(long, value_name = "N", default_value_t = Params::default().algorithm1.max_subparts)]
    max_subparts: usize,
    /// Tolerance of the coarse and refinement AECM runs
    #[arg(long, value_name = "T", default_value_t = Params::default().refine_tol)]
    refine_tol: f64,
    /// Stop after Algorithm 1's coarse AECM (--parts parts from k-means++), whatever --part-rule says: no part
    /// rule decides the count
    #[arg(long)]
    no_refine: bool,
    /// With at least 5N vertices: coarse and refinement stages on about N well-spread vertices, final AECM on
    /// all (0 = all)
    #[arg(long, value_name = "N", default_value_t = Params::default().algorithm1.subset_vertices)]
    subset: usize,
    /// With at least 2N vertices: the part decisions on a coarse mesh of about N vertices, the last AECM on all
    /// (N x 20 / poses with fewer than 20 poses; 0 = decide on all vertices)
    #[arg(long, value_name = "N", default_value_t = Params::default().tree.coarse_vertices)]
    coarse: usize,
    /// Exact part count: auto (the part rule's own count) or N (split / merge until N)
    #[arg(long, value_name = "N", default_value = "auto", value_parser = bones)]
    bones: Bones,
    /// Fit from this partition, with exactly its count (the page's Refine): a JSON array of one part per vertex,
    /// or a fit JSON (`fit --json`: its `labels`)
    #[arg(long, value_name = "FILE")]
    start_labels: Option<std::path::PathBuf>,
    /// (last: its options under their own heading)
    #[command(flatten)]
    pub input: InputArgs,
}

/// One part per vertex from `path`: a JSON array of labels, or a fit JSON's `labels`.
fn read_labels(path: &std::path::Path) -> Result<Vec<u32>, String> {
    let shown = path.display();
    let text = std::fs::read_to_string(path).map_err(|e| format!("--start-labels {shown}: cannot read it: {e}"))?;
    let value: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| format!("--start-labels {shown}: not JSON ({e}); give an array of labels or a fit JSON"))?;
    let labels = value.get("labels").unwrap_or(&value);
    serde_json::from_value(labels.clone()).map_err(|_| {
        format!(
            "--start-labels {shown}: not an array of whole numbers (one part per vertex) nor a fit JSON with `labels`"
        )
    })
}

impl FitArgs {
    /// The fit parameters asked for (the library's defaults for the rest).
    pub fn params(&self) -> Result<Params, String> {
        let d = Params::default();
        let mut p = Params {
            seed: self.seed,
            tol: self.tol,
            max_iter: self.max_iter,
            variance_floor: self.floor,
            refine_tol: self.refine_tol,
            target_parts: self.bones.0,
            tree: TreeParams { coarse_vertices: self.coarse },
            distinct: DistinctParams { distinct_ratio: self.distinct_ratio, blend_ratio: self.blend_ratio },
            algorithm1: Algorithm1Params {
                parts: self.parts,
                max_subparts: self.max_subparts,
                subset_vertices: self.subset,
                ..d.algorithm1.clone()
            },
            ..d
        };
        if self.literal_eq18 {
            p.lambda_rule = LambdaRule::PaperEq18;
        }
        p.px_em = !self.no_px;
        p.accelerate = !self.no_accel;
        p.refine = !self.no_refine;
        if let Some(rule) = self.part_rule {
            p.part_rule = rule;
        }
        if let Some(e) = self.refine_threshold {
            if let Some(rule @ (PartRule::Distinct | PartRule::Tree)) = self.part_rule {
                let name = PART_RULES.iter().find(|r| r.1 == rule).map_or("", |r| r.0);
                return Err(format!(
                    "--refine-threshold is the paper's part rule (threshold): leave out --part-rule {name}"
                ));
            }
            p.algorithm1.threshold.refine_threshold = e;
            p.part_rule = PartRule::Threshold;
        }
        Ok(p)
    }

    /// Where the fit starts: the partition of --start-labels, if given.
    pub fn start(&self) -> Result<FitStart, String> {
        Ok(FitStart { labels: self.start_labels.as_deref().map(read_labels).transpose()? })
    }

    /// The parameters (checked) and the population (and its truth when generated).
    pub fn load(&self) -> Result<(Params, Population, Option<posemfa::synth::Generated>), String> {
        self.input.no_model("this command")?;
        let params = self.params()?;
        params.validate().map_err(|e| e.to_string())?;
        let (pop, truth) = self.input.load()?;
        Ok((params, pop, truth))
    }
}

/// A folder / files, or `synth:PRESET[:VERTICES[:POSES[:SEED[:BAND[:MAX_ANGLE]]]]]` (a generated population
/// with its truth).
fn load_inputs(
    inputs: &[String],
    gltf: &posemfa::mesh::gltf::Options,
) -> Result<(Population, Option<posemfa::synth::Generated>), String> {
    if let [one] = inputs {
        if let Some(rest) = one.strip_prefix("synth:") {
            let mut it = rest.split(':');
            let preset = preset(it.next().unwrap_or("")).map_err(|e| format!("{e} (in '{one}')"))?;
            let mut spec = posemfa::synth::Spec { preset, ..Default::default() };
            let field = |v: Option<&str>, what: &str| -> Result<Option<f64>, String> {
                v.map(|v| v.parse::<f64>().map_err(|_| format!("{what} '{v}' in '{one}' is not a number"))).transpose()
            };
            let whole = |v: Option<&str>, what: &str| -> Result<Option<u64>, String> {
                v.map(|v| v.parse::<u64>().map_err(|_| format!("{what} '{v}' in '{one}' is not a number"))).transpose()
            };
            if let Some(v) = whole(it.next(), "vertex count")? {
                spec.vertices = v as usize;
            }
            if let Some(v) = whole(it.next(), "pose count")? {
                spec.poses = v as usize;
            }
            if let Some(v) = whole(it.next(), "seed")? {
                spec.seed = v;
            }
            if let Some(v) = field(it.next(), "joint band")? {
                spec.joint_band = v;
            }
            if let Some(v) = field(it.next(), "max angle")? {
                spec.max_angle_deg = v;
            }
            let g = posemfa::synth::generate(&spec).map_err(|e| e.to_string())?;
            return Ok((g.population.clone(), Some(g)));
        }
    }
    let options = posemfa::mesh::ReadOptions { gltf: gltf.clone() };
    let pop = Population::read(posemfa::mesh::Sources::paths(inputs), &options).map_err(|e| e[0].to_string())?;
    Ok((pop, None))
}

// ---------------------------------------------------------------- fit output (fit, bench)

/// Where the fit's result goes and how often it runs: fit and bench.
#[derive(clap::Args)]
#[command(next_help_heading = "Output")]
pub struct RunArgs {
    /// Write the result as JSON
    #[arg(long, value_name = "OUT", value_hint = ValueHint::FilePath)]
    pub json: Option<String>,
    /// No per-stage progress on stderr
    #[arg(long)]
    pub quiet: bool,
    /// Fit N times; times are the median
    #[arg(long, value_name = "N", default_value_t = 1)]
    repeat: usize,
}

impl RunArgs {
    /// How many fits (at least one).
    pub fn repeat(&self) -> usize {
        self.repeat.max(1)
    }
}

fn stage_name(s: &Stage) -> String {
    match s {
        Stage::Coarse => "coarse".into(),
        Stage::Refine { part, of, sub_parts } => format!("refining part {} of {of} ({sub_parts} sub-parts)", part + 1),
        Stage::Final { .. } => "final".into(),
        Stage::Done => "done".into(),
    }
}

/// Fits `pop` with `params` from `start`; with `quiet` false, each stage's name goes to stderr as it starts.
pub fn run_fit(params: &Params, start: &FitStart, pop: &Population, quiet: bool) -> Result<FitResult, String> {
    let mut pipe = Pipeline::starting(pop, params, start).map_err(|e| e.to_string())?;
    let mut last_stage = String::new();
    let mut observer = |p: &Progress| {
        let name = stage_name(&p.stage);
        let top = name.split(' ').next().unwrap_or("").to_string();
        if !quiet && top != last_stage {
            eprintln!("stage: {name}");
            last_stage = top;
        }
        true
    };
    pipe.run(&mut observer).map_err(|e| e.to_string())
}

pub fn write_json(path: &str, pop: &Population, result: &FitResult) -> Result<(), String> {
    let json = posemfa::export::json::fit_to_json(pop, result);
    std::fs::write(path, json).map_err(|e| format!("cannot write {path}: {e}"))
}

pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
    if v.is_empty() {
        0.0
    } else {
        v[v.len() / 2]
    }
}

/// Adjusted Rand index of the labels and rotation errors (degrees) against a generated population's truth
/// (`posemfa::metrics::GroundTruthAccuracy`: the same payload as the page's).
pub fn ground_truth_json(g: &posemfa::synth::Generated, m: &posemfa::mfa::Model) -> serde_json::Value {
    posemfa::metrics::ground_truth_accuracy(m, g)
        .and_then(|a| serde_json::to_value(a).map_err(|e| posemfa::Error::Io(e.to_string())))
        .unwrap_or_else(|e| serde_json::json!({ "error": e.to_string() }))
}

// ---------------------------------------------------------------- articulation (interpolate, export-gltf, reports)

/// The smooth skin weights' blend band: the articulation subcommands.
#[derive(clap::Args)]
#[command(next_help_heading = "Articulation options")]
pub struct BandArgs {
    /// Smooth weights: blend half-width as a fraction of the smaller part's RMS radius
    #[arg(long, value_name = "B", default_value_t = posemfa::articulate::skin::DEFAULT_BAND)]
    band: f64,
}

/// Fits (quietly) or reads --model, and builds the articulated model (`command` names the subcommand).
pub fn articulate_fit(
    command: &str,
    fit: &FitArgs,
    band: &BandArgs,
) -> Result<(Population, posemfa::articulate::Articulation), String> {
    let (pop, art, _) = articulate_fit_rig(command, fit, band)?;
    Ok((pop, art))
}

/// [`articulate_fit`], and the rig kept in the --model file if it has one.
pub fn articulate_fit_rig(
    command: &str,
    fit: &FitArgs,
    band: &BandArgs,
) -> Result<(Population, posemfa::articulate::Articulation, Option<posemfa::model_file::SavedRig>), String> {
    let f = fit.fitted_with_data(command)?;
    let art = band.articulate(&f.result, &f.pop)?;
    Ok((f.pop, art, f.saved_rig))
}

impl BandArgs {
    /// The articulated model of a fit.
    pub fn articulate(
        &self,
        result: &FitResult,
        pop: &Population,
    ) -> Result<posemfa::articulate::Articulation, String> {
        posemfa::articulate::Articulation::with_band(&result.model, pop, self.band).map_err(|e| e.to_string())
    }
}

const WEIGHTS: &[(&str, Weights)] =
    &[("rigid", Weights::Rigid), ("smooth", Weights::Smooth), ("fitted", Weights::Fitted)];
const JOINTS: &[(&str, Joints)] = &[("free", Joints::Free), ("fixed", Joints::Fixed)];
const MORPHS: &[(&str, Morphs)] = &[("none", Morphs::None), ("residual", Morphs::Residual)];

/// The rig a .glb carries: export-gltf and rig-report.
#[derive(clap::Args)]
#[command(next_help_heading = "Rig options")]
pub struct RigArgs {
    /// Skin weights: rigid (default), smooth (a prior) or fitted (SSDR against every pose)
    #[arg(long, value_name = "rigid|smooth|fitted", value_parser = choice(WEIGHTS))]
    weights: Option<Weights>,
    /// Most joints per vertex, 1 to 8 (default 4; JOINTS_1 past 4)
    #[arg(long, value_name = "K")]
    influences: Option<usize>,
    /// Free (default: bones move freely) or fixed (rotation-only local animation, constant bone lengths)
    #[arg(long, value_name = "free|fixed", value_parser = choice(JOINTS))]
    joints: Option<Joints>,
    /// None (default) or residual: one morph target per pose, so the clip reproduces every pose
    #[arg(long, value_name = "none|residual", value_parser = choice(MORPHS))]
    morphs: Option<Morphs>,
    /// Pose the mesh is bound in (default: the file named reference.obj if any, else 1)
    #[arg(long, value_name = "N", value_parser = pose_number)]
    bind: Option<usize>,
    /// Fitted weights, free joints: every bone also scales along three axes of its own (a scale channel on a
    /// leaf node per bone)
    #[arg(long)]
    bone_scale: bool,
    /// Fitted weights, free joints: every bone's motion is affine (rotation, scale along axes that turn from
    /// pose to pose, translation: two leaf nodes per bone), as Hyperspectral Inverse Skinning's bones
    #[arg(long)]
    bone_affine: bool,
    /// Fitted weights: a vertex's candidate bones are its part's and those within N steps of it in the part
    /// graph, 1 to 3 (default 1)
    #[arg(long, value_name = "N")]
    candidate_rings: Option<usize>,
    /// Fitted weights: most alternations of the weight, bone and bind-position solves (default 30)
    #[arg(long, value_name = "N")]
    alternations: Option<usize>,
    /// Fitted weights: the alternations stop once one lowers the squared error by less than this fraction
    /// (default 0.01; 0 runs every one of --alternations)
    #[arg(long, value_name = "T")]
    alternation_tol: Option<f64>,
}

impl RigArgs {
    /// Whether --weights was given.
    pub fn weights_given(&self) -> bool {
        self.weights.is_some()
    }

    /// The pose the rig is bound in, 0-based: --bind, else the file whose name (without extension) is
    /// `reference`, else the first.
    pub fn bind(&self, pop: &Population) -> Result<usize, String> {
        match self.bind {
            Some(k) => pose_index("--bind", k, pop.n_shapes()),
            None => Ok(posemfa::export::rig_report::default_bind_pose(pop)),
        }
    }

    /// The export options for this population.
    pub fn options(&self, pop: &Population) -> Result<GltfOptions, String> {
        let mut g = GltfOptions {
            weights: self.weights.unwrap_or_default(),
            joints: self.joints.unwrap_or_default(),
            morphs: self.morphs.unwrap_or_default(),
            bind_pose: self.bind(pop)?,
            bone_scale: self.bone_scale,
            bone_affine: self.bone_affine,
            ..Default::default()
        };
        if let Some(r) = self.candidate_rings {
            g.rings = r;
        }
        if let Some(n) = self.alternations {
            g.iterations = n;
        }
        if let Some(t) = self.alternation_tol {
            g.tol = t;
        }
        if let Some(k) = self.influences {
            g.influences = k;
        }
        g.rig_options().validate(pop.n_shapes()).map_err(|e| e.to_string())?;
        Ok(g)
    }
}
