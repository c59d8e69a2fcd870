//! posemfa command line. Run `posemfa help`.
//!
//! Layout, so that a subcommand or an option is added in one place:
//! - [`commands`] lists every subcommand: name, synopsis, one line of what it does, its arguments type and its
//!   function (`cmd_*`, one per subcommand).
//! - Every option is one row ([`Opt`]) of an option group ([`Group`]): name, value name, help, and how it sets its
//!   field. Groups shared by several subcommands (the fit options, the articulation band) are written once,
//!   generic over the subcommands' argument types through [`HasFit`] / [`HasBand`].
//! - [`parse`] turns the words after the subcommand into its arguments type with `lexopt` (which does the
//!   tokenising: `--name value`, `--name=value`, `--`), and `help` prints the same tables, so the help can never
//!   miss an option.

use posemfa::articulate::{Blend, RootRule, Skin};
use posemfa::export::gltf::Weights;
use posemfa::export::json::fit_to_json;
use posemfa::mesh::Population;
use posemfa::model::hierarchy::{FitResult, Pipeline, Progress, Stage};
use posemfa::model::{LambdaRule, Params, PartRule};
use std::ffi::OsString;
use std::io::Write;
use std::process::ExitCode;

/// println! that never panics (a closed pipe, e.g. `| head`, just ends the output).
macro_rules! out {
    ($($t:tt)*) => {{
        let _ = writeln!(std::io::stdout().lock(), $($t)*);
    }};
}

// ================================================================ the option machinery

/// One option of a subcommand whose arguments are a `T`.
struct Opt<T> {
    /// `--name`.
    name: &'static str,
    help: &'static str,
    kind: Kind<T>,
}

enum Kind<T> {
    /// `--name`: sets its field.
    Flag(fn(&mut T)),
    /// `--name VALUE` (the value's name in the help): stores the value, or says what is wrong with it (the caller
    /// names the option).
    Value(&'static str, fn(&mut T, &str) -> Result<(), String>),
}

fn val<T>(
    name: &'static str,
    value: &'static str,
    help: &'static str,
    set: fn(&mut T, &str) -> Result<(), String>,
) -> Opt<T> {
    Opt { name, help, kind: Kind::Value(value, set) }
}

fn flag<T>(name: &'static str, help: &'static str, set: fn(&mut T)) -> Opt<T> {
    Opt { name, help, kind: Kind::Flag(set) }
}

/// A titled list of options. `shared` groups (used by several subcommands) are printed once by `posemfa help`.
struct Group<T> {
    title: &'static str,
    shared: bool,
    opts: Vec<Opt<T>>,
}

/// A subcommand's arguments: its option groups and what it does with a word that is not an option.
trait Args: Default + 'static {
    fn groups() -> Vec<Group<Self>>;
    fn positional(&mut self, word: String) -> Result<(), String>;
}

/// Stores a text value.
fn text(slot: &mut Option<String>, v: &str) -> Result<(), String> {
    *slot = Some(v.to_string());
    Ok(())
}

fn num<N: std::str::FromStr>(v: &str) -> Result<N, String> {
    v.parse().map_err(|_| format!("'{v}' is not a valid number"))
}

/// The value named `v` among `choices`; otherwise an error listing them ("'x': use a, b or c").
fn one_of<V: Copy>(v: &str, choices: &[(&str, V)]) -> Result<V, String> {
    if let Some(&(_, value)) = choices.iter().find(|(name, _)| *name == v) {
        return Ok(value);
    }
    let names: Vec<&str> = choices.iter().map(|(name, _)| *name).collect();
    let list = match names.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => names.join(""),
    };
    Err(format!("'{v}': use {list}"))
}

/// Parses `words` (the arguments after the subcommand) into `T`; `Ok(None)` when `--help` / `-h` was asked for.
fn parse<T: Args>(cmd: &str, words: Vec<OsString>) -> Result<Option<T>, String> {
    use lexopt::prelude::*;
    let groups = T::groups();
    let mut args = T::default();
    let mut p = lexopt::Parser::from_args(words);
    let see = format!("(`posemfa help {cmd}` lists its options)");
    while let Some(arg) = p.next().map_err(|e| format!("{cmd}: {e} {see}"))? {
        match arg {
            Long("help") | Short('h') => return Ok(None),
            Long(name) => {
                let name = format!("--{name}");
                let opt = groups
                    .iter()
                    .flat_map(|g| &g.opts)
                    .find(|o| o.name == name)
                    .ok_or_else(|| format!("{cmd}: unknown option {name} {see}"))?;
                match opt.kind {
                    Kind::Flag(set) => set(&mut args),
                    Kind::Value(what, set) => {
                        let missing = || format!("{cmd}: {name} needs a value ({name} {what})");
                        let v =
                            p.value().map_err(|_| missing())?.string().map_err(|e| format!("{cmd}: {name}: {e}"))?;
                        if v.starts_with("--") {
                            return Err(format!("{} (got the option {v})", missing()));
                        }
                        set(&mut args, &v).map_err(|e| format!("{cmd}: {name}: {e}"))?;
                    }
                }
            }
            Short(c) => return Err(format!("{cmd}: unknown option -{c} {see}")),
            Value(word) => {
                let word = word.string().map_err(|e| format!("{cmd}: {e}"))?;
                args.positional(word).map_err(|e| format!("{cmd}: {e} {see}"))?;
            }
        }
    }
    Ok(Some(args))
}

/// Help text of a group, one option per line.
struct GroupHelp {
    title: &'static str,
    shared: bool,
    lines: Vec<(String, &'static str)>,
}

/// One subcommand.
struct Command {
    name: &'static str,
    synopsis: &'static str,
    about: &'static str,
    groups: Vec<GroupHelp>,
    run: Box<dyn Fn(Vec<OsString>) -> Result<(), String>>,
}

fn command<T: Args>(
    name: &'static str,
    synopsis: &'static str,
    about: &'static str,
    run: fn(T) -> Result<(), String>,
) -> Command {
    let groups = T::groups()
        .into_iter()
        .map(|g| GroupHelp {
            title: g.title,
            shared: g.shared,
            lines: g
                .opts
                .iter()
                .map(|o| match o.kind {
                    Kind::Flag(_) => (o.name.to_string(), o.help),
                    Kind::Value(v, _) => (format!("{} {v}", o.name), o.help),
                })
                .collect(),
        })
        .collect();
    Command {
        name,
        synopsis,
        about,
        groups,
        run: Box::new(move |words| match parse::<T>(name, words)? {
            Some(args) => run(args),
            None => {
                out!("{}", command_help(&commands(), name).unwrap_or_default());
                Ok(())
            }
        }),
    }
}

const HEADER: &str = "posemfa: learn rigid parts and their motion from registered triangle meshes

Inputs (DIR_OR_FILES): a folder of OBJ files, the files themselves (natural order of the names), or
synth:PRESET[:VERTICES[:POSES[:SEED[:BAND[:MAX_ANGLE]]]]], a generated population (quadruped, arm, snake,
blob, spider, giraffe, hand) whose ground truth (adjusted Rand index, rotation error) is then reported
too. Poses are numbered from 1.";

fn group_text(g: &GroupHelp) -> String {
    let mut s = format!("  {}:\n", g.title);
    for (left, help) in &g.lines {
        if left.len() <= 22 {
            s += &format!("    {left:<22} {help}\n");
        } else {
            s += &format!("    {left}\n    {:<22} {help}\n", "");
        }
    }
    s
}

fn command_text(c: &Command, shared_in_full: bool) -> String {
    let mut s = format!("posemfa {} {}\n    {}\n", c.name, c.synopsis, c.about);
    let mut elsewhere = Vec::new();
    for g in &c.groups {
        if g.shared && !shared_in_full {
            elsewhere.push(g.title);
        } else {
            s += &group_text(g);
        }
    }
    if !elsewhere.is_empty() {
        s += &format!("  and the {} (below)\n", elsewhere.join(", the "));
    }
    s
}

/// `posemfa help`: every subcommand with its options; each shared group once, at the end.
fn full_help(cmds: &[Command]) -> String {
    let mut s =
        format!("{HEADER}\n\nUSAGE: posemfa COMMAND ARGS... [options]   (`posemfa help COMMAND`: one command)\n");
    let mut shared: Vec<&GroupHelp> = Vec::new();
    for c in cmds {
        s += "\n";
        s += &command_text(c, false);
        for g in c.groups.iter().filter(|g| g.shared) {
            if !shared.iter().any(|h| h.title == g.title) {
                shared.push(g);
            }
        }
    }
    for g in shared {
        s += "\n";
        s += &group_text(g);
    }
    s += "\nposemfa help [COMMAND]\n    this help, or one command's (also `posemfa COMMAND --help`)\n";
    s
}

fn command_help(cmds: &[Command], name: &str) -> Option<String> {
    cmds.iter().find(|c| c.name == name).map(|c| format!("{HEADER}\n\n{}", command_text(c, true)))
}

// ================================================================ the subcommands

/// Every subcommand, in the order `posemfa help` lists them.
fn commands() -> Vec<Command> {
    vec![
        command::<InspectArgs>(
            "inspect",
            "FILE.obj",
            "print vertices and triangles as JSON (exit 1 on error)",
            cmd_inspect,
        ),
        command::<FitRun>(
            "fit",
            "DIR_OR_FILES... [options]",
            "fit the model (Algorithm 1) and print a summary",
            cmd_fit,
        ),
        command::<FitRun>(
            "bench",
            "DIR_OR_FILES... [options]",
            "fit and print per-stage figures as JSON (time, iterations, E-step GFLOP/s, kernel limits, peak memory)",
            cmd_bench,
        ),
        command::<GenerateArgs>(
            "generate",
            "PRESET --out DIR [options]",
            "write a generated population (quadruped, arm, snake, blob, spider, giraffe, hand) as OBJ files",
            cmd_generate,
        ),
        command::<InterpolateArgs>(
            "interpolate",
            "DIR_OR_FILES... --from I --to J --t T --out pose.obj [options]",
            "fit, then write one interpolated pose as OBJ in the original units with the population's faces",
            cmd_interpolate,
        ),
        command::<GltfArgs>(
            "export-gltf",
            "DIR_OR_FILES... --out model.glb [options]",
            "fit, then write binary glTF 2.0: mesh bound in one pose, skeleton, skin (rigid, smooth or fitted\n    \
             weights), clips \"training poses\" (one pose per second) and \"interpolated\" (rigid/smooth, free joints)",
            cmd_export_gltf,
        ),
        command::<RigReportArgs>(
            "rig-report",
            "DIR_OR_FILES... [--glb FILE.glb] [options]",
            "fit, build and write the rig, then play its .glb's \"training poses\" clip by linear blend skinning and\n    \
             print E_RMS (Kavan et al. 2010), max error, per-pose errors and time per stage as JSON",
            cmd_rig_report,
        ),
        command::<ReportArgs>(
            "articulate-report",
            "DIR_OR_FILES... --from I --to J [options]",
            "fit, then print endpoint errors, volume and edge stretch at t for every interpolation method, as JSON",
            cmd_articulate_report,
        ),
    ]
}

fn main() -> ExitCode {
    let mut words: Vec<OsString> = std::env::args_os().skip(1).collect();
    let cmds = commands();
    let first = words.first().map(|w| w.to_string_lossy().into_owned());
    let res = match first.as_deref() {
        None => Err(format!("no command\n\n{}", full_help(&cmds))),
        Some("help" | "--help" | "-h") => match words.get(1).map(|w| w.to_string_lossy().into_owned()) {
            None => {
                out!("{}", full_help(&cmds));
                Ok(())
            }
            Some(name) => match command_help(&cmds, &name) {
                Some(h) => {
                    out!("{h}");
                    Ok(())
                }
                None => Err(format!("help: unknown command '{name}' (commands: {})", names(&cmds))),
            },
        },
        Some(name) => match cmds.iter().find(|c| c.name == name) {
            Some(c) => (c.run)(words.split_off(1)),
            None => Err(format!("unknown command '{name}' (commands: {}; `posemfa help` lists them)", names(&cmds))),
        },
    };
    match res {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn names(cmds: &[Command]) -> String {
    cmds.iter().map(|c| c.name).collect::<Vec<_>>().join(", ")
}

// ---------------------------------------------------------------- shared option groups

/// Inputs and fit parameters: every subcommand that fits.
#[derive(Default)]
struct FitArgs {
    inputs: Vec<String>,
    params: Params,
    /// Choices for glTF inputs.
    gltf: posemfa::mesh::gltf::Options,
}

trait HasFit {
    fn fit(&mut self) -> &mut FitArgs;
}

fn fit_group<T: HasFit>() -> Group<T> {
    Group {
        title: "fit options",
        shared: true,
        opts: vec![
            val("--parts", "M", "coarse parts (default 11)", |o: &mut T, v| num(v).map(|n| o.fit().params.parts = n)),
            val("--seed", "S", "random seed (default 0)", |o: &mut T, v| num(v).map(|n| o.fit().params.seed = n)),
            val("--tol", "T", "convergence tolerance on |dL|/n_v (default 1e-3)", |o: &mut T, v| {
                num(v).map(|n| o.fit().params.tol = n)
            }),
            val("--max-iter", "N", "iteration cap per AECM run (default 300)", |o: &mut T, v| {
                num(v).map(|n| o.fit().params.max_iter = n)
            }),
            val("--floor", "F", "variance floor, unit-box units^2 (default 1e-7)", |o: &mut T, v| {
                num(v).map(|n| o.fit().params.variance_floor = n)
            }),
            flag(
                "--literal-eq18",
                "the paper's literal eq 18 for Lambda (breaks monotonicity; for teaching)",
                |o: &mut T| {
                    o.fit().params.lambda_rule = LambdaRule::PaperEq18;
                },
            ),
            flag(
                "--no-px",
                "no parameter-expanded step at the end of cycle 2 (PX-EM, on by default; same optimum)",
                |o: &mut T| {
                    o.fit().params.px_em = false;
                },
            ),
            flag(
                "--no-accel",
                "no SQUAREM acceleration of AECM (on by default; same optimum, still monotone)",
                |o: &mut T| {
                    o.fit().params.accelerate = false;
                },
            ),
            val("--part-rule", "RULE", "how the part count is decided: distinct (default, scale-free) or threshold (the paper's)", |o: &mut T, v| {
                one_of(v, &[("distinct", PartRule::Distinct), ("threshold", PartRule::Threshold)]).map(|x| o.fit().params.part_rule = x)
            }),
            val(
                "--distinct-ratio",
                "K",
                "part rule distinct: a joint must explain K times a typical part's variance to keep two parts (default 4)",
                |o: &mut T, v| num(v).map(|n| o.fit().params.distinct_ratio = n),
            ),
            val(
                "--blend-ratio",
                "B",
                "part rule distinct: a part moving as a fixed blend of two neighbours to within B is flesh (default 0.1)",
                |o: &mut T, v| num(v).map(|n| o.fit().params.blend_ratio = n),
            ),
            val(
                "--refine-threshold",
                "E",
                "the paper's part rule: stop splitting a part below this mean variance (default 1e-5; implies --part-rule threshold)",
                |o: &mut T, v| {
                    num(v).map(|n| {
                        o.fit().params.refine_threshold = n;
                        o.fit().params.part_rule = PartRule::Threshold;
                    })
                },
            ),
            val("--max-subparts", "N", "Algorithm 1: most sub-parts per coarse part (default 6)", |o: &mut T, v| {
                num(v).map(|n| o.fit().params.max_subparts = n)
            }),
            val(
                "--refine-tol",
                "T",
                "tolerance of the coarse and refinement AECM runs (default 1e-2)",
                |o: &mut T, v| num(v).map(|n| o.fit().params.refine_tol = n),
            ),
            flag("--no-refine", "stop after the coarse AECM", |o: &mut T| o.fit().params.refine = false),
            val(
                "--subset",
                "N",
                "with at least 5N vertices: coarse and refinement stages on about N well-spread vertices, final AECM on all (default 2000; 0 = all)",
                |o: &mut T, v| num(v).map(|n| o.fit().params.subset_vertices = n),
            ),
            val("--bones", "N", "exact part count: auto (default, Algorithm 1's own) or N (split / merge until N)", |o: &mut T, v| {
                o.fit().params.target_parts = if v == "auto" { None } else { Some(num(v)?) };
                Ok(())
            }),
            val("--mesh", "NAME", "glTF input: the mesh (name or index; default the one with most vertices)", |o: &mut T, v| {
                text(&mut o.fit().gltf.mesh, v)
            }),
            val("--animation", "NAME", "glTF input: the animation (name or index; default the one with most keyframes)", |o: &mut T, v| {
                text(&mut o.fit().gltf.animation, v)
            }),
            val("--frames", "N", "glTF input: sample the animation at N evenly spaced times (default: its keyframes)", |o: &mut T, v| {
                num(v).map(|n| o.fit().gltf.frames = Some(n))
            }),
            val("--poses-from", "WHAT", "glTF input: animation or morph-targets (default: the animation if one moves the mesh)", |o: &mut T, v| {
                one_of(
                    v,
                    &[
                        ("animation", posemfa::mesh::gltf::PoseSource::Animation),
                        ("morph-targets", posemfa::mesh::gltf::PoseSource::MorphTargets),
                    ],
                )
                .map(|x| o.fit().gltf.source = x)
            }),
        ],
    }
}

impl FitArgs {
    /// The population (and its truth when generated), after checking the parameters.
    fn load(&self) -> Result<(Population, Option<posemfa::synth::Generated>), String> {
        if self.inputs.is_empty() {
            return Err("no input: give a folder of OBJ files, the files, or synth:PRESET".into());
        }
        self.params.validate().map_err(|e| e.to_string())?;
        load_inputs(&self.inputs, &self.gltf)
    }
}

/// Half-width of the smooth skin weights' blend band: the articulation subcommands.
trait HasBand {
    fn band(&mut self) -> &mut Option<f64>;
}

fn band_group<T: HasBand>() -> Group<T> {
    Group {
        title: "articulation options",
        shared: true,
        opts: vec![val(
            "--band",
            "B",
            "smooth weights: blend half-width as a fraction of the smaller part's RMS radius (default 1)",
            |o: &mut T, v| num(v).map(|n| *o.band() = Some(n)),
        )],
    }
}

/// For an articulation subcommand's arguments (fields `fit` and `band`, options in `options()`): `HasFit`,
/// `HasBand`, and `Args` with its own options, then the articulation and fit options; words are inputs.
macro_rules! articulation_args {
    ($t:ty, rig) => {
        impl HasFit for $t {
            fn fit(&mut self) -> &mut FitArgs {
                &mut self.fit
            }
        }
        impl HasBand for $t {
            fn band(&mut self) -> &mut Option<f64> {
                &mut self.band
            }
        }
        impl HasRig for $t {
            fn rig(&mut self) -> &mut RigArgs {
                &mut self.rig
            }
        }
        impl Args for $t {
            fn groups() -> Vec<Group<Self>> {
                vec![<$t>::options(), rig_group(), band_group(), fit_group()]
            }
            fn positional(&mut self, word: String) -> Result<(), String> {
                self.fit.inputs.push(word);
                Ok(())
            }
        }
    };
    ($t:ty) => {
        impl HasFit for $t {
            fn fit(&mut self) -> &mut FitArgs {
                &mut self.fit
            }
        }
        impl HasBand for $t {
            fn band(&mut self) -> &mut Option<f64> {
                &mut self.band
            }
        }
        impl Args for $t {
            fn groups() -> Vec<Group<Self>> {
                vec![<$t>::options(), band_group(), fit_group()]
            }
            fn positional(&mut self, word: String) -> Result<(), String> {
                self.fit.inputs.push(word);
                Ok(())
            }
        }
    };
}

fn pose_number(v: &str) -> Result<usize, String> {
    v.parse::<usize>().map_err(|_| format!("'{v}' is not a pose number (poses are numbered from 1)"))
}

/// A 1-based pose number checked against the population; 0-based.
fn pose_index(name: &str, k: Option<usize>, n: usize) -> Result<usize, String> {
    let k = k.ok_or_else(|| format!("{name} is required"))?;
    if k == 0 || k > n {
        return Err(format!("{name} {k}: poses are numbered 1 to {n} (natural order of the file names)"));
    }
    Ok(k - 1)
}

// ---------------------------------------------------------------- inspect

#[derive(Default)]
struct InspectArgs {
    file: Option<String>,
}

impl Args for InspectArgs {
    fn groups() -> Vec<Group<Self>> {
        Vec::new()
    }
    fn positional(&mut self, word: String) -> Result<(), String> {
        if self.file.is_some() {
            return Err(format!("inspect takes one file (got a second: {word})"));
        }
        self.file = Some(word);
        Ok(())
    }
}

fn cmd_inspect(a: InspectArgs) -> Result<(), String> {
    let file = a.file.ok_or("inspect: give one OBJ file (posemfa inspect FILE.obj)")?;
    let bytes = std::fs::read(&file).map_err(|e| format!("cannot read {file}: {e}"))?;
    let name = std::path::Path::new(&file).file_name().map_or(file.clone(), |n| n.to_string_lossy().into_owned());
    let mesh = posemfa::mesh::obj::parse_obj(&name, &bytes).map_err(|e| e.to_string())?;
    let out = serde_json::json!({
        "file": name,
        "n_vertices": mesh.positions.len(),
        "n_triangles": mesh.faces.len(),
        "vertices": mesh.positions,
        "triangles": mesh.faces,
    });
    out!("{out}");
    Ok(())
}

// ---------------------------------------------------------------- fit, bench

struct FitRun {
    fit: FitArgs,
    json: Option<String>,
    quiet: bool,
    repeat: usize,
}

impl Default for FitRun {
    fn default() -> Self {
        FitRun { fit: FitArgs::default(), json: None, quiet: false, repeat: 1 }
    }
}

impl HasFit for FitRun {
    fn fit(&mut self) -> &mut FitArgs {
        &mut self.fit
    }
}

impl Args for FitRun {
    fn groups() -> Vec<Group<Self>> {
        vec![
            Group {
                title: "output",
                shared: false,
                opts: vec![
                    val("--json", "OUT", "write the result as JSON", |o: &mut Self, v| text(&mut o.json, v)),
                    flag("--quiet", "no per-stage progress on stderr", |o: &mut Self| o.quiet = true),
                    val("--repeat", "N", "fit N times; times are the median (default 1)", |o: &mut Self, v| {
                        num::<usize>(v).map(|n| o.repeat = n.max(1))
                    }),
                ],
            },
            fit_group(),
        ]
    }
    fn positional(&mut self, word: String) -> Result<(), String> {
        self.fit.inputs.push(word);
        Ok(())
    }
}

fn stage_name(s: &Stage) -> String {
    match s {
        Stage::Coarse => "coarse".into(),
        Stage::Refine { part, of, sub_parts } => format!("refining part {} of {of} ({sub_parts} sub-parts)", part + 1),
        Stage::Final => "final".into(),
        Stage::Done => "done".into(),
    }
}

/// Fits `pop` with `params`; with `quiet` false, each stage's name goes to stderr as it starts.
fn run_fit(params: &Params, pop: &Population, quiet: bool) -> Result<FitResult, String> {
    let mut pipe = Pipeline::new(pop, params).map_err(|e| e.to_string())?;
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

fn cmd_fit(o: FitRun) -> Result<(), String> {
    let t_load = posemfa::clock::now_ms();
    let (pop, truth) = o.fit.load()?;
    let load_ms = posemfa::clock::now_ms() - t_load;
    let mut totals = Vec::new();
    let mut result = None;
    for _ in 0..o.repeat {
        let t0 = posemfa::clock::now_ms();
        result = Some(run_fit(&o.fit.params, &pop, o.quiet)?);
        totals.push(posemfa::clock::now_ms() - t0);
    }
    let result = result.expect("repeat is at least 1");
    let m = &result.model;
    let s = &result.stages;
    out!(
        "{} shapes x {} vertices | parts: coarse {} -> refined {} -> final {} | final AECM {} iterations ({}) | RMSE {:.5} (unit box) | {:.0} ms (load {:.0} ms)",
        pop.n_shapes(),
        pop.n_vertices(),
        s.coarse_parts,
        s.refined_parts,
        s.final_parts,
        m.iterations,
        if m.converged { "converged" } else { "NOT converged: iteration cap reached" },
        m.rmse(&pop),
        median(&mut totals),
        load_ms
    );
    let d = posemfa::model::diagnosis::diagnose_fit(&pop, &result);
    out!("  {}: {}", if d.articulated { "articulated" } else { "NOT articulated" }, d.reason);
    if let Some(g) = &truth {
        out!("  ground truth: {}", ground_truth_json(g, m));
    } else {
        out!("  poses: {}", pop.source);
    }
    if let [.., last] = result.part_curve.as_slice() {
        out!(
            "  part rule: {} merges from {} parts; the next pair scored {:.2} (kept apart from {}: --distinct-ratio)",
            result.part_curve.len() - 1,
            result.part_curve[0].parts,
            last.score,
            o.fit.params.distinct_ratio
        );
    }
    for st in &result.stats {
        out!("  {:<7} {:>8.1} ms  {:>5} iterations in {:>3} AECM runs", st.name, st.ms, st.iterations, st.aecm_runs);
    }
    if let Some(path) = &o.json {
        write_json(path, &pop, &result)?;
        out!("wrote {path}");
    }
    Ok(())
}

fn cmd_bench(o: FitRun) -> Result<(), String> {
    let t_load = posemfa::clock::now_ms();
    let (pop, truth) = o.fit.load()?;
    let load_ms = posemfa::clock::now_ms() - t_load;
    // the kernels right after each fit, so that each fraction compares two measurements of one moment
    let data = posemfa::model::data::Data::from_population(&pop);
    let mut totals = Vec::new();
    let mut limits = Vec::new();
    let mut result = None;
    for _ in 0..o.repeat {
        let t0 = posemfa::clock::now_ms();
        let r = run_fit(&o.fit.params, &pop, o.quiet)?;
        totals.push(posemfa::clock::now_ms() - t0);
        limits.push(posemfa::model::limit::limit_report(&data, &r.model.parts, &r.stats, 200.0));
        result = Some(r);
    }
    let result = result.expect("repeat is at least 1");
    let m = &result.model;
    let mut fractions: Vec<f64> = limits.iter().map(|l| l.fraction).collect();
    let limit = limits.last().expect("repeat is at least 1");
    let vertex_major = posemfa::model::estep::kernel_rate_vertex_major(&data, &m.parts, 200.0);
    let stages: Vec<_> = result
        .stats
        .iter()
        .zip(&limit.stage_fractions)
        .map(|(s, fraction)| {
            serde_json::json!({
                "stage": s.name, "ms": s.ms, "iterations": s.iterations, "aecm_runs": s.aecm_runs,
                "estep_ms": s.estep_ms, "estep_gflop": s.estep_flops / 1e9, "estep_gflop_f32": s.estep_flops_f32 / 1e9,
                "estep_gflops_per_s": if s.estep_ms > 0.0 { s.estep_flops / s.estep_ms / 1e6 } else { 0.0 },
                "estep_fraction_of_limit": fraction,
            })
        })
        .collect();
    let fit_ms = median(&mut totals.clone());
    let out = serde_json::json!({
        "runtime": "native",
        "inputs": o.fit.inputs, "shapes": pop.n_shapes(), "vertices": pop.n_vertices(),
        "load_ms": load_ms, "fit_ms_median": fit_ms, "fit_ms_all": totals,
        "parts": m.n_parts(), "rmse": m.rmse(&pop), "iterations": result.stats.iter().map(|s| s.iterations).sum::<usize>(),
        "stages": stages,
        "kernel_limit_f64": limit.f64, "kernel_limit_f32": limit.f32,
        "estep_fraction_of_limit": median(&mut fractions), "estep_fraction_of_limit_all": fractions,
        "kernel_vertex_major_f64": vertex_major,
        "peak_memory_bytes": peak_rss_bytes(),
        "ground_truth": truth.as_ref().map(|g| ground_truth_json(g, m)),
    });
    out!("{}", serde_json::to_string_pretty(&out).unwrap_or_default());
    if let Some(path) = &o.json {
        write_json(path, &pop, &result)?;
    }
    Ok(())
}

fn write_json(path: &str, pop: &Population, result: &FitResult) -> Result<(), String> {
    std::fs::write(path, fit_to_json(pop, result)).map_err(|e| format!("cannot write {path}: {e}"))
}

/// Peak resident set of this process (Linux: VmHWM in /proc/self/status), or null elsewhere.
fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
    if v.is_empty() {
        0.0
    } else {
        v[v.len() / 2]
    }
}

/// A folder / files, or `synth:PRESET[:VERTICES[:POSES[:SEED[:BAND[:MAX_ANGLE]]]]]` (a generated population with its truth).
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
    Ok((Population::from_paths_with(inputs, gltf).map_err(|e| e.to_string())?, None))
}

fn preset(name: &str) -> Result<posemfa::synth::Preset, String> {
    serde_json::from_value(serde_json::json!(name))
        .map_err(|_| {
            let all: Vec<&str> = posemfa::synth::Preset::ALL.iter().map(|p| p.name()).collect();
            format!("unknown preset '{name}': use one of {}", all.join(", "))
        })
}

/// Adjusted Rand index of the labels and rotation errors (degrees) against a generated population's truth
/// (`posemfa::metrics::GroundTruthAccuracy`: the same payload as the page's).
fn ground_truth_json(g: &posemfa::synth::Generated, m: &posemfa::model::Model) -> serde_json::Value {
    posemfa::metrics::ground_truth_accuracy(m, g)
        .and_then(|a| serde_json::to_value(a).map_err(|e| posemfa::Error::Io(e.to_string())))
        .unwrap_or_else(|e| serde_json::json!({ "error": e.to_string() }))
}

// ---------------------------------------------------------------- generate

#[derive(Default)]
struct GenerateArgs {
    spec: posemfa::synth::Spec,
    format: Option<String>,
    preset_given: bool,
    out: Option<String>,
}

impl Args for GenerateArgs {
    fn groups() -> Vec<Group<Self>> {
        vec![Group {
            title: "generate options",
            shared: false,
            opts: vec![
                val("--out", "DIR", "folder to write the files to (required)", |o: &mut Self, v| {
                    text(&mut o.out, v)
                }),
                val(
                    "--format",
                    "F",
                    "obj (default), ply (binary, float32), ply-ascii, pc2 (one point cache + rest.obj), glb (one \
                     .glb: morph target per pose, animated one per frame)",
                    |o: &mut Self, v| match v {
                        "obj" | "ply" | "ply-ascii" | "pc2" | "glb" => text(&mut o.format, v),
                        _ => Err(format!("--format takes obj, ply, ply-ascii, pc2 or glb, not '{v}'")),
                    },
                ),
                val("--vertices", "N", "vertex count (default 10000)", |o: &mut Self, v| {
                    num(v).map(|n| o.spec.vertices = n)
                }),
                val("--poses", "P", "pose count (default 20)", |o: &mut Self, v| num(v).map(|n| o.spec.poses = n)),
                val("--seed", "S", "random seed (default 0)", |o: &mut Self, v| num(v).map(|n| o.spec.seed = n)),
                val(
                    "--band",
                    "B",
                    "half-width of the flesh band around each joint (default 0.05)",
                    |o: &mut Self, v| num(v).map(|n| o.spec.joint_band = n),
                ),
                val("--noise", "X", "vertex noise, standard deviation (default 0)", |o: &mut Self, v| {
                    num(v).map(|n| o.spec.noise = n)
                }),
                val("--max-angle", "DEG", "largest joint angle, degrees (default 40)", |o: &mut Self, v| {
                    num(v).map(|n| o.spec.max_angle_deg = n)
                }),
            ],
        }]
    }
    fn positional(&mut self, word: String) -> Result<(), String> {
        if self.preset_given {
            return Err(format!("unexpected argument '{word}' (generate takes one PRESET)"));
        }
        self.spec.preset = preset(&word)?;
        self.preset_given = true;
        Ok(())
    }
}

fn cmd_generate(a: GenerateArgs) -> Result<(), String> {
    let out_dir = a.out.ok_or("generate needs --out DIR")?;
    let g = posemfa::synth::generate(&a.spec).map_err(|e| e.to_string())?;
    std::fs::create_dir_all(&out_dir).map_err(|e| format!("cannot create {out_dir}: {e}"))?;
    let pop = &g.population;
    let files: Vec<(String, Vec<u8>)> = match a.format.as_deref().unwrap_or("obj") {
        "obj" => posemfa::synth::obj_files(&g).into_iter().map(|(n, t)| (n, t.into_bytes())).collect(),
        "pc2" => {
            let rest = posemfa::export::obj::write_obj(&pop.shapes[0], &pop.faces, "faces for poses.pc2 (pose 1)");
            vec![("rest.obj".into(), rest.into_bytes()), ("poses.pc2".into(), posemfa::mesh::cache::write_pc2(&pop.shapes))]
        }
        "glb" => {
            let name = a.spec.preset.name();
            let glb = posemfa::export::morph_glb::write_morph_glb(name, &pop.names, &pop.shapes, &pop.faces)
                .map_err(|e| e.to_string())?;
            vec![(format!("{name}.glb"), glb)]
        }
        f => {
            let fmt = if f == "ply" { posemfa::export::ply::PlyFormat::Binary } else { posemfa::export::ply::PlyFormat::Ascii };
            pop.names
                .iter()
                .zip(&pop.shapes)
                .map(|(n, s)| {
                    let comment = format!("posemfa synthetic population: preset {}, {n}", a.spec.preset.name());
                    (n.replace(".obj", ".ply"), posemfa::export::ply::write_ply(s, &pop.faces, fmt, &comment))
                })
                .collect()
        }
    };
    for (name, bytes) in files {
        let path = std::path::Path::new(&out_dir).join(&name);
        std::fs::write(&path, bytes).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    }
    out!(
        "wrote {} poses of the {} ({} vertices, {} parts) to {out_dir}",
        g.population.n_shapes(),
        a.spec.preset.name(),
        g.population.n_vertices(),
        g.n_parts()
    );
    Ok(())
}

// ---------------------------------------------------------------- articulation: interpolate, export-gltf, report

/// Fits (quietly) and builds the articulated model.
fn articulate_fit(fit: &FitArgs, band: Option<f64>) -> Result<(Population, posemfa::articulate::Articulation), String> {
    let (pop, _truth) = fit.load()?;
    let result = run_fit(&fit.params, &pop, true)?;
    let band = band.unwrap_or(posemfa::articulate::skin::DEFAULT_BAND);
    let art = posemfa::articulate::Articulation::with_band(&result.model, &pop, band).map_err(|e| e.to_string())?;
    Ok((pop, art))
}

#[derive(Default)]
struct InterpolateArgs {
    fit: FitArgs,
    band: Option<f64>,
    from: Option<usize>,
    to: Option<usize>,
    t: Option<f64>,
    out: Option<String>,
    skin: Skin,
    blend: Blend,
    no_residual: bool,
    paper_root: bool,
    paper: bool,
    linear: bool,
}
articulation_args!(InterpolateArgs);

impl InterpolateArgs {
    fn options() -> Group<Self> {
        Group {
            title: "interpolate options",
            shared: false,
            opts: vec![
                val("--from", "I", "first pose (required)", |o: &mut Self, v| pose_number(v).map(|n| o.from = Some(n))),
                val("--to", "J", "second pose (required)", |o: &mut Self, v| pose_number(v).map(|n| o.to = Some(n))),
                val("--t", "T", "where between them: 0 = I, 1 = J (required)", |o: &mut Self, v| {
                    num(v).map(|n| o.t = Some(n))
                }),
                val("--out", "pose.obj", "OBJ file to write (required)", |o: &mut Self, v| text(&mut o.out, v)),
                val(
                    "--skin",
                    "rigid|smooth",
                    "rigid (default: every vertex on its part) or smooth (weights across part boundaries)",
                    |o: &mut Self, v| {
                        one_of(v, &[("rigid", Skin::Rigid), ("smooth", Skin::Smooth)]).map(|x| o.skin = x)
                    },
                ),
                val(
                    "--blend",
                    "dq|lbs",
                    "smooth skin blending: dq (dual quaternion, default) or lbs (linear blend)",
                    |o: &mut Self, v| {
                        one_of(v, &[("dq", Blend::DualQuaternion), ("lbs", Blend::Linear)]).map(|x| o.blend = x)
                    },
                ),
                flag("--no-residual", "leave out eq 24's residual (ends = rigid reconstructions)", |o: &mut Self| {
                    o.no_residual = true;
                }),
                flag(
                    "--paper-root",
                    "the paper's root (smallest rotation) instead of the anchor (largest part)",
                    |o: &mut Self| {
                        o.paper_root = true;
                    },
                ),
                flag(
                    "--paper",
                    "Algorithm 2 as printed: paper root, BFS tree, no joint-offset blending (ends not exact)",
                    |o: &mut Self| {
                        o.paper = true;
                    },
                ),
                flag(
                    "--linear",
                    "plain linear vertex interpolation of the two poses (the baseline)",
                    |o: &mut Self| {
                        o.linear = true;
                    },
                ),
            ],
        }
    }
}

fn cmd_interpolate(a: InterpolateArgs) -> Result<(), String> {
    use posemfa::articulate::Options;
    let out = a.out.clone().ok_or("interpolate: --out is required")?;
    let t = a.t.ok_or("interpolate: --t is required")?;
    // --paper first: the other choices refine it, whatever their order on the command line
    let mut opts = if a.paper { Options::paper() } else { Options::default() };
    if a.paper_root {
        opts.root = RootRule::Paper;
    }
    if a.no_residual {
        opts.residual = false;
    }
    opts.skin = a.skin;
    opts.blend = a.blend;
    let (pop, art) = articulate_fit(&a.fit, a.band)?;
    let i = pose_index("--from", a.from, pop.n_shapes())?;
    let j = pose_index("--to", a.to, pop.n_shapes())?;
    let (pos, how) = if a.linear {
        (art.linear(i, j, t).map_err(|e| e.to_string())?, "linear vertex interpolation".to_string())
    } else {
        let p = art.interpolate(i, j, t, &opts).map_err(|e| e.to_string())?;
        (p, serde_json::to_string(&opts).unwrap_or_default())
    };
    let header = format!(
        "posemfa interpolate: pose {} -> {} ({} -> {}) at t = {t}\n{how}",
        i + 1,
        j + 1,
        pop.names[i],
        pop.names[j]
    );
    let text = posemfa::export::obj::write_obj(&art.to_original(&pos), &pop.faces, &header);
    std::fs::write(&out, text).map_err(|e| format!("cannot write {out}: {e}"))?;
    out!("wrote {out}");
    Ok(())
}

/// The rig a .glb carries: export-gltf and rig-report.
#[derive(Default)]
struct RigArgs {
    weights: Weights,
    influences: Option<usize>,
    joints: posemfa::export::gltf::Joints,
    morphs: posemfa::export::gltf::Morphs,
    bind: Option<usize>,
}

trait HasRig {
    fn rig(&mut self) -> &mut RigArgs;
}

fn rig_group<T: HasRig>() -> Group<T> {
    use posemfa::export::gltf::{Joints, Morphs};
    Group {
        title: "rig options",
        shared: true,
        opts: vec![
            val(
                "--weights",
                "rigid|smooth|fitted",
                "skin weights: rigid (default), smooth (a prior) or fitted (SSDR against every pose)",
                |o: &mut T, v| {
                    one_of(
                        v,
                        &[
                            ("rigid", Weights::Rigid),
                            ("smooth", Weights::Smooth),
                            ("fitted", Weights::Fitted),
                        ],
                    )
                    .map(|x| o.rig().weights = x)
                },
            ),
            val("--influences", "K", "most joints per vertex, 1 to 8 (default 4; JOINTS_1 past 4)", |o: &mut T, v| {
                num(v).map(|n| o.rig().influences = Some(n))
            }),
            val(
                "--joints",
                "free|fixed",
                "free (default: bones move freely) or fixed (rotation-only local animation, constant bone lengths)",
                |o: &mut T, v| {
                    one_of(v, &[("free", Joints::Free), ("fixed", Joints::Fixed)]).map(|x| o.rig().joints = x)
                },
            ),
            val(
                "--morphs",
                "none|residual",
                "none (default) or residual: one morph target per pose, so the clip reproduces every pose",
                |o: &mut T, v| {
                    one_of(v, &[("none", Morphs::None), ("residual", Morphs::Residual)]).map(|x| o.rig().morphs = x)
                },
            ),
            val(
                "--bind",
                "N",
                "pose the mesh is bound in (default: the file named reference.obj if any, else 1)",
                |o: &mut T, v| pose_number(v).map(|n| o.rig().bind = Some(n)),
            ),
        ],
    }
}

impl RigArgs {
    /// The export options for this population.
    fn options(&self, pop: &Population) -> Result<posemfa::export::gltf::GltfOptions, String> {
        let bind = match self.bind {
            Some(_) => pose_index("--bind", self.bind, pop.n_shapes())?,
            None => default_bind(pop),
        };
        let mut g = posemfa::export::gltf::GltfOptions {
            weights: self.weights,
            joints: self.joints,
            morphs: self.morphs,
            bind_pose: bind,
            ..Default::default()
        };
        if let Some(k) = self.influences {
            g.influences = k;
        }
        g.rig_options().validate(pop.n_shapes()).map_err(|e| e.to_string())?;
        Ok(g)
    }
}

/// The pose a rig is bound in by default: the file whose name (without extension) is `reference`, else the first.
fn default_bind(pop: &Population) -> usize {
    posemfa::export::rig_report::default_bind_pose(pop)
}

#[derive(Default)]
struct GltfArgs {
    fit: FitArgs,
    band: Option<f64>,
    rig: RigArgs,
    out: Option<String>,
    samples: Option<usize>,
}
articulation_args!(GltfArgs, rig);

impl GltfArgs {
    fn options() -> Group<Self> {
        Group {
            title: "export-gltf options",
            shared: false,
            opts: vec![
                val("--out", "model.glb", "file to write (required)", |o: &mut Self, v| text(&mut o.out, v)),
                val(
                    "--samples",
                    "N",
                    "samples per second of the \"interpolated\" clip (default 10)",
                    |o: &mut Self, v| num(v).map(|n| o.samples = Some(n)),
                ),
            ],
        }
    }
}

fn cmd_export_gltf(a: GltfArgs) -> Result<(), String> {
    let out = a.out.clone().ok_or("export-gltf: --out is required")?;
    let (pop, art) = articulate_fit(&a.fit, a.band)?;
    let mut g = a.rig.options(&pop)?;
    if let Some(s) = a.samples {
        g.samples_per_second = s;
    }
    let glb = posemfa::export::gltf::to_glb(&art, &g).map_err(|e| e.to_string())?;
    std::fs::write(&out, &glb).map_err(|e| format!("cannot write {out}: {e}"))?;
    out!("wrote {out} ({} bytes, {} parts, {} poses)", glb.len(), art.graph.used_parts().len(), pop.n_shapes());
    Ok(())
}

#[derive(Default)]
struct RigReportArgs {
    fit: FitArgs,
    band: Option<f64>,
    rig: RigArgs,
    glb: Option<String>,
    out: Option<String>,
}
articulation_args!(RigReportArgs, rig);

impl RigReportArgs {
    fn options() -> Group<Self> {
        Group {
            title: "rig-report options",
            shared: false,
            opts: vec![
                val(
                    "--glb",
                    "FILE.glb",
                    "measure this .glb (written by export-gltf from the same files) instead of fitting one",
                    |o: &mut Self, v| text(&mut o.glb, v),
                ),
                val("--out", "rig.glb", "also write the .glb that was measured", |o: &mut Self, v| text(&mut o.out, v)),
            ],
        }
    }
}

fn cmd_rig_report(a: RigReportArgs) -> Result<(), String> {
    use posemfa::export::gltf::{play_glb, to_glb};
    use posemfa::export::rig_report::rig_error;
    let ms = |t: std::time::Instant| t.elapsed().as_secs_f64() * 1e3;
    let t_all = std::time::Instant::now();
    let mut timings = serde_json::Map::new();
    let t = std::time::Instant::now();
    let (pop, _truth) = a.fit.load()?;
    timings.insert("read".into(), ms(t).into());
    let mut info = serde_json::Map::new();
    let glb = match &a.glb {
        Some(file) => {
            let glb = std::fs::read(file).map_err(|e| format!("cannot read {file}: {e}"))?;
            info.insert("glb".into(), file.clone().into());
            glb
        }
        None => {
            let t = std::time::Instant::now();
            let result = run_fit(&a.fit.params, &pop, true)?;
            timings.insert("fit".into(), ms(t).into());
            let t = std::time::Instant::now();
            let band = a.band.unwrap_or(posemfa::articulate::skin::DEFAULT_BAND);
            let art = posemfa::articulate::Articulation::with_band(&result.model, &pop, band).map_err(|e| e.to_string())?;
            timings.insert("articulate".into(), ms(t).into());
            let g = a.rig.options(&pop)?;
            let t = std::time::Instant::now();
            let rig = posemfa::articulate::rig::build(&art, &g.rig_options()).map_err(|e| e.to_string())?;
            timings.insert("rig".into(), ms(t).into());
            let t = std::time::Instant::now();
            let glb = posemfa::export::gltf::write_glb(&art, &rig, &g).map_err(|e| e.to_string())?;
            timings.insert("write".into(), ms(t).into());
            let _ = to_glb;
            info.insert("options".into(), serde_json::to_value(g).unwrap_or_default());
            info.insert("parts".into(), result.model.n_parts().into());
            info.insert("islands".into(), posemfa::model::islands::island_count(&result.model.labels, &pop.faces).into());
            info.insert("solver_trace".into(), rig.trace.clone().into());
            glb
        }
    };
    if let Some(out) = &a.out {
        std::fs::write(out, &glb).map_err(|e| format!("cannot write {out}: {e}"))?;
    }
    let t = std::time::Instant::now();
    let play = play_glb(&glb).map_err(|e| e.to_string())?;
    let bind = match a.rig.bind {
        Some(_) => pose_index("--bind", a.rig.bind, pop.n_shapes())?,
        None => default_bind(&pop),
    };
    let err = rig_error(&pop, &play, bind).map_err(|e| e.to_string())?;
    timings.insert("evaluate".into(), ms(t).into());
    timings.insert("total".into(), ms(t_all).into());
    let mut json = serde_json::to_value(&err).map_err(|e| e.to_string())?;
    if let Some(m) = json.as_object_mut() {
        m.insert("bones".into(), play.joint_parent.len().into());
        m.insert("rest".into(), pop.names[bind].clone().into());
        m.insert("bytes".into(), glb.len().into());
        m.insert("timings_ms".into(), timings.into());
        m.extend(info);
    }
    out!("{json}");
    Ok(())
}

#[derive(Default)]
struct ReportArgs {
    fit: FitArgs,
    band: Option<f64>,
    from: Option<usize>,
    to: Option<usize>,
    t: Option<f64>,
    glb: Option<String>,
    validate: bool,
}
articulation_args!(ReportArgs);

impl ReportArgs {
    fn options() -> Group<Self> {
        Group {
            title: "articulate-report options",
            shared: false,
            opts: vec![
                val("--from", "I", "first pose (required)", |o: &mut Self, v| pose_number(v).map(|n| o.from = Some(n))),
                val("--to", "J", "second pose (required)", |o: &mut Self, v| pose_number(v).map(|n| o.to = Some(n))),
                val("--t", "T", "where between them (default 0.5)", |o: &mut Self, v| num(v).map(|n| o.t = Some(n))),
                val("--glb", "OUT.glb", "also write the rigid .glb and check its animation", |o: &mut Self, v| {
                    text(&mut o.glb, v)
                }),
                flag(
                    "--validate",
                    "with --glb: run scripts/validate-gltf.mjs (Khronos validator) on it",
                    |o: &mut Self| {
                        o.validate = true;
                    },
                ),
            ],
        }
    }
}

fn cmd_articulate_report(a: ReportArgs) -> Result<(), String> {
    let t = a.t.unwrap_or(0.5);
    let t0 = posemfa::clock::now_ms();
    let (pop, art) = articulate_fit(&a.fit, a.band)?;
    let fit_ms = posemfa::clock::now_ms() - t0;
    let i = pose_index("--from", a.from, pop.n_shapes())?;
    let j = pose_index("--to", a.to, pop.n_shapes())?;
    let rep = posemfa::articulate::report::report(&art, i, j, t).map_err(|e| e.to_string())?;
    let mut out = serde_json::to_value(&rep).map_err(|e| e.to_string())?;
    out["inputs"] = serde_json::json!(a.fit.inputs);
    out["fit_ms"] = serde_json::json!(fit_ms);
    if let Some(path) = &a.glb {
        let g = posemfa::export::gltf::GltfOptions::default();
        let glb = posemfa::export::gltf::to_glb(&art, &g).map_err(|e| e.to_string())?;
        std::fs::write(path, &glb).map_err(|e| format!("cannot write {path}: {e}"))?;
        let check = posemfa::export::gltf::check_glb(&art, &glb).map_err(|e| e.to_string())?;
        let mut gl = serde_json::json!({ "path": path, "bytes": glb.len(), "check": check });
        if a.validate {
            let script = concat!(env!("CARGO_MANIFEST_DIR"), "/scripts/validate-gltf.mjs");
            let res = std::process::Command::new("node")
                .arg(script)
                .arg(path)
                .output()
                .map_err(|e| format!("cannot run node {script}: {e}"))?;
            let text = String::from_utf8_lossy(&res.stdout).into_owned();
            gl["validator"] = serde_json::from_str(&text).unwrap_or(serde_json::json!({
                "error": format!("validator did not print JSON (exit {:?}): {} {}", res.status.code(), text, String::from_utf8_lossy(&res.stderr))
            }));
        }
        out["gltf"] = gl;
    }
    out!("{}", serde_json::to_string_pretty(&out).map_err(|e| e.to_string())?);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    #[test]
    fn option_names_are_unique_within_each_command_and_well_formed() {
        for c in commands() {
            let mut seen = BTreeMap::new();
            for g in &c.groups {
                for (left, _) in &g.lines {
                    let name = left.split(' ').next().unwrap_or_default().to_string();
                    assert!(name.starts_with("--") && name.len() > 2, "{}: option '{name}'", c.name);
                    assert!(seen.insert(name.clone(), g.title).is_none(), "{}: {name} is in two groups", c.name);
                }
            }
        }
    }

    #[test]
    fn flags_refine_paper_whatever_the_order() {
        let words = ["d", "--paper-root", "--paper", "--no-residual"].map(OsString::from).to_vec();
        let a = parse::<InterpolateArgs>("interpolate", words).unwrap().unwrap();
        assert!(a.paper && a.paper_root && a.no_residual);
        assert_eq!(a.fit.inputs, vec!["d".to_string()]);
    }
}
