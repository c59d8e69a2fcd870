//! `posemfa fit DIR_OR_FILES...`: fit the model and print a summary (or, with --model, the saved fit's).

use crate::shared::{ground_truth_json, median, run_fit, write_json, FitArgs, RunArgs};
use clap::ValueHint;
use posemfa::model_file::ModelFile;

/// Fit the model (or read a saved one with --model) and print a summary
#[derive(clap::Args)]
pub struct Args {
    /// Save the fit as a model file (.posemfa) that --model, the page and the embed open without fitting
    #[arg(long, value_name = "FILE.posemfa", value_hint = ValueHint::FilePath)]
    save: Option<String>,
    /// With --save: leave the poses out of the model file (smaller; views of the data then need the poses)
    #[arg(long, requires = "save")]
    without_poses: bool,
    /// With --save: also keep the rig `export-gltf --weights fitted` and `rig-report --weights fitted` build
    /// (their default options), so that with --model they take it instead of solving the skin weights again
    /// (adds that solve to this command, and about 60 bytes per vertex to the file)
    #[arg(long, requires = "save")]
    with_rig: bool,
    #[command(flatten)]
    pub run: RunArgs,
    #[command(flatten)]
    pub fit: FitArgs,
}

pub fn run(o: Args) -> Result<(), String> {
    let t_load = posemfa::clock::now_ms();
    let mut totals = Vec::new();
    let (mut saved, truth, load_ms) = match &o.fit.input.model {
        Some(_) => {
            let f = o.fit.fitted(o.run.quiet)?;
            let load_ms = posemfa::clock::now_ms() - t_load;
            // the figures measured on the poses when it was saved (or now on the poses given with it)
            let saved = match f.saved_summary {
                Some(summary) => ModelFile {
                    result: f.result,
                    params: f.params,
                    population: f.pop,
                    has_data: !f.stand_in,
                    summary,
                    rig: f.saved_rig,
                },
                None => ModelFile::new(f.pop, f.result, f.params),
            };
            (saved, f.truth, load_ms)
        }
        None => {
            let start = o.fit.start()?;
            let (params, pop, truth) = o.fit.load()?;
            let load_ms = posemfa::clock::now_ms() - t_load;
            let mut result = None;
            for _ in 0..o.run.repeat() {
                let t0 = posemfa::clock::now_ms();
                result = Some(run_fit(&params, &start, &pop, o.run.quiet)?);
                totals.push(posemfa::clock::now_ms() - t0);
            }
            let result = result.ok_or("no fit ran")?;
            (ModelFile::new(pop, result, params), truth, load_ms)
        }
    };
    let (pop, result, params) = (&saved.population, &saved.result, &saved.params);
    let m = &result.model;
    let s = &result.stages;
    let timing = if totals.is_empty() {
        format!(
            "read from {} in {load_ms:.0} ms",
            o.fit.input.model.as_ref().map_or(String::new(), |p| p.display().to_string())
        )
    } else {
        format!("{:.0} ms (load {load_ms:.0} ms)", median(&mut totals))
    };
    out!(
        "{} shapes x {} vertices | parts: coarse {} -> refined {} -> final {} | final AECM {} iterations ({}) | RMSE {:.5} (unit box; E_RMS {:.3}) | {timing}",
        pop.n_shapes(),
        pop.n_vertices(),
        s.coarse_parts,
        s.refined_parts,
        s.final_parts,
        m.iterations,
        if m.converged { "converged" } else { "NOT converged: iteration cap reached" },
        saved.summary.rmse,
        saved.summary.e_rms,
    );
    match &saved.summary.diagnosis {
        Some(d) => out!(
            "  {}: {}",
            if d.undecided {
                "no verdict"
            } else if d.articulated {
                "articulated"
            } else {
                "NOT articulated"
            },
            d.reason
        ),
        None => out!("  {}", posemfa::parts::diagnosis::UNFINISHED),
    }
    if let Some(g) = &truth {
        out!("  ground truth: {}", ground_truth_json(g, m));
    } else {
        out!("  poses: {}", pop.source);
    }
    if !saved.has_data {
        out!("  the model file holds no poses: the figures above were measured when it was saved");
    }
    if let [.., last] = result.part_curve.as_slice() {
        out!(
            "  part rule: {} merges from {} parts; the next pair scored {:.2} (kept apart from {}: --distinct-ratio)",
            result.part_curve.len() - 1,
            result.part_curve[0].parts,
            last.score,
            params.distinct.distinct_ratio
        );
    }
    for st in &result.stats {
        out!("  {:<7} {:>8.1} ms  {:>5} iterations in {:>3} AECM runs", st.name, st.ms, st.iterations, st.aecm_runs);
    }
    if let Some(path) = &o.run.json {
        if !saved.has_data {
            return Err(format!(
                "--json {path}: the model file holds no poses, and the JSON's figures (RMSE, islands, diagnosis) are \
                 measured on them; give the poses after the options (DIR_OR_FILES)"
            ));
        }
        write_json(path, pop, result)?;
        out!("wrote {path}");
    }
    if let Some(path) = &o.save {
        if o.with_rig {
            if !saved.has_data {
                return Err(format!(
                    "--with-rig: the model file holds no poses, and the rig's skin weights are solved against them; \
                     give the poses after the options (DIR_OR_FILES)"
                ));
            }
            let options = posemfa::export::gltf::GltfOptions {
                weights: posemfa::export::gltf::Weights::Fitted,
                bind_pose: posemfa::export::rig_report::default_bind_pose(&saved.population),
                ..Default::default()
            }
            .rig_options();
            let band = posemfa::articulate::skin::DEFAULT_BAND;
            let rig = posemfa::model_file::SavedRig::build(&saved.result.model, &saved.population, band, options)
                .map_err(|e| e.to_string())?;
            saved.rig = Some(rig);
        }
        let bytes = saved.to_bytes(!o.without_poses);
        std::fs::write(path, &bytes).map_err(|e| format!("cannot write {path}: {e}"))?;
        out!(
            "wrote {path} ({} bytes, {}{})",
            bytes.len(),
            if o.without_poses || !saved.has_data { "without the poses" } else { "with the poses" },
            if saved.rig.is_some() { ", with the rig of --weights fitted" } else { "" }
        );
    }
    Ok(())
}
