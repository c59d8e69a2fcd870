//! Where the heap peak of a fit goes: a counting allocator around the system one, the pipeline stepped one
//! AECM iteration at a time, and after each step the most bytes live during it, by stage.
//!
//!   cargo run --release --example mem_probe -- INPUT [--seed S]
//!
//! INPUT: a folder of meshes or `synth:PRESET:VERTICES:POSES[:SEED]`. Prints the live bytes after loading, the
//! peak of every stage (bytes and bytes per vertex-pose) and the whole fit's peak (the population included).

use posemfa::mesh::Population;
use posemfa::mfa::params::Params;
use posemfa::parts::hierarchy::{Pipeline, Stage};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};

struct Counting;
static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(l) };
        if !p.is_null() {
            let now = LIVE.fetch_add(l.size(), Relaxed) + l.size();
            PEAK.fetch_max(now, Relaxed);
        }
        p
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) };
        LIVE.fetch_sub(l.size(), Relaxed);
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, new: usize) -> *mut u8 {
        let q = unsafe { System.realloc(p, l, new) };
        if !q.is_null() {
            if new >= l.size() {
                let now = LIVE.fetch_add(new - l.size(), Relaxed) + new - l.size();
                PEAK.fetch_max(now, Relaxed);
            } else {
                LIVE.fetch_sub(l.size() - new, Relaxed);
            }
        }
        q
    }
}

#[global_allocator]
static A: Counting = Counting;

fn load(input: &str) -> Population {
    if let Some(rest) = input.strip_prefix("synth:") {
        let f: Vec<&str> = rest.split(':').collect();
        let preset = match f[0] {
            "quadruped" => posemfa::synth::Preset::Quadruped,
            "arm" => posemfa::synth::Preset::Arm,
            "snake" => posemfa::synth::Preset::Snake,
            other => panic!("preset {other}?"),
        };
        let mut spec = posemfa::synth::Spec { preset, ..Default::default() };
        if let Some(v) = f.get(1) {
            spec.vertices = v.parse().unwrap();
        }
        if let Some(v) = f.get(2) {
            spec.poses = v.parse().unwrap();
        }
        if let Some(v) = f.get(3) {
            spec.seed = v.parse().unwrap();
        }
        // the generator's own working set is not the fit's: keep only the population
        posemfa::synth::generate(&spec).unwrap().population
    } else {
        Population::new(posemfa::mesh::Sources::paths(&[input])).unwrap()
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let input = args.first().expect("usage: mem_probe INPUT [--seed S]");
    let seed = args.iter().position(|a| a == "--seed").map_or(0, |i| args[i + 1].parse().unwrap());
    let pop = load(input);
    let vp = (pop.n_vertices() * pop.n_shapes()) as f64;
    let loaded = LIVE.load(Relaxed);
    println!(
        "{input}: {} vertices x {} shapes; live after loading {:.1} MB ({:.1} B/vertex-pose); load peak {:.1} MB",
        pop.n_vertices(),
        pop.n_shapes(),
        loaded as f64 / 1e6,
        loaded as f64 / vp,
        PEAK.load(Relaxed) as f64 / 1e6
    );
    PEAK.store(LIVE.load(Relaxed), Relaxed);
    let params = Params { seed, ..Params::default() };
    let mut stage_peaks: Vec<(String, usize)> = Vec::new();
    fn note(stage_peaks: &mut Vec<(String, usize)>, name: String, peak: usize) {
        match stage_peaks.last_mut() {
            Some(last) if last.0 == name => last.1 = last.1.max(peak),
            _ => stage_peaks.push((name, peak)),
        }
    }
    let mut p = Pipeline::new(&pop, &params).unwrap();
    let mut fit_peak = PEAK.swap(LIVE.load(Relaxed), Relaxed);
    note(&mut stage_peaks, "new".into(), fit_peak);
    let mut names = 0;
    let mut runs = 0;
    while !p.is_done() {
        let progress = p.step().unwrap();
        let peak = PEAK.swap(LIVE.load(Relaxed), Relaxed);
        fit_peak = fit_peak.max(peak);
        let name = match progress.stage {
            Stage::Coarse => "coarse".to_string(),
            Stage::Refine { .. } => "refine".to_string(),
            Stage::Final { .. } => format!("final run {}", runs + 1),
            Stage::Done => "done".to_string(),
        };
        if matches!(progress.stage, Stage::Final { .. }) && progress.run_finished {
            runs += 1;
        }
        names += 1;
        note(&mut stage_peaks, name, peak);
    }
    let r = p.result();
    let parts = r.model.n_parts();
    let rmse = r.model.rmse(&pop);
    drop(r);
    drop(p);
    for (name, peak) in &stage_peaks {
        println!("  {name:>10}: peak {:7.1} MB  {:6.1} B/vertex-pose", *peak as f64 / 1e6, *peak as f64 / vp);
    }
    println!("fit peak {:.1} MB = {:.1} B/vertex-pose (population included); {parts} parts, RMSE {rmse:.6}, {names} steps; live after {:.1} MB",
        fit_peak as f64 / 1e6, fit_peak as f64 / vp, LIVE.load(Relaxed) as f64 / 1e6);
}
